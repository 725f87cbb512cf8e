#include "scenarios/design.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "gates/sluice_gate.hpp"
#include "core/recording.hpp"
#include "scenarios/toml_table.hpp"

namespace canalsim::scenarios {
namespace {

double offtake_total(const PoolSpec& pool) {
  double sum = 0.0;
  for (const auto& o : pool.offtakes) sum += o.discharge_m3s;
  return sum;
}

// Q in the pool at x: the inflow less the offtakes upstream of x.
double discharge_at(const PoolSpec& pool, double inflow, double x) {
  double q = inflow;
  for (const auto& o : pool.offtakes) q -= o.x_m < x ? o.discharge_m3s : 0.0;
  return q;
}

bool needs_design(const Scenario& s) {
  bool any = s.head_gate && s.head_gate->auto_opening;
  for (const auto& g : s.gates) any = any || g.auto_opening;
  for (const auto& p : s.pools) {
    for (const auto& o : p.offtakes) any = any || (o.kind == OfftakeKind::orifice && o.coefficient <= 0.0);
  }
  return any;
}

double squared_froude(const solver::Section& s, double q, double y, double g) {
  const double a = s.area(y);
  return q * q * s.top_width(y) / (g * a * a * a);
}

}  // namespace

double cell_bed_elevation(const PoolSpec& pool, int cell) {
  const double dx = pool.length_m / pool.cells;
  return pool.bed_elevation_m - pool.bed_slope * (cell + 0.5) * dx;
}

int offtake_cell(const PoolSpec& pool, double x_m) {
  const double dx = pool.length_m / pool.cells;
  return std::clamp(static_cast<int>(x_m / dx), 0, pool.cells - 1);
}

bool offtake_at_end(const PoolSpec& pool, double x_m) { return x_m >= pool.length_m * (1.0 - 1e-12); }

gates::GateGeometry gate_geometry(const GateSpec& g) {
  gates::GateGeometry geometry;
  geometry.width = g.width_m;
  geometry.law.law = g.law == GateLaw::swamee ? gates::GateLaw::swamee : gates::GateLaw::simple;
  // One meaning for both laws: a multiplier on the published coefficient (Swamee's; Cd = 0.6 of
  // the paper's eq. 9/11).
  geometry.law.discharge_coefficient_multiplier = g.discharge_coefficient;
  geometry.law.submerged_discharge_coefficient_multiplier = g.submerged_coefficient();
  geometry.law.leakage_opening = g.leakage_m;
  geometry.law.zero_head = g.zero_head_m;
  geometry.law.opening_exponent = g.cd_opening_exponent;
  geometry.law.opening_curvature = g.cd_opening_curvature;
  geometry.law.reference_opening = g.cd_reference_opening();
  geometry.law.border_floor_ratio = g.border_floor_ratio;
  return geometry;
}

std::vector<PoolFlows> design_flows(const Scenario& s) {
  const std::size_t n = s.pools.size();
  std::vector<PoolFlows> flows(n);
  double total_offtakes = 0.0;
  for (const auto& p : s.pools) total_offtakes += offtake_total(p);
  const bool end_known = s.downstream.kind == DownstreamKind::closed || s.downstream.kind == DownstreamKind::pump;
  const double end_flow = s.downstream.kind == DownstreamKind::pump ? s.downstream.pump_discharge_m3s : 0.0;
  double head = 0.0;
  if (s.upstream.kind == UpstreamKind::discharge) {
    head = s.upstream.discharge_m3s;
    if (end_known && std::abs(head - total_offtakes - end_flow) > 1e-9 * std::max(head, 1.0)) {
      throw InputError(s.source + ": upstream.discharge_m3s = " + format_value(head) +
                       ": expected the offtakes' design discharges plus the end's outflow (" +
                       format_value(total_offtakes + end_flow) + " m^3/s) for a steady design state");
    }
  } else if (end_known) {
    head = total_offtakes + end_flow;
  } else {
    throw InputError(s.source + ": opening_m = \"auto\" and orifice offtakes need the design flows: expected "
                                "[upstream] kind = \"discharge\" or [downstream] kind = \"closed\" or \"pump\"");
  }
  double q = head;
  for (std::size_t i = 0; i < n; ++i) {
    flows[i].inflow = q;
    q -= offtake_total(s.pools[i]);
    if (q < -1e-9 * std::max(head, 1.0)) {
      throw InputError(s.source + ": pools[" + std::to_string(i) + "].offtakes: the design discharges exceed the flow "
                       "reaching the pool (" + format_value(flows[i].inflow) + " m^3/s)");
    }
    flows[i].outflow = std::max(q, 0.0);
  }
  return flows;
}

double gvf_slope(const solver::Section& s, double n, double s0, double q, double y, double g) {
  const double a = s.area(y);
  const double r = a / s.wetted_perimeter(y);
  const double sf = n * n * q * std::abs(q) / (a * a * std::pow(r, 4.0 / 3.0));
  return (s0 - sf) / (1.0 - squared_froude(s, q, y, g));
}

BackwaterProfile backwater_profile(const PoolSpec& pool, double inflow, double end_depth, double g) {
  constexpr int kStepsPerCell = 8;
  const solver::Section section{pool.bottom_width_m, pool.side_slope};
  const double dx = pool.length_m / pool.cells;
  BackwaterProfile profile;
  profile.end_depth = end_depth;
  profile.cell_depth.resize(static_cast<std::size_t>(pool.cells));
  double y = end_depth, x = pool.length_m;
  // RK4 from x to x − length (upstream) in `steps` steps.
  auto integrate = [&](double length, int steps) {
    const double h = length / steps;
    for (int j = 0; j < steps; ++j, x -= h) {
      const double q = discharge_at(pool, inflow, x - 0.5 * h);
      auto f = [&](double yy) { return gvf_slope(section, pool.manning_n, pool.bed_slope, q, yy, g); };
      const double k1 = f(y), k2 = f(y - 0.5 * h * k1), k3 = f(y - 0.5 * h * k2), k4 = f(y - h * k3);
      y -= h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
      if (!(y > 0.0) || squared_froude(section, q, y, g) > 0.95) {
        throw std::runtime_error("pool '" + pool.name + "': the design backwater profile reaches critical flow at x = " +
                                 format_value(x - h) + " m (a target depth too low for Q = " + format_value(q) + " m^3/s?)");
      }
    }
  };
  integrate(0.5 * dx, kStepsPerCell / 2);  // x = L to the last cell centre
  profile.cell_depth.back() = y;
  for (int k = pool.cells - 2; k >= 0; --k) {
    integrate(dx, kStepsPerCell);
    profile.cell_depth[static_cast<std::size_t>(k)] = y;
  }
  integrate(0.5 * dx, kStepsPerCell / 2);  // first cell centre to x = 0
  profile.start_depth = y;
  return profile;
}

double gate_opening_for(const gates::GateGeometry& gate, double discharge, double y1, double y3, double max_opening) {
  const gates::SluiceGate law(gate.law);
  auto passed = [&](double a) { return gate.width * law.discharge(y1, y3, a); };
  if (passed(max_opening) < discharge) {
    throw std::runtime_error("cannot pass " + format_value(discharge) + " m^3/s with y1 = " + format_value(y1) + " m, y3 = " +
                             format_value(y3) + " m even fully open (" + format_value(max_opening) + " m passes " +
                             format_value(passed(max_opening)) + " m^3/s)");
  }
  // q rises with the opening up to the critical cap (sluice_gate.hpp): bisection keeps the
  // smallest opening that passes the flow.
  double lo = 0.0, hi = max_opening;
  for (int it = 0; it < 200 && hi - lo > 1e-12 * max_opening; ++it) {
    const double a = 0.5 * (lo + hi);
    (passed(a) < discharge ? lo : hi) = a;
  }
  return 0.5 * (lo + hi);
}

Scenario resolve_design(const Scenario& in) {
  if (!needs_design(in)) return in;
  Scenario s = in;
  const auto flows = design_flows(s);
  auto fail = [&](const std::string& key, const std::exception& e) -> void {
    throw InputError(s.source + ": " + key + ": " + e.what());
  };
  std::vector<double> start_depth(s.pools.size(), 0.0);  // design depth at each pool's x = 0
  for (std::size_t i = 0; i < s.pools.size(); ++i) {
    PoolSpec& p = s.pools[i];
    if (p.target_depth_m <= 0.0) continue;
    double profile_end_depth = p.target_depth_m;
    try {
      const BackwaterProfile profile = backwater_profile(p, flows[i].inflow, p.target_depth_m);
      p.design_depth_m = profile.cell_depth;
      p.design_discharge_m3s.resize(profile.cell_depth.size());
      for (int k = 0; k < p.cells; ++k) {
        p.design_discharge_m3s[static_cast<std::size_t>(k)] = discharge_at(p, flows[i].inflow, (k + 0.5) * p.length_m / p.cells);
      }
      start_depth[i] = profile.start_depth;
      profile_end_depth = profile.end_depth;
    } catch (const std::runtime_error& e) {
      fail("pools[" + std::to_string(i) + "].target_depth_m", e);
    }
    for (std::size_t k = 0; k < p.offtakes.size(); ++k) {
      OfftakeSpec& o = p.offtakes[k];
      if (o.kind != OfftakeKind::orifice || o.coefficient > 0.0) continue;  // fixed, or already sized
      const double design_depth = offtake_at_end(p, o.x_m) ? profile_end_depth
                                                           : p.design_depth_m[static_cast<std::size_t>(offtake_cell(p, o.x_m))];
      const double head = design_depth - o.invert_m;
      if (!(head > 0.0)) {
        throw InputError(s.source + ": pools[" + std::to_string(i) + "].offtakes[" + std::to_string(k) +
                         "].invert_m = " + format_value(o.invert_m) + ": expected it below the design level");
      }
      // An orifice's square root apart, as the solver evaluates it (solver/reach.cpp).
      o.coefficient = o.discharge_m3s / (o.exponent == 0.5 ? std::sqrt(head) : std::pow(head, o.exponent));
    }
  }
  if (s.head_gate && s.head_gate->auto_opening) {
    GateSpec& g = *s.head_gate;
    g.auto_opening = false;
    try {
      g.opening_m = gate_opening_for(gate_geometry(g), flows[0].inflow, s.upstream.level_m, start_depth[0],
                                     g.max_opening_m);
    } catch (const std::runtime_error& e) {
      fail("head_gate.opening_m", e);
    }
  }
  for (std::size_t i = 0; i < s.gates.size(); ++i) {
    GateSpec& g = s.gates[i];
    if (!g.auto_opening) continue;
    g.auto_opening = false;  // resolved: the copy has a number
    const PoolSpec &up = s.pools[i], &down = s.pools[i + 1];
    // The solver's link sees the reconstructed states at the two end faces: the end cells' slopes
    // are one-sided differences towards the interior, which extrapolate each pool's (linear) bed
    // to its end, so the beds there are the pools' beds at x = L and x = 0.
    const double z_up = up.bed_elevation_m - up.bed_slope * up.length_m, z_down = down.bed_elevation_m;
    const double sill = std::max(z_up, z_down);
    const double y1 = z_up + up.target_depth_m - sill;
    const double y3 = std::max(z_down + start_depth[i + 1] - sill, 0.0);
    try {
      g.opening_m = gate_opening_for(gate_geometry(g), flows[i].outflow, y1, y3, g.max_opening_m);
    } catch (const std::runtime_error& e) {
      fail("gates[" + std::to_string(i) + "].opening_m", e);
    }
  }
  return s;
}

}  // namespace canalsim::scenarios
