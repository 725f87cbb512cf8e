#include "study/paper.hpp"

#include <stdexcept>

#include "study/study.hpp"

namespace canalsim::study {

extern const char* const kPaperTablesJson;  // generated from data/paper_tables.json

const nlohmann::json& paper_tables() {
  static const nlohmann::json tables = nlohmann::json::parse(kPaperTablesJson);
  return tables;
}

double paper_value(const std::string& pointer) {
  const auto& t = paper_tables();
  const nlohmann::json::json_pointer p(pointer);
  if (!t.contains(p) || !t.at(p).is_number()) {
    throw std::out_of_range("paper_tables.json: no number at " + pointer);
  }
  return t.at(p).get<double>();
}

std::string paper_fit(const ModelTable& t, const std::string& op, const std::string& field) {
  return "/" + t.spec.paper_key + "/fits/" + op + "/" + field;
}

}  // namespace canalsim::study
