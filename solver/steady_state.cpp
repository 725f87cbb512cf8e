#include "solver/steady_state.hpp"

#include "solver/illinois.hpp"
#include "solver/rates_jacobian.hpp"
#include "solver/scheme.hpp"
#include "solver/sundials_handles.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

namespace canalsim::solver {
namespace {

// Everything KINSOL's callbacks need.
struct Problem {
  Canal* canal;
  double time;
  RatesPattern pattern;
  std::vector<double> rates;
  std::vector<double> unknown_scale;  // typical |A| and |Q| per unknown
  int evaluations = 0;
};

// KINSOL residual: F(u) = L(u). A negative area is a recoverable failure (KINSOL backtracks).
int residual(N_Vector u, N_Vector f, void* data) {
  auto* p = static_cast<Problem*>(data);
  if (!load_state(*p->canal, N_VGetArrayPointer(u))) return 1;
  p->canal->evaluate_rates(p->time, p->rates);
  ++p->evaluations;
  double* out = N_VGetArrayPointer(f);
  for (std::size_t k = 0; k < p->rates.size(); ++k) {
    if (!std::isfinite(p->rates[k])) return 1;
    out[k] = p->rates[k];
  }
  return 0;
}

// The coloured finite-difference Jacobian (solver/rates_jacobian.hpp) in KINSOL's CSC matrix.
int jacobian(N_Vector u, N_Vector f, SUNMatrix J, void* data, N_Vector, N_Vector) {
  auto* p = static_cast<Problem*>(data);
  std::copy(p->pattern.column_start.begin(), p->pattern.column_start.end(), SUNSparseMatrix_IndexPointers(J));
  std::copy(p->pattern.row.begin(), p->pattern.row.end(), SUNSparseMatrix_IndexValues(J));
  const bool ok = rates_jacobian(*p->canal, p->time, N_VGetArrayPointer(u), N_VGetArrayPointer(f), p->unknown_scale,
                                 p->pattern, {}, SUNSparseMatrix_Data(J), &p->evaluations);
  return ok ? 0 : 1;
}

// --- first guess by shooting -----------------------------------------------------------------
//
// For one reach between two boundaries without lateral flow the steady discharge Q is uniform
// and the profile is a gradually varied flow curve. Shooting on Q: the downstream boundary's own
// flux fixes the last cell's depth (mass flux = Q), the energy equation with Manning friction
// (standard step, Chow 1959 §10-3) carries the depth upstream cell by cell, and Q is corrected by
// the secant method until the upstream boundary also passes Q. The result is not the discrete
// steady state (the scheme balances momentum with reconstructed states) but lies within ~1e-4 of
// it, well inside Newton's quadratic basin, where the flat start (Q = 0) took 9–15 iterations.
// Used only when it lowers the residual; otherwise Newton starts from the canal's state.

struct Shooting {
  Canal& canal;
  double time;
  const Reach& reach;
  const Section& section;
  double g;
  std::vector<double> depth;  // cell depths of the last profile

  double boundary_mass(End end, double h, double q) const {
    const int i = end == End::upstream ? 0 : reach.cells() - 1;
    Flux f{};
    canal.boundary_flux(0, end, {section.area(h), q, h, reach.bed()[static_cast<std::size_t>(i)]}, time, &f);
    return f.mass;
  }

