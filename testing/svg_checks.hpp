// Checks of an SVG text that tests share (tests/plot, tests/cli): its tags balance and its text
// reads as numbers people write.
#pragma once

#include <string>
#include <vector>

namespace canalsim::plot_test {

// "" when every element is closed in order (self-closing ones included), else what is wrong.
inline std::string unbalanced_tags(const std::string& svg) {
  std::vector<std::string> open;
  for (std::size_t at = svg.find('<'); at != std::string::npos; at = svg.find('<', at + 1)) {
    const std::size_t end = svg.find('>', at);
    if (end == std::string::npos) return "a tag is not closed at " + std::to_string(at);
    const std::string tag = svg.substr(at + 1, end - at - 1);
    if (tag.empty() || tag[0] == '?' || tag[0] == '!') continue;
    if (tag.back() == '/') continue;
    const std::string name = tag.substr(tag[0] == '/' ? 1 : 0, tag.find_first_of(" \t\n/", 1) - (tag[0] == '/' ? 1 : 0));
    if (tag[0] != '/') {
      open.push_back(name);
    } else if (open.empty() || open.back() != name) {
      return "</" + name + "> closes " + (open.empty() ? std::string("nothing") : "<" + open.back() + ">");
    } else {
      open.pop_back();
    }
  }
  return open.empty() ? "" : "<" + open.back() + "> is never closed";
}

// The text between tags (tick labels, titles, legend entries).
inline std::vector<std::string> text_nodes(const std::string& svg) {
  std::vector<std::string> out;
  for (std::size_t at = svg.find('>'); at != std::string::npos; at = svg.find('>', at + 1)) {
    const std::size_t next = svg.find('<', at);
    if (next == std::string::npos) break;
    if (next > at + 1) out.push_back(svg.substr(at + 1, next - at - 1));
  }
  return out;
}

// A text that is a negative zero: "-0", "-0.0", "-0.00".
inline bool is_negative_zero(const std::string& s) {
  return s.size() >= 2 && s[0] == '-' && s[1] == '0' && s.find_first_not_of("0.", 1) == std::string::npos;
}

}  // namespace canalsim::plot_test
