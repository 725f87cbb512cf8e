#include "calibration/scenario_file.hpp"

#include "core/text.hpp"

#include <cmath>
#include <map>
#include <sstream>

#include "core/errors.hpp"
#include "core/format.hpp"

namespace canalsim::calibration {
namespace {

// The table a header line opens ("[a.b]" -> "a.b", the k-th "[[pools]]" -> "pools[k]"), or "".
std::string header_of(const std::string& line, std::map<std::string, int>& array_counts) {
  const std::string t = trim(line.substr(0, line.find('#')));
  if (t.size() > 4 && t.rfind("[[", 0) == 0 && t.compare(t.size() - 2, 2, "]]") == 0) {
    const std::string name = trim(t.substr(2, t.size() - 4));
    return name + "[" + std::to_string(++array_counts[name]) + "]";
  }
  if (t.size() > 2 && t.front() == '[' && t.back() == ']') return trim(t.substr(1, t.size() - 2));
  return "";
}

// The key a "key = value" line sets, or "".
std::string key_of(const std::string& line) {
  const std::string t = trim(line);
  if (t.empty() || t[0] == '#' || t[0] == '[') return "";
  const auto eq = t.find('=');
  return eq == std::string::npos ? "" : trim(t.substr(0, eq));
}

}  // namespace

std::string edit_scenario_toml(const std::string& text, const std::vector<KeyEdit>& edits) {
  std::vector<std::string> lines;
  {
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
  }
  for (const KeyEdit& e : edits) {
    const auto dot = e.key.rfind('.');
    const std::string table = dot == std::string::npos ? "" : e.key.substr(0, dot);
    const std::string key = e.key.substr(dot == std::string::npos ? 0 : dot + 1);
    const std::string shown = e.text.empty() ? format_g(e.value, 10) : e.text;
    const std::string written = key + " = " + shown + (e.comment.empty() ? "" : "  # " + e.comment);
    std::map<std::string, int> counts;
    std::string current;
    long header = table.empty() ? -1 : -2;  // line index of the table's header; -1 = the root table
    bool done = false;
    for (std::size_t i = 0; i < lines.size() && !done; ++i) {
      const std::string h = header_of(lines[i], counts);
      if (!h.empty()) {
        current = h;
        if (current == table) header = static_cast<long>(i);
        continue;
      }
      if (current == table && key_of(lines[i]) == key) {
        lines[i] = written;
        done = true;
      }
    }
    if (done) continue;
    if (header >= -1) {
      lines.insert(lines.begin() + (header + 1), written);
    } else if (table.find('[') != std::string::npos) {
      throw InputError("scenario key " + e.key + ": the file has no table " + table + " to hold it");
    } else {
      lines.push_back("");
      lines.push_back("[" + table + "]");
      lines.push_back(written);
    }
  }
  std::string out;
  for (const auto& line : lines) out += line + "\n";
  return out;
}

namespace {

// "name = value" lines of a table of names, non-finite values left out.
std::string named_values(const std::map<std::string, double>& values) {
  std::string out;
  for (const auto& [name, v] : values) {
    if (!std::isfinite(v)) continue;
    const std::string key = name.find('.') == std::string::npos ? name : "\"" + name + "\"";
    out += key + " = " + format_g(v, 6) + "\n";
  }
  return out;
}

}  // namespace

std::string with_calibration_table(const std::string& text, const std::map<std::string, double>& deviations,
                                   double baseline_rms_mm, const std::map<std::string, double>& deviations_alone,
                                   const std::map<std::string, double>& baseline_rms_by_channel,
                                   const std::map<std::string, double>& baseline_slow_rms_by_channel) {
  std::string out;
  std::map<std::string, int> counts;
  bool skipping = false;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    const std::string h = header_of(line, counts);
    if (!h.empty()) skipping = h.rfind("calibration", 0) == 0 && (h.size() == 11 || h[11] == '.');
    if (!skipping) out += line + "\n";
  }
  while (out.size() >= 2 && out.compare(out.size() - 2, 2, "\n\n") == 0) out.pop_back();
  if (std::isfinite(baseline_rms_mm) && baseline_rms_mm > 0.0) {
    out += "\n[calibration]  # canalsim calibrate: what the calibrated model still misses on its baseline\n"
           "baseline_rms_mm = " + format_g(baseline_rms_mm, 6) + "\n";
  }
  if (!baseline_rms_by_channel.empty()) {
    out += "\n[calibration.baseline_rms]  # the same residual RMS for each level channel [mm]\n" +
           named_values(baseline_rms_by_channel);
  }
  if (!baseline_slow_rms_by_channel.empty()) {
    out += "\n[calibration.baseline_slow_rms]  # its part slower than 2 s (periods the bores' smearing does not reach) [mm]\n" +
           named_values(baseline_slow_rms_by_channel);
  }
  out += "\n[calibration.std]  # one statistical standard deviation of each calibrated parameter (canalsim calibrate);\n"
         "                   # canalsim diagnose reads it: an effect must exceed what calibration left open\n" +
         named_values(deviations);
  if (!deviations_alone.empty()) {
    out += "\n[calibration.std_alone]  # the same with the other parameters held at their estimates: what\n"
           "                         # canalsim diagnose, fitting one effect at a time, takes as left open\n" +
           named_values(deviations_alone);
  }
  return out;
}

}  // namespace canalsim::calibration