  // Depth of the last cell for which the downstream boundary passes q; NaN if none is found.
  double downstream_depth(double q, double start) const {
    auto f = [&](double h) { return boundary_mass(End::downstream, h, q) - q; };
    // Secant from the previous shot's depth (it moves little between shots): four or five calls.
    {
      double h0 = start, f0 = f(h0), h1 = start * (1.0 + 1e-3), f1 = f(h1);
      for (int it = 0; it < 12 && std::isfinite(f0) && std::isfinite(f1) && f1 != f0; ++it) {
        const double h2 = std::clamp(h1 - f1 * (h1 - h0) / (f1 - f0), 0.5 * h1, 2.0 * h1);
        h0 = h1;
        f0 = f1;
        h1 = h2;
        f1 = f(h1);
        if (std::abs(h1 - h0) <= 1e-10 * h1 && std::isfinite(f1)) return h1;
      }
    }
    // Otherwise bracket and refine.
    double lo = start, flo = f(lo);
    if (!std::isfinite(flo)) return NAN;
    // Walk away from the start (mass flux grows with depth for a structure or a level) until the
    // sign changes: by doubling upwards, halving downwards.
    double hi = lo, fhi = flo;
    for (int k = 0; k < 60 && (flo < 0.0) == (fhi < 0.0) && fhi != 0.0; ++k) {
      lo = hi;
      flo = fhi;
      hi = flo < 0.0 ? hi * 1.25 : hi * 0.8;
      fhi = f(hi);
      if (!std::isfinite(fhi)) return NAN;
    }
    if (fhi == 0.0) return hi;
    if ((flo < 0.0) == (fhi < 0.0)) return NAN;
    if (lo > hi) {
      std::swap(lo, hi);
      std::swap(flo, fhi);
    }
    IllinoisOptions o;
    o.max_iterations = 60;
    o.relative_width = 1e-10;
    return illinois(f, lo, hi, flo, fhi, o).last;
  }

  // Friction slope n² Q|Q| / (A² R^{4/3}) = n² Q|Q| ρ^{4/3} / A² with ρ = P/A (no pow).
  double friction_slope(double h, double q) const {
    const double a = section.area(h), rho = section.wetted_perimeter(h) / a;
    const double rho_m13 = inverse_cube_root_positive(rho);
    return reach.manning_n() * reach.manning_n() * q * std::abs(q) * rho * rho * rho_m13 * rho_m13 / (a * a);
  }

  // Standard-step profile from the last cell's depth upstream; false if it leaves the subcritical
  // branch or fails to converge.
  bool profile(double q, double h_last) {
    const int n = reach.cells();
    const double dx = reach.cell_length();
    const auto& z = reach.bed();
    depth.assign(static_cast<std::size_t>(n), 0.0);
    depth.back() = h_last;
    auto energy = [&](double h) {
      const double a = section.area(h);
      return h + q * q / (2.0 * g * a * a);
    };
    for (int i = n - 2; i >= 0; --i) {
      const auto j = static_cast<std::size_t>(i);
      const double h1 = depth[j + 1];
      const double head = z[j + 1] + energy(h1) + 0.5 * dx * friction_slope(h1, q);
      // Start from the previous cell's depth change (the profile is smooth away from bed steps).
      const double trend = i + 2 < n ? h1 - depth[j + 2] - (z[j + 1] - z[j + 2]) : 0.0;
      double h = std::max(h1 + trend + z[j + 1] - z[j], 0.5 * h1);
      bool converged = false;
      for (int it = 0; it < 30; ++it) {
        // F(h) = z + E(h) − ½ dx S_f(h) − head; F' = 1 − Fr² + (10/3)·½ dx S_f / h (wide channel).
        const double a = section.area(h), t = section.top_width(h);
        const double froude2 = q * q * t / (g * a * a * a);
        const double sf = friction_slope(h, q);
        const double slope = 1.0 - froude2 + (5.0 / 3.0) * dx * sf / h;
        if (!(froude2 < 0.9) || !(slope > 0.0)) return false;  // near critical: no guess
        const double step = (z[j] + energy(h) - 0.5 * dx * sf - head) / slope;
        h = std::max(h - step, 0.5 * h);
        // Converged when the step is below 1e-6 h: Newton's error after it is ~(1e-6)² h, far
        // below the O(dx²) gap between this profile and the discrete steady state.
        if (std::abs(step) <= 1e-6 * h) {
          converged = true;
          break;
        }
      }
      if (!converged || !std::isfinite(h)) return false;
      depth[j] = h;
    }
    return true;
  }

