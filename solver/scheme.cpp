// Kernels of one Runge–Kutta stage (see scheme.hpp). The loops carry `omp simd` so that the
// max/min/sum reductions vectorise without -ffast-math (compiled with -fopenmp-simd: no OpenMP
// runtime), and on x86-64 with GCC the entry points are cloned for AVX-512F / AVX2 / baseline (feature tests, not CPU models) and
// chosen at load time (target_clones), so the library stays portable.
#include "solver/scheme.hpp"

#include <cfloat>
#include <cmath>
#include <type_traits>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_ADDRESS__)
#define CANALSIM_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define CANALSIM_VECTOR_CLONES
#endif

namespace canalsim::solver {

struct ReachKernels {
  // Steps (1)–(3). Returns the largest wave speed over interior faces.
  template <class Ops>
  [[gnu::always_inline]] static inline double interior_fluxes(Reach& r, const Ops& ops, const StageSettings& s) {
    const int n = r.cells_;
    const double* __restrict a = r.area_.data();
    const double* __restrict q = r.discharge_.data();
    const double* __restrict z = r.bed_.data();
    double* __restrict h = r.h_.data();
    double* __restrict u = r.u_.data();
    double* __restrict eta = r.eta_.data();
    double* __restrict inv_a = r.inv_area_.data();
    double* __restrict dh = r.dh_.data();
    double* __restrict du = r.du_.data();
    double* __restrict deta = r.deta_.data();
    const double dry = s.dry_depth;
    primitives_loop(n, a, q, z, h, u, eta, inv_a, ops, dry);
    if (s.second_order) {
      const double th = s.theta;
      if (s.centred_kinks) {
        // Linearisation (not a time step's path): tolerances relative to the reach's flow.
        double deepest = 0.0;
        for (int i = 0; i < n; ++i) deepest = std::max(deepest, h[i]);
        const double depth_tolerance = 1e-5 * deepest, velocity_tolerance = 1e-5 * ops.celerity(deepest);
        for (int i = 1; i < n - 1; ++i) {
          dh[i] = slope_centred_at_kinks(h[i - 1], h[i], h[i + 1], depth_tolerance, s.van_leer, th);
          deta[i] = slope_centred_at_kinks(eta[i - 1], eta[i], eta[i + 1], depth_tolerance, s.van_leer, th);
          du[i] = slope_centred_at_kinks(u[i - 1], u[i], u[i + 1], velocity_tolerance, s.van_leer, th);
        }
      } else if (s.van_leer) {
#pragma omp simd
        for (int i = 1; i < n - 1; ++i) {
          dh[i] = van_leer_slope(h[i - 1], h[i], h[i + 1]);
          deta[i] = van_leer_slope(eta[i - 1], eta[i], eta[i + 1]);
          du[i] = van_leer_slope(u[i - 1], u[i], u[i + 1]);
        }
      } else {
#pragma omp simd
        for (int i = 1; i < n - 1; ++i) {
          dh[i] = limited_slope(h[i - 1], h[i], h[i + 1], th);
          deta[i] = limited_slope(eta[i - 1], eta[i], eta[i + 1], th);
          du[i] = limited_slope(u[i - 1], u[i], u[i + 1], th);
        }
      }
      // End cells: the one-sided difference towards the interior when both cells are wet (so the
      // boundary face sees a second-order state and a bed extrapolated to the end, which keeps
      // steady friction profiles second order up to the boundary); zero slope next to dry cells,
      // which keeps lake-at-rest exact at shores. The depth slope is clipped to keep h ± dh/2 >= 0.
      end_slopes(h, eta, u, dh, deta, du, 0, 1, dry);
      end_slopes(h, eta, u, dh, deta, du, n - 1, n - 2, dry);
    }
    double* __restrict fm = r.face_mass_.data();
    double* __restrict fl = r.face_momentum_left_.data();
    double* __restrict fr = r.face_momentum_right_.data();
    double smax = 0.0;
#pragma omp simd reduction(max : smax)
    for (int f = 1; f < n; ++f) {
      const int L = f - 1, R = f;
      // Reconstructed values at the face from each side.
      const double hm = h[L] + 0.5 * dh[L], etam = eta[L] + 0.5 * deta[L];
      const double hp = h[R] - 0.5 * dh[R], etap = eta[R] - 0.5 * deta[R];
      const double um = u[L] + 0.5 * du[L], up = u[R] - 0.5 * du[R];
      // Hydrostatic reconstruction: one bed level per face, depths that keep η.
      const double zface = std::max(etam - hm, etap - hp);
      const double hl = std::max(0.0, etam - zface);
      const double hr = std::max(0.0, etap - zface);
      const PointState left{ops.area(hl), hl > dry ? um : 0.0, ops.pressure(hl), ops.celerity(hl)};
      const PointState right{ops.area(hr), hr > dry ? up : 0.0, ops.pressure(hr), ops.celerity(hr)};
      const Flux flux = hll_flux(left, right);
      fm[f] = flux.mass;
      // Each side sees the pressure of its own reconstructed depth (Audusse et al. 2004, eq. 2.6).
      fl[f] = flux.momentum + (ops.pressure(hm) - left.pressure);
      fr[f] = flux.momentum + (ops.pressure(hp) - right.pressure);
      smax = std::max(smax, flux.max_speed);
    }
    return smax;
  }

