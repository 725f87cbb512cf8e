// The published tables of Gharab, Feliu-Batlle & Rivas-Perez (2019), embedded at configure time.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace canalsim::study {

struct ModelTable;

// The paper's tables (study/data/paper_tables.json, embedded at configure time).

const nlohmann::json& paper_tables();
// The number at a JSON pointer, e.g. "/table1_LIOM/fits/op1/K"; throws std::out_of_range naming
// the pointer when it is absent or not a number.
double paper_value(const std::string& pointer);

// The JSON pointer of a fitted value of `table` in the paper's tables, "/table1_LIOM/fits/op1/K".
std::string paper_fit(const ModelTable& table, const std::string& op, const std::string& field);

}  // namespace canalsim::study