  // Upstream mismatch of discharge q: what the upstream boundary passes minus q (NaN: failed).
  double mismatch(double q, double* h_last) {
    const double h = downstream_depth(q, *h_last);
    if (!std::isfinite(h) || !profile(q, h)) return NAN;
    *h_last = h;
    return boundary_mass(End::upstream, depth.front(), q) - q;
  }
};

// Replaces the canal's state by the shooting profile when it succeeds; returns whether it did.
bool shooting_guess(Canal& canal, double time) {
  if (canal.reach_count() != 1) return false;
  const Reach& reach = canal.reach(0);
  if (reach.has_end_withdrawal()) return false;
  for (double ql : reach.lateral_inflow())
    if (ql != 0.0) return false;
  Shooting shot{canal, time, reach, reach.section(), canal.options().gravity, {}};
  const int n = reach.cells();
  const double h_down = reach.depth(n - 1), h_up = reach.depth(0);
  if (!(h_down > 0.0 && h_up > 0.0)) return false;
  // Two discharges to start the secant: what each boundary passes for the current end cells.
  double q0 = shot.boundary_mass(End::downstream, h_down, reach.discharge().back());
  double q1 = shot.boundary_mass(End::upstream, h_up, reach.discharge().front());
  // Only flowing canals (Q > 0). A level boundary passes nothing for a pool at rest: start the
  // secant from the other end's discharge then.
  if (!(q0 > 0.0)) q0 = 0.99 * q1;
  if (!(q1 > 0.0)) q1 = 1.01 * q0;
  if (!(q0 > 0.0) || !(q1 > 0.0)) return false;
  if (q0 == q1) q1 = 1.01 * q0;
  double h_last = h_down;
  double m0 = shot.mismatch(q0, &h_last);
  double m1 = shot.mismatch(q1, &h_last);
  for (int it = 0; it < 40 && std::isfinite(m0) && std::isfinite(m1); ++it) {
    if (std::abs(q1 - q0) <= 1e-8 * q1 || m1 == 0.0) break;
    if (m1 == m0) return false;
    double q2 = q1 - m1 * (q1 - q0) / (m1 - m0);
    q2 = std::clamp(q2, 0.5 * q1, 2.0 * q1);  // keep Q positive and steps moderate
    q0 = q1;
    m0 = m1;
    q1 = q2;
    m1 = shot.mismatch(q1, &h_last);
  }
  if (!std::isfinite(m1) || std::abs(m1) > 1e-6 * q1) return false;
  Reach& r = canal.reach(0);
  for (int i = 0; i < n; ++i) {
    const auto j = static_cast<std::size_t>(i);
    r.area()[j] = r.section().area(shot.depth[j]);
    r.discharge()[j] = q1;
  }
  return true;
}

// Scaled residual size of the canal's state: max over cells of |dh/dt| / depth_scale and
// |dQ/dt| / q_scale (the guess is kept only if it lowers this).
double residual_size(Canal& canal, double time, std::vector<double>& rates, double depth_scale, double q_scale) {
  canal.evaluate_rates(time, rates);
  double worst = 0.0;
  std::size_t c = 0;
  for (int r = 0; r < canal.reach_count(); ++r) {
    const Reach& reach = canal.reach(r);
    for (int i = 0; i < reach.cells(); ++i, ++c) {
      const double top = std::max(reach.section().top_width(reach.depth(i)), 1e-12);
      const double v = std::max(std::abs(rates[2 * c]) / top / depth_scale, std::abs(rates[2 * c + 1]) / q_scale);
      worst = std::max(worst, std::isfinite(v) ? v : INFINITY);
    }
  }
  return worst;
}

void silent(int, const char*, const char*, char*, void*) {}

std::string kinsol_message(int flag) {
  switch (flag) {
    case KIN_LINESEARCH_NONCONV: return "the line search could not reduce the residual";
    case KIN_MAXITER_REACHED: return "the maximum number of Newton iterations was reached";
    case KIN_MXNEWT_5X_EXCEEDED: return "five consecutive Newton steps were too large (no nearby steady state?)";
    case KIN_LINESEARCH_BCFAIL: return "the line search kept failing its convergence condition";
    case KIN_LINSOLV_NO_RECOVERY: return "the sparse linear solve failed";
    case KIN_SYSFUNC_FAIL: return "the residual could not be evaluated (non-finite or negative depth)";
    case KIN_REPTD_SYSFUNC_ERR: return "the residual failed repeatedly (negative depths on the way)";
    default: return "KINSOL failed with flag " + std::to_string(flag);
  }
}

}  // namespace

Status SteadyStateOptions::validate() const {
  if (!(depth_tolerance > 0.0 && depth_tolerance <= 1e-2)) {
    return Status::error("SteadyStateOptions.depth_tolerance = " + std::to_string(depth_tolerance) +
                         ": expected a value in (0, 0.01] m");
  }
  for (const double rate : {stalled_depth_rate, stalled_discharge_rate}) {
    if (!(rate >= 0.0 && rate <= 1e-3)) {
      return Status::error("SteadyStateOptions.stalled_depth_rate / stalled_discharge_rate = " + std::to_string(rate) +
                           ": expected a value in [0, 1e-3]");
    }
  }
  if (max_iterations < 1 || max_iterations > 1000) {
    return Status::error("SteadyStateOptions.max_iterations = " + std::to_string(max_iterations) +
                         ": expected an integer in [1, 1000]");
  }
  if (iterations_per_jacobian < 1 || iterations_per_jacobian > 100) {
    return Status::error("SteadyStateOptions.iterations_per_jacobian = " + std::to_string(iterations_per_jacobian) +
                         ": expected an integer in [1, 100]");
  }
  if (continuation_attempts < 0 || continuation_attempts > 20) {
    return Status::error("SteadyStateOptions.continuation_attempts = " +
                         std::to_string(continuation_attempts) + ": expected an integer in [0, 20]");
  }
  return Status::ok();
}

// The largest |dh/dt| [m/s] and |dQ/dt| [m³/s²] of the canal's state, into `summary`.
static void measure_rates(Canal& canal, Problem& problem, SteadyStateSummary& summary) {
  canal.evaluate_rates(problem.time, problem.rates);
  std::size_t c = 0;
  for (int r = 0; r < canal.reach_count(); ++r) {
    const Reach& reach = canal.reach(r);
    for (int i = 0; i < reach.cells(); ++i, ++c) {
      const double top = reach.section().top_width(reach.depth(i));
      summary.max_depth_rate = std::max(summary.max_depth_rate, std::abs(problem.rates[2 * c]) / top);
      summary.max_discharge_rate = std::max(summary.max_discharge_rate, std::abs(problem.rates[2 * c + 1]));
    }
  }
}

static double largest_discharge(const Canal& canal) {
  double q = 0.0;
  for (int r = 0; r < canal.reach_count(); ++r) {
    for (double qi : canal.reach(r).discharge()) q = std::max(q, std::abs(qi));
  }
  return q;
}

// One Newton solve from the canal's current state.
static SteadyStateSummary newton(Canal& canal, const SteadyStateOptions& options, int iterations_per_jacobian) {
  SteadyStateSummary summary;
  const int n = canal.total_cells();
  const sunindextype unknowns = 2 * static_cast<sunindextype>(n);

  Problem problem{&canal, canal.time(), rates_jacobian_pattern(n), {},
                  std::vector<double>(static_cast<std::size_t>(unknowns)), 0};
  // Scales: a typical area and discharge per reach (1 mm of depth and 1% of the largest
  // discharge at least), so that tolerances and FD steps are relative to the flow.
  std::vector<double> initial(static_cast<std::size_t>(unknowns));
  store_state(canal, initial.data());
  double q_scale = 1e-9, a_scale = 1e-12;
  for (sunindextype k = 0; k < unknowns; k += 2) {
    a_scale = std::max(a_scale, std::abs(initial[static_cast<std::size_t>(k)]));
    q_scale = std::max(q_scale, std::abs(initial[static_cast<std::size_t>(k + 1)]));
  }
  for (sunindextype k = 0; k < unknowns; k += 2) {
    problem.unknown_scale[static_cast<std::size_t>(k)] = a_scale;
    problem.unknown_scale[static_cast<std::size_t>(k + 1)] = std::max(q_scale, 1e-3 * a_scale);
  }

  sundials::Context context;  // declared first: destroyed after every object made with it
  const VectorHandle u_handle(N_VNew_Serial(unknowns, context));
  const VectorHandle u_scale_handle(N_VNew_Serial(unknowns, context));
  const VectorHandle f_scale_handle(N_VNew_Serial(unknowns, context));
  N_Vector u = u_handle.get(), u_scale = u_scale_handle.get(), f_scale = f_scale_handle.get();
  std::copy(initial.begin(), initial.end(), N_VGetArrayPointer(u));
  // Unknowns scaled by their typical size; residuals by the rate that size changes at over one
  // cell-crossing time of a gravity wave, dx / sqrt(g h): both are then O(1) near the solution.
  double min_dx = INFINITY, max_depth = 1e-6;
  for (int r = 0; r < canal.reach_count(); ++r) {
    min_dx = std::min(min_dx, canal.reach(r).cell_length());
    for (int i = 0; i < canal.reach(r).cells(); ++i) max_depth = std::max(max_depth, canal.reach(r).depth(i));
  }
  const double crossing = min_dx / std::sqrt(canal.options().gravity * max_depth);
  for (sunindextype k = 0; k < unknowns; ++k) {
    const double scale = problem.unknown_scale[static_cast<std::size_t>(k)];
    NV_Ith_S(u_scale, k) = 1.0 / scale;
    NV_Ith_S(f_scale, k) = crossing / scale;
  }
  const MatrixHandle J_handle(SUNSparseMatrix(unknowns, unknowns, static_cast<sunindextype>(problem.pattern.row.size()),
                                              CSC_MAT, context));
  SUNMatrix J = J_handle.get();
  const LinearSolverHandle ls_handle(SUNLinSol_KLU(u, J, context));
  SUNLinearSolver ls = ls_handle.get();
  // The Jacobian is a band (unknowns ordered along the canal, cell by cell): the natural ordering
  // keeps the factors inside it, and skips COLAMD's analysis (a third of the setup).
  SUNLinSol_KLUSetOrdering(ls, 2);
  const KinsolHandle kin(KINCreate(context));
  int flag = KINInit(kin.get(), residual, u);
  if (flag == KIN_SUCCESS) flag = KINSetUserData(kin.get(), &problem);
  if (flag == KIN_SUCCESS) flag = KINSetErrHandlerFn(kin.get(), silent, nullptr);  // we report
  if (flag == KIN_SUCCESS) flag = KINSetLinearSolver(kin.get(), ls, J);
  if (flag == KIN_SUCCESS) flag = KINSetJacFn(kin.get(), jacobian);
  // Modified Newton from the shooting guess: one Jacobian serves up to 3 iterations (each
  // then costs one residual instead of 2·kRateColours + 1; KINSOL re-evaluates it when the line search
  // stalls). From any other start a fresh Jacobian every iteration: far from the solution a stale
  // one took 35 iterations where Newton takes 9.
  if (flag == KIN_SUCCESS) flag = KINSetMaxSetupCalls(kin.get(), iterations_per_jacobian);
  if (flag == KIN_SUCCESS) flag = KINSetNumMaxIters(kin.get(), options.max_iterations);
  if (flag == KIN_SUCCESS) flag = KINSetFuncNormTol(kin.get(), 1e-13);
  if (flag == KIN_SUCCESS) flag = KINSetScaledStepTol(kin.get(), options.depth_tolerance * canal.reach(0).section().top_width(max_depth) / a_scale);
  if (flag == KIN_SUCCESS) flag = KINSol(kin.get(), u, KIN_LINESEARCH, u_scale, f_scale);
  long iterations = 0;
  KINGetNumNonlinSolvIters(kin.get(), &iterations);
  summary.iterations = static_cast<int>(iterations);
  summary.residual_evaluations = problem.evaluations;
  // KINSOL iterates in place: u holds the solution, or the last iterate when it failed (which a
  // stalled_depth_rate may accept).
  const bool usable = (flag >= 0 || options.stalled_depth_rate > 0.0) && load_state(canal, N_VGetArrayPointer(u));
  if (usable) measure_rates(canal, problem, summary);
  if (flag >= 0) return summary;
  if (usable && summary.max_depth_rate <= options.stalled_depth_rate &&
      summary.max_discharge_rate <= options.stalled_discharge_rate * largest_discharge(canal)) {
    summary.stalled = true;
    summary.stall = "the last attempt stalled after " + std::to_string(iterations) + " iterations: " + kinsol_message(flag);
    return summary;
  }
  load_state(canal, initial.data());
  summary.max_depth_rate = summary.max_discharge_rate = 0.0;
  summary.status = Status::error("steady state not found after " + std::to_string(iterations) +
                                 " Newton iterations: " + kinsol_message(flag));
  return summary;
}

}  // namespace canalsim::solver

