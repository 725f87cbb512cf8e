// The one JSON policy for numbers: JSON has no NaN or infinity, so a value that is not defined
// (an index of a part whose levels do not vary, a deviation that was not estimated) is written as
// null, which every reader (Python's json, pandas, jq) takes for "missing".
#pragma once

#include <cmath>

#include <nlohmann/json.hpp>

namespace canalsim {

inline nlohmann::json json_number(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr); }

}  // namespace canalsim
