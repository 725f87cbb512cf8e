#include "solver/steady_state.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <vector>

#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

namespace canalsim::solver {
namespace {

constexpr int kStencil = 3;                    // half-width of the dependence, in cells (2 + margin)
constexpr int kColours = 2 * kStencil + 1;     // cells this far apart share a colour

// Everything KINSOL's callbacks need.
struct Problem {
  Canal* canal;
  double time;
  int cells;
  std::vector<double> rates;
  std::vector<double> unknown_scale;  // typical |A| and |Q| per unknown
  int evaluations = 0;
};

// Writes the unknowns (A, Q interleaved per cell) into the reaches. False if an area is negative.
bool load_state(Canal& canal, const double* u) {
  std::size_t c = 0;
  for (int r = 0; r < canal.reach_count(); ++r) {
    Reach& reach = canal.reach(r);
    for (int i = 0; i < reach.cells(); ++i, ++c) {
      if (!(u[2 * c] >= 0.0) || !std::isfinite(u[2 * c + 1])) return false;
      reach.area()[static_cast<std::size_t>(i)] = u[2 * c];
      reach.discharge()[static_cast<std::size_t>(i)] = u[2 * c + 1];
    }
  }
  return true;
}

void store_state(const Canal& canal, double* u) {
  std::size_t c = 0;
  for (int r = 0; r < canal.reach_count(); ++r) {
    const Reach& reach = canal.reach(r);
    for (int i = 0; i < reach.cells(); ++i, ++c) {
      u[2 * c] = reach.area()[static_cast<std::size_t>(i)];
      u[2 * c + 1] = reach.discharge()[static_cast<std::size_t>(i)];
    }
  }
}

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

// Coloured finite-difference Jacobian in CSC form: column j = 2c + m holds rows of cells
// c - kStencil .. c + kStencil.
int jacobian(N_Vector u, N_Vector f, SUNMatrix J, void* data, N_Vector work1, N_Vector) {
  auto* p = static_cast<Problem*>(data);
  const int n = p->cells;
  double* x = N_VGetArrayPointer(u);
  const double* f0 = N_VGetArrayPointer(f);
  double* fp = N_VGetArrayPointer(work1);
  sunindextype* colptr = SUNSparseMatrix_IndexPointers(J);
  sunindextype* rowidx = SUNSparseMatrix_IndexValues(J);
  double* values = SUNSparseMatrix_Data(J);
  // Pattern (fixed): the band of each column.
  sunindextype nz = 0;
  for (int c = 0; c < n; ++c) {
    for (int m = 0; m < 2; ++m) {
      colptr[2 * c + m] = nz;
      for (int r = std::max(0, c - kStencil); r <= std::min(n - 1, c + kStencil); ++r) {
        rowidx[nz++] = 2 * r;
        rowidx[nz++] = 2 * r + 1;
      }
    }
  }
  colptr[2 * n] = nz;
  std::vector<double> step(2 * static_cast<std::size_t>(n));
  for (int colour = 0; colour < kColours; ++colour) {
    for (int m = 0; m < 2; ++m) {
      for (int c = colour; c < n; c += kColours) {
        const std::size_t j = 2 * static_cast<std::size_t>(c) + m;
        step[j] = 1e-7 * std::max(std::abs(x[j]), p->unknown_scale[j]);
        x[j] += step[j];
      }
      const int failed = residual(u, work1, data);
      for (int c = colour; c < n; c += kColours) {
        const std::size_t j = 2 * static_cast<std::size_t>(c) + m;
        x[j] -= step[j];
        for (sunindextype k = colptr[j]; k < colptr[j + 1]; ++k) {
          values[k] = failed ? 0.0 : (fp[rowidx[k]] - f0[rowidx[k]]) / step[j];
        }
      }
      if (failed) return 1;
    }
  }
  return load_state(*p->canal, x) ? 0 : 1;
}

void silent(int, const char*, const char*, char*, void*) {}

struct KinsolDeleter {
  void operator()(void* mem) const { KINFree(&mem); }
};

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
  if (max_iterations < 1 || max_iterations > 1000) {
    return Status::error("SteadyStateOptions.max_iterations = " + std::to_string(max_iterations) +
                         ": expected an integer in [1, 1000]");
  }
  if (continuation_attempts < 0 || continuation_attempts > 20) {
    return Status::error("SteadyStateOptions.continuation_attempts = " +
                         std::to_string(continuation_attempts) + ": expected an integer in [0, 20]");
  }
  return Status::ok();
}

// One Newton solve from the canal's current state.
static SteadyStateSummary newton(Canal& canal, const SteadyStateOptions& options) {
  SteadyStateSummary summary;
  const int n = canal.total_cells();
  const sunindextype unknowns = 2 * static_cast<sunindextype>(n);

  Problem problem{&canal, canal.time(), n, {}, std::vector<double>(static_cast<std::size_t>(unknowns)), 0};
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

  sundials::Context context;
  N_Vector u = N_VNew_Serial(unknowns, context);
  N_Vector u_scale = N_VNew_Serial(unknowns, context);
  N_Vector f_scale = N_VNew_Serial(unknowns, context);
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
  SUNMatrix J = SUNSparseMatrix(unknowns, unknowns, unknowns * 2 * kColours, CSC_MAT, context);
  SUNLinearSolver ls = SUNLinSol_KLU(u, J, context);
  std::unique_ptr<void, KinsolDeleter> kin(KINCreate(context));
  int flag = KINInit(kin.get(), residual, u);
  if (flag == KIN_SUCCESS) flag = KINSetUserData(kin.get(), &problem);
  if (flag == KIN_SUCCESS) flag = KINSetErrHandlerFn(kin.get(), silent, nullptr);  // we report
  if (flag == KIN_SUCCESS) flag = KINSetLinearSolver(kin.get(), ls, J);
  if (flag == KIN_SUCCESS) flag = KINSetJacFn(kin.get(), jacobian);
  if (flag == KIN_SUCCESS) flag = KINSetMaxSetupCalls(kin.get(), 1);  // fresh Jacobian every step
  if (flag == KIN_SUCCESS) flag = KINSetNumMaxIters(kin.get(), options.max_iterations);
  if (flag == KIN_SUCCESS) flag = KINSetFuncNormTol(kin.get(), 1e-13);
  if (flag == KIN_SUCCESS) flag = KINSetScaledStepTol(kin.get(), options.depth_tolerance * canal.reach(0).section().top_width(max_depth) / a_scale);
  if (flag == KIN_SUCCESS) flag = KINSol(kin.get(), u, KIN_LINESEARCH, u_scale, f_scale);
  long iterations = 0;
  KINGetNumNonlinSolvIters(kin.get(), &iterations);
  summary.iterations = static_cast<int>(iterations);
  if (flag < 0) {
    load_state(canal, initial.data());
    summary.status = Status::error("steady state not found after " + std::to_string(iterations) +
                                   " Newton iterations: " + kinsol_message(flag));
  } else {
    load_state(canal, N_VGetArrayPointer(u));
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
  summary.residual_evaluations = problem.evaluations;
  kin.reset();
  SUNLinSolFree(ls);
  SUNMatDestroy(J);
  N_VDestroy(f_scale);
  N_VDestroy(u_scale);
  N_VDestroy(u);
  return summary;
}

}  // namespace canalsim::solver

namespace canalsim::solver {

SteadyStateSummary solve_steady_state(Canal& canal, const SteadyStateOptions& options) {
  SteadyStateSummary summary;
  if (summary.status = options.validate(); !summary.status) return summary;
  if (summary.status = canal.check_ready(); !summary.status) return summary;
  // Pseudo-transient continuation: Newton's basin around a non-smooth (limited) scheme can be
  // small, so when it fails, march a few wave-crossing times of the longest reach towards the
  // steady state and try again (Kelley & Keyes 1998). Marching advances boundary states
  // (reservoirs, actuators) as any run would.
  double crossing = 0.0;
  for (int r = 0; r < canal.reach_count(); ++r) {
    const Reach& reach = canal.reach(r);
    double depth = 1e-3;
    for (int i = 0; i < reach.cells(); ++i) depth = std::max(depth, reach.depth(i));
    crossing = std::max(crossing, reach.length() / std::sqrt(canal.options().gravity * depth));
  }
  const double start_time = canal.time();
  int iterations = 0, evaluations = 0;
  for (int attempt = 0; attempt <= options.continuation_attempts; ++attempt) {
    if (attempt > 0) {
      const Status marched = canal.advance_to(canal.time() + 3.0 * crossing);
      if (!marched) {
        summary.status = marched;
        break;
      }
    }
    summary = newton(canal, options);
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
