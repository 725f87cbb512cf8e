#include "scenarios/run_report.hpp"

#include <algorithm>

#include "core/format.hpp"

namespace canalsim::scenarios {

WallWatch::WallWatch(const Scenario& scenario) {
  for (const PoolSpec& p : scenario.pools) pools_.push_back({p.name, p.wall_height_m});
}

void WallWatch::observe(const solver::Canal& canal, double time) {
  for (int r = 0; r < canal.reach_count() && r < static_cast<int>(pools_.size()); ++r) {
    const solver::Reach& reach = canal.reach(r);
    Pool& pool = pools_[static_cast<std::size_t>(r)];
    double deepest = 0.0;
    for (int i = 0; i < reach.cells(); ++i) deepest = std::max(deepest, reach.depth(i));
    if (deepest > pool.wall && pool.first_time < 0.0) pool.first_time = time;
    if (deepest > pool.highest) {
      pool.highest = deepest;
      pool.highest_time = time;
    }
  }
}

std::vector<std::string> WallWatch::overtopped() const {
  std::vector<std::string> texts;
  for (const Pool& p : pools_) {
    if (p.first_time < 0.0) continue;
    texts.push_back("pool '" + p.name + "' (wall " + format_g(p.wall) + " m) above its wall from t = " +
                    format_g(p.first_time) + " s, highest depth " + format_g(p.highest) + " m at t = " +
                    format_g(p.highest_time) + " s");
  }
  return texts;
}

void record_run_report(Recording& rec, const solver::VolumeBalance& b, double until, const WallWatch& walls) {
  rec.set_meta("volume_until_s", format_g(until, 10));
  rec.set_meta("volume_inflow_m3", format_g(b.inflow, 10));
  rec.set_meta("volume_outflow_m3", format_g(b.outflow, 10));
  rec.set_meta("volume_lateral_m3", format_g(b.lateral, 10));
  rec.set_meta("volume_storage_change_m3", format_g(b.storage_change(), 10));
  rec.set_meta("volume_relative_error", format_g(b.relative_error(), 3));
  std::string warnings;
  for (const auto& text : walls.overtopped()) warnings += (warnings.empty() ? "" : "; ") + text;
  if (!warnings.empty()) rec.set_meta("warning_overtopping", warnings);
}

std::vector<std::string> run_report_lines(const Recording& rec) {
  std::vector<std::string> lines;
  if (!rec.meta("volume_inflow_m3").empty()) {
    lines.push_back("volume balance of " + rec.meta("scenario") + "/" + rec.meta("experiment") +
                    " [m³] over 0-" + rec.meta("volume_until_s") + " s: inflow " + rec.meta("volume_inflow_m3") + ", outflow " + rec.meta("volume_outflow_m3") +
                    ", lateral " + rec.meta("volume_lateral_m3") + ", storage change " +
                    rec.meta("volume_storage_change_m3") + ", relative error " + rec.meta("volume_relative_error"));
  }
  std::string warnings = rec.meta("warning_overtopping");
  while (!warnings.empty()) {
    const auto cut = warnings.find("; pool '");
    lines.push_back("warning: " + warnings.substr(0, cut));
    warnings = cut == std::string::npos ? "" : warnings.substr(cut + 2);
  }
  return lines;
}

}  // namespace canalsim::scenarios