  // Step (1). Arrays as __restrict parameters and the section by value, like update_loop, and
  // selects on values instead of std::max: written inline with std::max, GCC 12 reported "control
  // flow in loop" (-fopt-info-vec-missed) and ran this loop scalar, about a sixth of the stage
  // time in the lab flume.
  template <class Ops>
  [[gnu::always_inline]] static inline void primitives_loop(
      const int n, const double* __restrict a, const double* __restrict q, const double* __restrict z,
      double* __restrict h, double* __restrict u, double* __restrict eta, double* __restrict inv_a,
      const Ops ops, const double dry) {
#pragma omp simd
    for (int i = 0; i < n; ++i) {
      const double ai = a[i];
      const double depth = ops.depth(ai);
      const double hi = depth > 0.0 ? depth : 0.0;
      h[i] = hi;
      // Divide unconditionally (guarded denominator) and select: a conditional division would
      // stop the loop from vectorising. 1/A is kept for the friction term of the update.
      const double inverse_area = 1.0 / (ai > 1e-300 ? ai : 1e-300);
      inv_a[i] = inverse_area;
      // Computed whatever the branch, then selected.
      const double velocity = q[i] * inverse_area;
      u[i] = hi > dry ? velocity : 0.0;
      eta[i] = z[i] + hi;
    }
  }

  // Step (4). The centred source g Ā (z_left − z_right) with Ā = (I1(h_right) − I1(h_left)) /
  // (h_right − h_left) cancels the pressure difference of a lake at rest exactly (Audusse et al.
  // 2004, §3); friction Q ← Q* / (1 + dt g n² |Q| / (A R^{4/3})) is linearly implicit, so it
  // damps without bound but never reverses the flow (e.g. Liang & Marche 2009).
  template <class Ops, bool kFriction>
  [[gnu::always_inline]] static inline UpdateResult update(Reach& r, const Ops& ops, const UpdateSettings& s) {
    return update_loop<Ops, kFriction>(r.cells_, r.area_.data(), r.discharge_.data(), r.area0_.data(),
                                       r.discharge0_.data(), r.h_.data(), r.inv_area_.data(), r.u_.data(), r.dh_.data(),
                                       r.deta_.data(), r.lateral_inflow_.data(), r.face_mass_.data(),
                                       r.face_momentum_left_.data(), r.face_momentum_right_.data(), ops,
                                       s.dt, s.dt / r.dx_, s.alpha, s.dry_depth, s.friction);
  }

