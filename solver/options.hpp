// Options of the finite-volume solver and the description of one reach, as plain structs with
// documented defaults, and validation functions that name the offending field and its allowed
// range (in the style of Ceres' Solver::Options::IsValid).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "solver/section.hpp"
#include "solver/status.hpp"

namespace canalsim::solver {

enum class SpatialOrder { first = 1, second = 2 };

// Slope limiter of the second-order reconstruction (docs/numerics.md §2.1).
enum class Limiter {
  // van Leer's harmonic limiter σ = 2 d₋ d₊ / (d₋ + d₊) (same signs, else 0; van Leer 1974): a
  // differentiable function of the data except at extrema, so time marching settles on a steady
  // state at any stable Courant number (the default).
  van_leer,
  // Generalised minmod with parameter θ (limiter_theta). Its switching between one-sided
  // differences is not differentiable: above cfl ≈ 0.5 the scheme can keep a round-off-seeded
  // limit cycle (~1e-7 m in the lab flume) around a steady state instead of converging to it.
  generalised_minmod,
};

struct SolverOptions {
  // Courant number: dt = cfl * dx / max|wave speed| over all faces. Allowed (0, 1]. The second-order
  // scheme is positivity preserving for cfl <= 0.5 (Audusse & Bristeau 2005); above that a step
  // that would make a depth negative is retried with a smaller dt.
  double cfl = 0.45;
  // first: piecewise-constant states and forward Euler; second: MUSCL + Heun (SSP-RK2).
  SpatialOrder order = SpatialOrder::second;
  Limiter limiter = Limiter::van_leer;
  // Parameter θ in [1, 2] of the generalised minmod limiter (not used by van Leer's): 1 is minmod,
  // 2 is monotonised central. θ <= 2 keeps reconstructed depths non-negative and lake-at-rest exact
  // at wet/dry shores (van Leer's limiter satisfies the same bound, |σ| <= 2 min |d±|).
  double limiter_theta = 1.0;
  double gravity = 9.81;            // g [m/s²], > 0
  // Depth below which a cell is dry for velocity purposes: u = 0, Q set to 0 after a step. [m], in
  // [0, 0.01].
  double dry_depth = 1e-10;
  // Upper bound on the time step [s], > 0 (infinity: only the CFL condition limits dt).
  double max_time_step = std::numeric_limits<double>::infinity();
  // How many times a rejected step (negative depth, CFL violated in the second stage) may be
  // retried with half the time step before the run stops with an error. In [0, 60].
  int max_step_retries = 20;
};

// One prismatic reach: cells of equal length along x, x = 0 at the upstream end.
struct ReachSpec {
  std::string name = "reach";
  double length = 0.0;   // [m], > 0
  int cells = 0;         // >= 2
  Section section;       // bottom_width >= 0, side_slope >= 0, bottom_width + side_slope > 0
  double manning_n = 0.0;  // Manning coefficient [s/m^(1/3)], >= 0
  // Bed elevation z at each cell centre [m] (piecewise constant per cell); empty means flat at 0.
  std::vector<double> bed_elevation;
  // Initial depth h [m] and discharge Q [m³/s] at each cell; empty means 0 (dry, at rest).
  std::vector<double> initial_depth;
  std::vector<double> initial_discharge;
};

Status validate(const SolverOptions& options);
Status validate(const ReachSpec& spec);

}  // namespace canalsim::solver
