#include "sweep/table.hpp"

#include <cmath>

#include "sweep/compute.hpp"

namespace canalsim::sweep {
namespace {

std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// A message on one line: the table keeps one case to a line, and so does the journal it is
// resumed from.
std::string one_line(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  for (auto at = text.find_first_of("\r\n"); at != std::string::npos; at = text.find_first_of("\r\n", at)) {
    text.replace(at, 1, "; ");
  }
  return text;
}

// case, point, experiment and one per varied key: the status follows.
std::size_t case_cells_count(const SweepFile& sweep) { return 3 + sweep.vary.size(); }

std::string row(std::vector<std::string> cells, const std::string& status, const std::string& message,
                const std::vector<std::string>& computed) {
  cells.push_back(status);
  cells.push_back(one_line(message));
  cells.insert(cells.end(), computed.begin(), computed.end());
  return csv_line(cells);
}

}  // namespace

std::vector<std::string> table_columns(const SweepFile& sweep) {
  std::vector<std::string> names = {"case", "point", "experiment"};
  for (const auto& v : sweep.vary) names.push_back(v.key);
  names.push_back("status");
  names.push_back("message");
  for (auto& name : computed_columns(sweep.compute)) names.push_back(std::move(name));
  return names;
}

std::string table_header(const SweepFile& sweep) { return csv_line(table_columns(sweep)); }

std::string number_cell(double value) {
  if (std::isnan(value)) return "";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return exact_number(value);
}

std::string csv_line(const std::vector<std::string>& cells) {
  std::string line;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (i > 0) line += ',';
    line += csv_cell(cells[i]);
  }
  return line + "\n";
}

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      cells.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      cells.emplace_back();
    } else if (!quoted && (c == '\n' || c == '\r')) {
      break;
    } else {
      cells.back() += c;
    }
  }
  return cells;
}

std::vector<std::string> case_cells(const SweepFile& sweep, const Case& c) {
  std::vector<std::string> cells = {std::to_string(c.index), std::to_string(c.point), sweep.experiments[c.experiment]};
  for (const double v : c.values) cells.push_back(number_cell(v));
  return cells;
}

std::string ok_row(const SweepFile& sweep, const Case& c, const std::vector<std::string>& computed,
                   const std::string& warnings) {
  return row(case_cells(sweep, c), "ok", warnings, computed);
}

std::string failed_row(const SweepFile& sweep, const Case& c, const std::string& error) {
  return row(case_cells(sweep, c), "failed", error, std::vector<std::string>(computed_columns(sweep.compute).size()));
}

bool row_ok(const SweepFile& sweep, const std::string& row) {
  const std::vector<std::string> cells = split_csv_line(row);
  const std::size_t status = case_cells_count(sweep);
  return status < cells.size() && cells[status] == "ok";
}

}  // namespace canalsim::sweep