namespace canalsim::solver {

namespace {

// The shooting profile replaces the state only if its residual is smaller; returns whether it did.
bool try_shooting_guess(Canal& canal) {
  const double time = canal.time();
  std::vector<double> saved(2 * static_cast<std::size_t>(canal.total_cells()));
  store_state(canal, saved.data());
  double depth_scale = 1e-6, q_scale = 1e-12;
  for (int r = 0; r < canal.reach_count(); ++r) {
    for (int i = 0; i < canal.reach(r).cells(); ++i) depth_scale = std::max(depth_scale, canal.reach(r).depth(i));
  }
  if (!shooting_guess(canal, time)) {
    load_state(canal, saved.data());
    return false;
  }
  for (double q : canal.reach(0).discharge()) q_scale = std::max(q_scale, std::abs(q));
  std::vector<double> rates;
  const double guessed = residual_size(canal, time, rates, depth_scale, q_scale);
  std::vector<double> guess(saved.size());
  store_state(canal, guess.data());
  load_state(canal, saved.data());
  if (!(guessed < residual_size(canal, time, rates, depth_scale, q_scale))) return false;
  load_state(canal, guess.data());
  return true;
}

}  // namespace

// Limiter homotopy for a scheme whose limiter is not differentiable (generalised minmod): its
// residual has kinks wherever one-sided slopes tie, and Newton from a guess far from the solution
// can fail within a few iterations ("the line search could not reduce the residual"; the lab's
// op2 on 400 cells with the six parameters of the calibration tests perturbed). The steady state
// of van Leer's limiter — differentiable but at extrema — is found from the same guess, and is
// within the schemes' difference of the sought one; Newton with the scheme's own limiter then
// starts inside its basin. No time passes, so the boundaries' states do not move and a stall
// within SteadyStateOptions::stalled_* is as acceptable as in a first attempt. Returns the failed
// `summary` unchanged, and the canal as it was, when either solve fails.
static SteadyStateSummary through_van_leer(Canal& canal, const SteadyStateOptions& options, SteadyStateSummary summary) {
  const Limiter own = canal.options().limiter;
  if (canal.options().order != SpatialOrder::second || own == Limiter::van_leer) return summary;
  std::vector<double> before(2 * static_cast<std::size_t>(canal.total_cells()));
  store_state(canal, before.data());
  canal.set_limiter(Limiter::van_leer);
  SteadyStateOptions smooth = options;
  smooth.stalled_depth_rate = smooth.stalled_discharge_rate = 0.0;
  const SteadyStateSummary van_leer = newton(canal, smooth, 1);
  canal.set_limiter(own);
  if (!van_leer.status) return summary;
  SteadyStateSummary own_limiter = newton(canal, options, 1);
  own_limiter.iterations += summary.iterations + van_leer.iterations;
  own_limiter.residual_evaluations += summary.residual_evaluations + van_leer.residual_evaluations;
  if (own_limiter.status) return own_limiter;
  load_state(canal, before.data());
  return summary;
}

// The longest reach's wave-crossing time L / sqrt(g h_max) in the canal's state (h_max >= 1 mm).
static double longest_crossing(const Canal& canal) {
  double crossing = 0.0;
  for (int r = 0; r < canal.reach_count(); ++r) {
    const Reach& reach = canal.reach(r);
    double depth = 1e-3;
    for (int i = 0; i < reach.cells(); ++i) depth = std::max(depth, reach.depth(i));
    crossing = std::max(crossing, reach.length() / std::sqrt(canal.options().gravity * depth));
  }
  return crossing;
}

// Each continuation march lasts this many crossing times of the longest reach.
constexpr double kCrossingsPerMarch = 3.0;

double continuation_span(const Canal& canal, const SteadyStateOptions& options) {
  return options.continuation_attempts * kCrossingsPerMarch * longest_crossing(canal);
}

SteadyStateSummary solve_steady_state(Canal& canal, const SteadyStateOptions& options) {
  SteadyStateSummary summary;
  if (summary.status = options.validate(); !summary.status) return summary;
  if (summary.status = canal.check_ready(); !summary.status) return summary;
  // Pseudo-transient continuation: Newton's basin around a non-smooth (limited) scheme can be
  // small, so when it fails, march a few wave-crossing times of the longest reach towards the
  // steady state and try again (Kelley & Keyes 1998). Marching advances boundary states
  // (reservoirs, actuators) as any run would.
  const double crossing = longest_crossing(canal);
  const double start_time = canal.time();
  int iterations = 0, evaluations = 0;
  for (int attempt = 0; attempt <= options.continuation_attempts; ++attempt) {
    if (attempt > 0) {
      const Status marched = canal.advance_to(canal.time() + kCrossingsPerMarch * crossing);
      if (!marched) {
        summary.status = marched;
        break;
      }
    }
    std::vector<double> before;
    if (attempt == 0 && options.first_guess) {
      before.resize(2 * static_cast<std::size_t>(canal.total_cells()));
      store_state(canal, before.data());
    }
    const bool guessed = attempt == 0 && options.first_guess && try_shooting_guess(canal);
    // A stall is accepted only before any march: a march moves the boundaries' own states (a
    // reservoir's level drifts from its set point), which a steady canal then starts from.
    SteadyStateOptions this_attempt = options;
    if (attempt > 0) this_attempt.stalled_depth_rate = this_attempt.stalled_discharge_rate = 0.0;
    summary = newton(canal, this_attempt, guessed ? options.iterations_per_jacobian : 1);
    if (!summary.status && attempt == 0) summary = through_van_leer(canal, this_attempt, summary);
    // A failed Newton from the guess leaves the caller's state, not the guess, to continue from.
    if (!summary.status && guessed) load_state(canal, before.data());
    iterations += summary.iterations;
    evaluations += summary.residual_evaluations;
    if (summary.status) break;
  }
  canal.set_time(start_time);
  summary.iterations = iterations;
  summary.residual_evaluations = evaluations;
  return summary;
}

}  // namespace canalsim::solver
