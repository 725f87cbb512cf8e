#include "core/metadata.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <system_error>

#include "core/format.hpp"

namespace canalsim {
namespace {

using Type = MetadataKey::Type;

// Openings and levels up to 100 m, periods from a microsecond (kMinSamplePeriod) to 11 days: a
// value outside is a typo or corrupt data, and one that reached a model would overflow its cost.
constexpr double kMaxLengthMm = 1.0e5;
constexpr double kMaxVolumeM3 = 1.0e12;
constexpr double kMaxSeed = 9007199254740992.0;  // 2⁵³: every integer up to it is exact in a double

constexpr std::array kKeys = {
    MetadataKey{"scenario", Type::text, 0, 0, false, "", "the scenario the recording was simulated from"},
    MetadataKey{"experiment", Type::text, 0, 0, false, "", "the experiment's name (op1 … op4 in the lab)"},
    MetadataKey{"operating_opening_mm", Type::number, 0.0, kMaxLengthMm, false, "mm",
                "the gate opening the canal rested at before the first sample (else the first u_mm)"},
    MetadataKey{"initial_y_up_mm", Type::number, 0.0, kMaxLengthMm, true, "mm",
                "the upstream level the recording started from (else the mean y_up_mm before the command first changes)"},
    MetadataKey{"sampling_period_s", Type::number, kMinSamplePeriod, 1.0e6, false, "s",
                "the sampling period; equals the t_s step"},
    MetadataKey{"resampled_period_s", Type::number, kMinSamplePeriod, 1.0e6, false, "s",
                "the period `canalsim resample` wrote the rows on; equals the t_s step"},
    MetadataKey{"u_unit", Type::text, 0, 0, false, "", "the unit u_mm and x_up_mm are recorded in (mm when absent)"},
    MetadataKey{"u_scale_mm_per_unit", Type::number, 1.0e-6, 1.0e6, false, "mm per unit",
                "millimetres per u_unit; 1 when u_unit is mm"},
    MetadataKey{"y_unit", Type::text, 0, 0, false, "", "the unit of the level columns (mm when absent)"},
    MetadataKey{"y_scale_mm_per_unit", Type::number, 1.0e-6, 1.0e6, false, "mm per unit",
                "millimetres per y_unit; 1 when y_unit is mm"},
    MetadataKey{"generator", Type::text, 0, 0, false, "", "the program that wrote the recording"},
    MetadataKey{"initial_state", Type::text, 0, 0, false, "", "how the simulation's initial state was found"},
    MetadataKey{"volume_until_s", Type::number, 0.0, 1.0e7, false, "s", "the end of the volume balance"},
    MetadataKey{"volume_inflow_m3", Type::number, -kMaxVolumeM3, kMaxVolumeM3, false, "m³", "the balance's inflow"},
    MetadataKey{"volume_outflow_m3", Type::number, -kMaxVolumeM3, kMaxVolumeM3, false, "m³", "the balance's outflow"},
    MetadataKey{"volume_lateral_m3", Type::number, -kMaxVolumeM3, kMaxVolumeM3, false, "m³",
                "the balance's lateral inflow (offtakes negative)"},
    MetadataKey{"volume_storage_change_m3", Type::number, -kMaxVolumeM3, kMaxVolumeM3, false, "m³",
                "the change of the volume stored"},
    MetadataKey{"volume_relative_error", Type::number, -1.0e6, 1.0e6, false, "", "the balance's relative error"},
    MetadataKey{"warning_overtopping", Type::text, 0, 0, false, "", "the pools that rose above their walls"},
    MetadataKey{"signal", Type::text, 0, 0, false, "", "the signal `canalsim prbs` wrote"},
    MetadataKey{"stages", Type::integer, 2, 20, false, "", "the PRBS's shift-register stages"},
    MetadataKey{"clock_s", Type::number, 0.0, 3600.0, true, "s", "the PRBS's clock period"},
    MetadataKey{"amplitude_mm", Type::number, -1000.0, 1000.0, false, "mm", "the PRBS's amplitude"},
    MetadataKey{"seed", Type::integer, 0, kMaxSeed, false, "", "the PRBS's seed"},
};

}  // namespace

std::string metadata_range_text(const MetadataKey& k) {
  if (k.type == Type::text) return "text";
  const int digits = k.type == Type::integer ? 17 : 10;  // an integer's bound in full (2⁵³ for a seed)
  return std::string(k.above_low ? "(" : "[") + format_g(k.low, digits) + ", " + format_g(k.high, digits) + "]";
}

namespace {

std::string expected_text(const MetadataKey& k) {
  const std::string what = k.type == Type::integer ? "an integer"
                           : k.unit.empty()        ? "a number"
                                                   : "a number of " + std::string(k.unit);
  return "expected " + what + " in " + metadata_range_text(k);
}

// The whole text as a finite decimal number, as the reader takes a cell ("2x", "0x10", "nan",
// "inf" and "" are not).
std::optional<double> parse_finite(const std::string& text) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

std::string source_of(const Recording& recording) {
  return recording.source.empty() ? std::string("recording") : recording.source;
}

}  // namespace

std::span<const MetadataKey> known_metadata_keys() { return kKeys; }

const MetadataKey* find_metadata_key(std::string_view name) {
  const auto it = std::find_if(kKeys.begin(), kKeys.end(), [&](const MetadataKey& k) { return k.name == name; });
  return it == kKeys.end() ? nullptr : &*it;
}

std::string metadata_value_problem(std::string_view key, const std::string& value) {
  const MetadataKey* k = find_metadata_key(key);
  if (k == nullptr || k->type == Type::text) return "";
  const std::optional<double> number = parse_finite(value);
  const bool in_range = number && (k->above_low ? *number > k->low : *number >= k->low) && *number <= k->high &&
                        (k->type != Type::integer || *number == std::floor(*number));
  if (in_range) return "";
  std::string problem = "'";
  problem += format_excerpt(value);
  problem += "': ";
  problem += expected_text(*k);
  return problem;
}

std::optional<double> metadata_number(const Recording& recording, std::string_view key) {
  const std::string text = recording.meta(std::string(key));
  if (text.empty()) return std::nullopt;
  if (const std::string problem = metadata_value_problem(key, text); !problem.empty()) {
    throw InputError(source_of(recording) + ": metadata " + std::string(key) + ": " + problem);
  }
  return parse_finite(text);
}

void check_metadata(const Recording& recording, bool uniform_time,
                    const std::function<std::string(std::size_t)>& where) {
  const auto& metadata = recording.metadata;
  const auto line_of = [&](const std::string& key) {
    for (std::size_t i = 0; i < metadata.size(); ++i) {
      if (metadata[i].first == key) return i;
    }
    return metadata.size();
  };
  // 1. Each line on its own: a key given once, a known key's value in its range.
  for (std::size_t i = 0; i < metadata.size(); ++i) {
    const auto& [key, value] = metadata[i];
    if (const std::size_t first = line_of(key); first < i) {
      throw InputError(where(i) + ": metadata " + format_excerpt(key) + " given twice (first at " + where(first) +
                       "): expected each key once");
    }
    if (const std::string problem = metadata_value_problem(key, value); !problem.empty()) {
      throw InputError(where(i) + ": metadata " + key + ": " + problem);
    }
  }
  // 2. Keys that must agree: a scale names its unit, and a unit of mm has a scale of 1.
  for (const std::string which : {"u", "y"}) {
    const std::string unit_key = which + "_unit", scale_key = which + "_scale_mm_per_unit";
    const std::string unit = recording.meta(unit_key), scale = recording.meta(scale_key);
    if (!scale.empty() && unit.empty()) {
      throw InputError(where(line_of(scale_key)) + ": metadata " + scale_key + ": " + scale + " mm per unit of no name: " +
                       "expected " + unit_key + " too (the unit's name, e.g. # " + unit_key + ": counts)");
    }
    if (unit == "mm" && !scale.empty() && *parse_finite(scale) != 1.0) {
      throw InputError(where(line_of(scale_key)) + ": metadata " + scale_key + ": " + scale + " contradicts " +
                       unit_key + ": mm: expected 1 (or another " + unit_key + ")");
    }
  }
  // 3. The periods the metadata states are the rows' step.
  if (!uniform_time || !recording.has(columns::time) || recording.size() < 2) return;
  const auto& t = recording.column(columns::time);
  const double step = t[1] - t[0];
  for (const char* key : {"sampling_period_s", "resampled_period_s"}) {
    const std::string text = recording.meta(key);
    if (text.empty()) continue;
    const double period = *parse_finite(text);
    if (std::abs(period - step) > 0.01 * step) {
      throw InputError(where(line_of(key)) + ": metadata " + key + ": " + text + " s contradicts the t_s step of " +
                       format_g(step) + " s: expected the rows' sampling period");
    }
  }
}

}  // namespace canalsim