  // The loop takes its arrays as __restrict parameters and its constants by value: GCC honours
  // restrict only on parameters, and without it the stores to A and Q could alias the constants
  // and the loop would not vectorise.
  template <class Ops, bool kFriction>
  [[gnu::always_inline]] static inline UpdateResult update_loop(
      const int n, double* __restrict a, double* __restrict q, const double* __restrict a0,
      const double* __restrict q0, const double* __restrict h, const double* __restrict inv_a,
      const double* __restrict u,
      const double* __restrict dh, const double* __restrict deta, const double* __restrict ql,
      const double* __restrict fm, const double* __restrict fl, const double* __restrict fr,
      const Ops ops, const double dt, const double dt_dx, const double alpha, const double dry,
      const double friction) {
    const double beta = 1.0 - alpha;
    const double dry_area = ops.area(dry);
    const double g = ops.g;
    // Integer OR flags instead of min/sum reductions: GCC vectorises those without -ffast-math
    // (an `omp simd` min/+ reduction kept this loop scalar).
    int negative = 0, non_finite = 0, has_lateral = 0;
    for (int i = 0; i < n; ++i) {
      const double hleft = h[i] - 0.5 * dh[i], hright = h[i] + 0.5 * dh[i];
      const double source = g * ops.mean_area(hleft, hright) * (dh[i] - deta[i]);
      const double qlat = h[i] > dry ? ql[i] : std::max(ql[i], 0.0);
      const double a_star = a[i] - dt_dx * (fm[i + 1] - fm[i]) + dt * qlat;
      double q_star = q[i] - dt_dx * (fl[i + 1] - fr[i] - source) + dt * std::min(qlat, 0.0) * u[i];
      if constexpr (kFriction) {
        // k from the stage's own state (not Q*): a steady state then satisfies the discrete
        // momentum balance L(U) = k(U) Q exactly, for any dt.
        // Q* / (1 + dt k), k = g n² |Q| R^{-4/3} / A, with a division-free inverse cube root.
        // With ρ = P/A = 1/R (from the stored 1/A): R^{-4/3} = ρ^{4/3} = ρ² (ρ^{-1/3})², so the
        // whole term costs one division.
        const double rho = ops.perimeter(h[i]) * inv_a[i];
        const double rho_m13 = inverse_cube_root_positive(rho);
        const double rho43 = rho * rho * (rho_m13 * rho_m13);
        const double k_dt = h[i] > dry ? dt * friction * std::abs(q[i]) * rho43 * inv_a[i] : 0.0;
        q_star = q_star / (1.0 + k_dt);
      }
      q_star = a_star > dry_area ? q_star : 0.0;  // same as h(A*) > dry, without a square root
      const double a_new = alpha * a0[i] + beta * a_star;
      const double q_new = alpha * q0[i] + beta * q_star;
      a[i] = a_new;
      q[i] = q_new;
      negative |= a_new < 0.0;
      non_finite |= !(std::abs(a_new) + std::abs(q_new) <= DBL_MAX);  // NaN compares false
      has_lateral |= ql[i] != 0.0;
    }
    return {negative != 0, non_finite != 0, has_lateral != 0};
  }
};


namespace {

RectangularOps rectangular_ops(const Section& s, double g) { return {s.bottom_width, 1.0 / s.bottom_width, g}; }
TrapezoidalOps trapezoidal_ops(const Section& s, double g) {
  return {s.bottom_width, s.side_slope, g, 2.0 * std::sqrt(1.0 + s.side_slope * s.side_slope)};
}

}  // namespace

// No lambdas or helper templates between the clone and the kernels: everything below must be
// inlined into each target clone to be compiled for that instruction set.
CANALSIM_VECTOR_CLONES
double compute_interior_fluxes(Reach& reach, const StageSettings& settings, double gravity) {
  const Section& s = reach.section();
  if (s.is_rectangular()) return ReachKernels::interior_fluxes(reach, rectangular_ops(s, gravity), settings);
  return ReachKernels::interior_fluxes(reach, trapezoidal_ops(s, gravity), settings);
}

CANALSIM_VECTOR_CLONES
UpdateResult apply_stage_update(Reach& reach, const UpdateSettings& settings, double gravity) {
  const Section& s = reach.section();
  const bool friction = settings.friction > 0.0;
  if (s.is_rectangular()) {
    const RectangularOps ops = rectangular_ops(s, gravity);
    return friction ? ReachKernels::update<RectangularOps, true>(reach, ops, settings)
                    : ReachKernels::update<RectangularOps, false>(reach, ops, settings);
  }
  const TrapezoidalOps ops = trapezoidal_ops(s, gravity);
  return friction ? ReachKernels::update<TrapezoidalOps, true>(reach, ops, settings)
                  : ReachKernels::update<TrapezoidalOps, false>(reach, ops, settings);
}

double lateral_volume_rate(const Reach& reach, double dry_depth) {
  const auto& h = reach.h_;
  const auto& ql = reach.lateral_inflow();
  double sum = 0.0;
  for (std::size_t i = 0; i < ql.size(); ++i) sum += h[i] > dry_depth ? ql[i] : std::max(ql[i], 0.0);
  return sum * reach.cell_length();
}

}  // namespace canalsim::solver
