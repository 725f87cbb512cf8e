// Verification of the finite-volume scheme (solver/scheme.hpp driven through Canal): each test
// computes its reference in closed form (or by a root solve of a closed-form relation) here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <vector>

#include "solver/canal.hpp"
#include "solver/scheme.hpp"

namespace canalsim::solver {
namespace {

constexpr double g = 9.81;

// Bisection for a continuous f with a sign change on [lo, hi].
double bisect(const std::function<double(double)>& f, double lo, double hi) {
  double flo = f(lo);
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi), fm = f(mid);
    if ((fm <= 0.0) == (flo <= 0.0)) {
      lo = mid;
      flo = fm;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

ReachSpec rectangular_reach(double length, int cells, double width = 1.0) {
  ReachSpec spec;
  spec.length = length;
  spec.cells = cells;
  spec.section = {width, 0.0};
  return spec;
}

std::vector<double> cell_centres(const ReachSpec& spec) {
  std::vector<double> x(static_cast<std::size_t>(spec.cells));
  for (int i = 0; i < spec.cells; ++i) x[static_cast<std::size_t>(i)] = (i + 0.5) * spec.length / spec.cells;
  return x;
}

double max_velocity(const Reach& r) {
  double vmax = 0.0;
  for (int i = 0; i < r.cells(); ++i) {
    const auto j = static_cast<std::size_t>(i);
    if (r.area()[j] > 0.0) vmax = std::max(vmax, std::abs(r.discharge()[j] / r.area()[j]));
  }
  return vmax;
}

// ---------------------------------------------------------------------------------------------
// Building blocks of the kernels.

TEST(Kernels, InverseCubeRootIsAccurateTo1e9OverTwentyDecades) {
  for (double e = -10.0; e <= 10.0; e += 0.01) {
    const double x = std::pow(10.0, e);
    EXPECT_NEAR(inverse_cube_root_positive(x) * std::cbrt(x), 1.0, 1e-9) << "x = " << x;
  }
}

TEST(Kernels, GeneralisedMinmodIsZeroAtExtremaAndBetweenTheOneSidedDifferences) {
  EXPECT_EQ(limited_slope(1.0, 2.0, 1.5, 1.0), 0.0);
  EXPECT_EQ(limited_slope(1.0, 2.0, 4.0, 1.0), 1.0);
  EXPECT_EQ(limited_slope(1.0, 2.0, 4.0, 2.0), 1.5);  // centred difference when θ = 2
  EXPECT_EQ(limited_slope(4.0, 2.0, 1.0, 1.0), -1.0);
}

// ---------------------------------------------------------------------------------------------
// Lake at rest (well-balancing): η = const, u = 0 over a bump must stay exactly at rest.

double goutal_bump(double x) { return (x > 8.0 && x < 12.0) ? 0.2 - 0.05 * (x - 10.0) * (x - 10.0) : 0.0; }

void expect_lake_at_rest_preserved(const Section& section, double level, int steps) {
  ReachSpec spec = rectangular_reach(25.0, 100);
  spec.section = section;
  for (double x : cell_centres(spec)) {
    const double z = goutal_bump(x);
    spec.bed_elevation.push_back(z);
    spec.initial_depth.push_back(std::max(0.0, level - z));
  }
  Canal canal;
  ASSERT_TRUE(canal.add_reach(spec));
  canal.set_boundary(0, End::upstream, std::make_shared<WallBoundary>());
  canal.set_boundary(0, End::downstream, std::make_shared<WallBoundary>());
  for (int s = 0; s < steps; ++s) ASSERT_TRUE(canal.step()) << "step " << s;  // CFL-limited dt
  std::printf("    max |u| after %d steps: %.2e m/s\n", steps, max_velocity(canal.reach(0)));
  EXPECT_LT(max_velocity(canal.reach(0)), 1e-12);
}

TEST(LakeAtRest, RectangularOverSubmergedBumpStaysAtRestFor1000Steps) {
  expect_lake_at_rest_preserved({1.0, 0.0}, 0.5, 1000);
}
TEST(LakeAtRest, TrapezoidalOverSubmergedBumpStaysAtRestFor1000Steps) {
  expect_lake_at_rest_preserved({0.5, 1.5}, 0.5, 1000);
}
TEST(LakeAtRest, RectangularWithEmergingBumpAndDryCellsStaysAtRestFor1000Steps) {
  expect_lake_at_rest_preserved({1.0, 0.0}, 0.15, 1000);
}
TEST(LakeAtRest, TrapezoidalWithEmergingBumpAndDryCellsStaysAtRestFor1000Steps) {
  expect_lake_at_rest_preserved({0.5, 1.5}, 0.15, 1000);
}

// ---------------------------------------------------------------------------------------------
// Dam breaks (Stoker 1957 wet bed, Ritter 1892 dry bed), rectangular, flat, frictionless.

struct DamBreak {
  double h_left, h_right, x0;
  // Exact depth at (x, t) (Toro 2001, §4.3: rarefaction + shock, or rarefaction to a dry front).
  double depth(double x, double t) const {
    const double cl = std::sqrt(g * h_left);
    const double xi = (x - x0) / t;
    if (xi <= -cl) return h_left;
    const auto fan = [&](double s) { return std::pow(2.0 * cl - s, 2) / (9.0 * g); };
    if (h_right <= 0.0) return xi < 2.0 * cl ? fan(xi) : 0.0;
    // Middle state: rarefaction u = 2(cl − cm) equals the shock relation u = (hm − hr) sqrt(g(hm + hr)/(2 hm hr)).
    const double hm = bisect([&](double h) {
      return 2.0 * (cl - std::sqrt(g * h)) - (h - h_right) * std::sqrt(g * (h + h_right) / (2.0 * h * h_right));
    }, h_right, h_left);
    const double um = 2.0 * (cl - std::sqrt(g * hm));
    const double shock = hm * um / (hm - h_right);
    if (xi < um - std::sqrt(g * hm)) return fan(xi);
    if (xi < shock) return hm;
    return h_right;
  }
};

double dam_break_l1_error(const DamBreak& exact, int cells, double t_end) {
  ReachSpec spec = rectangular_reach(20.0, cells);
  for (double x : cell_centres(spec)) spec.initial_depth.push_back(x < exact.x0 ? exact.h_left : exact.h_right);
  Canal canal;
  EXPECT_TRUE(canal.add_reach(spec));
  canal.set_boundary(0, End::upstream, std::make_shared<TransmissiveBoundary>());
  canal.set_boundary(0, End::downstream, std::make_shared<TransmissiveBoundary>());
  EXPECT_TRUE(canal.advance_to(t_end));
  const Reach& r = canal.reach(0);
  double err = 0.0;
  for (int i = 0; i < r.cells(); ++i) err += std::abs(r.depth(i) - exact.depth(r.x_centre(i), t_end)) * r.cell_length();
  return err;
}

void expect_dam_break_converges(const DamBreak& exact, double t_end) {
  const double e100 = dam_break_l1_error(exact, 100, t_end);
  const double e400 = dam_break_l1_error(exact, 400, t_end);
  const double e1600 = dam_break_l1_error(exact, 1600, t_end);
  const double rate1 = std::log(e100 / e400) / std::log(4.0);
  const double rate2 = std::log(e400 / e1600) / std::log(4.0);
  std::printf("    L1 depth errors %.3e %.3e %.3e, rates %.3f %.3f\n", e100, e400, e1600, rate1, rate2);
  EXPECT_GE(rate1, 0.8);
  EXPECT_GE(rate2, 0.8);
}

TEST(DamBreak, StokerWetBedL1ErrorFallsAtRateAtLeast0p8) {
  expect_dam_break_converges({1.0, 0.1, 10.0}, 1.5);
}
TEST(DamBreak, RitterDryBedL1ErrorFallsAtRateAtLeast0p8) {
  expect_dam_break_converges({1.0, 0.0, 10.0}, 1.0);
}

// ---------------------------------------------------------------------------------------------
// Smooth simple wave before breaking: second order. With u − 2c = −2c∞ everywhere the solution is
// a right-going simple wave: h is constant along straight characteristics x = ξ + (3c(ξ) − 2c∞) t
// (Stoker 1957, ch. 10; Whitham 1974, §6.3), so h(x, t) = h0(ξ) with ξ solved by bisection.

struct SimpleWave {
  double h_inf = 1.0, amplitude = 0.1, centre = 3.0, half_width = 1.5;
  double h0(double x) const {
    const double s = (x - centre) / half_width;
    return std::abs(s) < 1.0 ? h_inf + amplitude * std::pow(std::cos(0.5 * M_PI * s), 4) : h_inf;
  }
  double u0(double x) const { return 2.0 * (std::sqrt(g * h0(x)) - std::sqrt(g * h_inf)); }
  double speed(double xi) const { return 3.0 * std::sqrt(g * h0(xi)) - 2.0 * std::sqrt(g * h_inf); }
  double depth(double x, double t) const {
    // ξ ↦ ξ + speed(ξ) t is increasing before breaking; bracket generously.
    const double cmax = speed(centre) + 1.0;
    const double xi = bisect([&](double s) { return s + speed(s) * t - x; }, x - cmax * t - 1.0, x + 1.0);
    return h0(xi);
  }
  // Cell average by 4-point Gauss–Legendre quadrature.
  double cell_average(double a, double b, double t) const {
    static const double xg[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
    static const double wg[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
    double s = 0.0;
    for (int k = 0; k < 4; ++k) s += wg[k] * depth(0.5 * (a + b) + 0.5 * (b - a) * xg[k], t);
    return 0.5 * s;
  }
};

double simple_wave_l1_error(const SimpleWave& w, int cells, double t_end) {
  ReachSpec spec = rectangular_reach(10.0, cells);
  const double dx = spec.length / cells;
  for (int i = 0; i < cells; ++i) {
    const double h = w.cell_average(i * dx, (i + 1) * dx, 0.0);
    spec.initial_depth.push_back(h);
    // Q = A u for the cell-averaged state: average of h u0 by the same quadrature.
    static const double xg[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
    static const double wg[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
    double q = 0.0;
    for (int k = 0; k < 4; ++k) {
      const double x = (i + 0.5) * dx + 0.5 * dx * xg[k];
      q += 0.5 * wg[k] * w.h0(x) * w.u0(x);
    }
    spec.initial_discharge.push_back(q);
  }
  SolverOptions options;
  options.limiter_theta = 1.5;
  Canal canal(options);
  EXPECT_TRUE(canal.add_reach(spec));
  canal.set_boundary(0, End::upstream, std::make_shared<TransmissiveBoundary>());
  canal.set_boundary(0, End::downstream, std::make_shared<TransmissiveBoundary>());
  EXPECT_TRUE(canal.advance_to(t_end));
  double err = 0.0;
  for (int i = 0; i < cells; ++i)
    err += std::abs(canal.reach(0).depth(i) - w.cell_average(i * dx, (i + 1) * dx, t_end)) * dx;
  return err;
}

TEST(SmoothFlow, SimpleWaveBeforeBreakingConvergesAtSecondOrder) {
  const SimpleWave w;
  // Breaking time: t_b = 1 / max(−d speed / dξ) (first crossing of characteristics).
  double steepest = 0.0;
  for (double x = w.centre - w.half_width; x < w.centre + w.half_width; x += 1e-4)
    steepest = std::max(steepest, -(w.speed(x + 1e-5) - w.speed(x - 1e-5)) / 2e-5);
  const double t_end = 0.5 / steepest;
  const double e1 = simple_wave_l1_error(w, 100, t_end);
  const double e2 = simple_wave_l1_error(w, 200, t_end);
  const double e3 = simple_wave_l1_error(w, 400, t_end);
  const double e4 = simple_wave_l1_error(w, 800, t_end);
  const double order = std::log(e3 / e4) / std::log(2.0);
  std::printf("    t = %.3f s (half the breaking time); L1 errors %.3e %.3e %.3e %.3e; orders %.2f %.2f %.2f\n",
              t_end, e1, e2, e3, e4, std::log(e1 / e2) / std::log(2.0), std::log(e2 / e3) / std::log(2.0), order);
  EXPECT_GE(order, 1.8);
}

// ---------------------------------------------------------------------------------------------
// Steady flow over a bump (Goutal & Maurel 1997): 25 m, b = 1, z = 0.2 − 0.05 (x − 10)² on
// 8 < x < 12. The steady depth satisfies Bernoulli, q²/(2 g h²) + h + z = E, whose subcritical or
// supercritical root is found by bisection on either side of the critical depth (q²/g)^(1/3).

double bernoulli_depth(double q, double energy, double z, bool subcritical) {
  const double hc = std::cbrt(q * q / g);
  const auto f = [&](double h) { return q * q / (2.0 * g * h * h) + h + z - energy; };
  return subcritical ? bisect(f, hc, 10.0) : bisect(f, 1e-6, hc);
}

struct BumpRun {
  std::vector<double> x, depth;
  double discharge_spread;  // max |Q − q| at the end
};

BumpRun run_bump(double q, double h_out, bool transmissive_outflow, double t_end) {
  ReachSpec spec = rectangular_reach(25.0, 200);
  for (double x : cell_centres(spec)) {
    spec.bed_elevation.push_back(goutal_bump(x));
    spec.initial_depth.push_back(std::max(h_out - goutal_bump(x), 0.0));
  }
  Canal canal;
  EXPECT_TRUE(canal.add_reach(spec));
  canal.set_boundary(0, End::upstream, FixedDischargeBoundary::constant(q));
  if (transmissive_outflow)
    canal.set_boundary(0, End::downstream, std::make_shared<TransmissiveBoundary>());
  else
    canal.set_boundary(0, End::downstream, FixedLevelBoundary::depth(h_out));
  EXPECT_TRUE(canal.advance_to(t_end));
  BumpRun run;
  run.discharge_spread = 0.0;
  const Reach& r = canal.reach(0);
  for (int i = 0; i < r.cells(); ++i) {
    run.x.push_back(r.x_centre(i));
    run.depth.push_back(r.depth(i));
    run.discharge_spread = std::max(run.discharge_spread, std::abs(r.discharge()[static_cast<std::size_t>(i)] - q));
  }
  return run;
}

double max_relative_error(const BumpRun& run, const std::function<double(double)>& exact,
                          const std::function<bool(double)>& include) {
  double worst = 0.0;
  for (std::size_t i = 0; i < run.x.size(); ++i)
    if (include(run.x[i])) worst = std::max(worst, std::abs(run.depth[i] - exact(run.x[i])) / exact(run.x[i]));
  return worst;
}

TEST(SteadyBump, SubcriticalFlowMatchesBernoulliWithin1Percent) {
  const double q = 4.42, h_out = 2.0;
  const BumpRun run = run_bump(q, h_out, false, 300.0);
  const double energy = q * q / (2.0 * g * h_out * h_out) + h_out;
  const double err = max_relative_error(run, [&](double x) { return bernoulli_depth(q, energy, goutal_bump(x), true); },
                                        [](double) { return true; });
  std::printf("    max relative depth error %.3e, max |Q - q| %.2e\n", err, run.discharge_spread);
  EXPECT_LT(err, 0.01);
}

TEST(SteadyBump, TranscriticalFlowWithoutShockMatchesBernoulliWithin1Percent) {
  const double q = 1.53;
  // Goutal & Maurel impose h = 0.66 downstream while the outflow is subcritical; once the flow
  // has become supercritical there the boundary leaves the interior in control.
  const BumpRun run = run_bump(q, 0.66, false, 300.0);
  // Critical at the crest (z = 0.2): E = 3/2 hc + 0.2; subcritical upstream, supercritical after.
  const double energy = 1.5 * std::cbrt(q * q / g) + 0.2;
  const double err = max_relative_error(
      run, [&](double x) { return bernoulli_depth(q, energy, goutal_bump(x), x < 10.0); },
      [](double x) { return std::abs(x - 10.0) > 0.3; });  // the sonic point itself is singular
  std::printf("    max relative depth error %.3e, max |Q - q| %.2e\n", err, run.discharge_spread);
  EXPECT_LT(err, 0.01);
}

TEST(SteadyBump, TranscriticalFlowWithShockMatchesBernoulliAndRankineHugoniotAwayFromTheJump) {
  const double q = 0.18, h_out = 0.33;
  const BumpRun run = run_bump(q, h_out, false, 600.0);
  const double energy_up = 1.5 * std::cbrt(q * q / g) + 0.2;
  const double energy_down = q * q / (2.0 * g * h_out * h_out) + h_out;
  const auto super = [&](double x) { return bernoulli_depth(q, energy_up, goutal_bump(x), false); };
  const auto sub_down = [&](double x) { return bernoulli_depth(q, energy_down, goutal_bump(x), true); };
  // Jump where the momentum function q²/h + g h²/2 is equal on both branches (Rankine–Hugoniot
  // for a standing shock).
  const auto momentum = [&](double h) { return q * q / h + 0.5 * g * h * h; };
  const double x_jump = bisect([&](double x) { return momentum(super(x)) - momentum(sub_down(x)); }, 10.01, 11.99);
  const auto exact = [&](double x) {
    if (x < 10.0) return bernoulli_depth(q, energy_up, goutal_bump(x), true);
    return x < x_jump ? super(x) : sub_down(x);
  };
  const double err = max_relative_error(run, exact, [&](double x) {
    return std::abs(x - 10.0) > 0.3 && std::abs(x - x_jump) > 0.75;
  });
  std::printf("    jump at x = %.3f m; max relative depth error away from it %.3e, max |Q - q| %.2e\n",
              x_jump, err, run.discharge_spread);
  EXPECT_LT(err, 0.01);
}

// ---------------------------------------------------------------------------------------------
// MacDonald-type steady flow with Manning friction (MacDonald et al. 1997; Delestre et al. 2013,
// SWASHES §3.1): choose h(x), derive the bed from the steady momentum equation
//   z'(x) = −(1 − Q² T / (g A³)) h'(x) − n² Q|Q| / (A² R^{4/3}),
// integrate it (Simpson, fine grid), and check the solver returns to h(x).

TEST(SteadyFriction, MacDonaldSubcriticalProfileIsRecoveredWithinHalfPercent) {
  for (const Section section : {Section{10.0, 0.0}, Section{2.0, 1.5}}) {
    const double length = 1000.0, n = 0.033;
    const double discharge = section.is_rectangular() ? 20.0 : 6.0;
    const double hc = section.critical_depth(discharge, g);
    const auto h = [&](double x) { return 1.3 * hc * (1.0 + 0.5 * std::exp(-16.0 * std::pow(x / length - 0.5, 2))); };
    const auto dh = [&](double x) { return (h(x + 1e-4) - h(x - 1e-4)) / 2e-4; };
    const auto slope = [&](double x) {
      const double d = h(x), a = section.area(d), t = section.top_width(d);
      const double r = a / section.wetted_perimeter(d);
      return -(1.0 - discharge * discharge * t / (g * a * a * a)) * dh(x) -
             n * n * discharge * discharge / (a * a * std::pow(r, 4.0 / 3.0));
    };
    ReachSpec spec;
    spec.length = length;
    spec.cells = 200;
    spec.section = section;
    spec.manning_n = n;
    // Bed at cell centres: z(x) = −∫_x^L z'(s) ds with z(L) = 0, Simpson with 200 panels per cell.
    const double dx = length / spec.cells;
    for (int i = 0; i < spec.cells; ++i) {
      const double x = (i + 0.5) * dx;
      const int panels = 2 * static_cast<int>(std::ceil((length - x) / dx) * 100);
      const double step = (length - x) / panels;
      double integral = slope(x) + slope(length);
      for (int k = 1; k < panels; ++k) integral += (k % 2 ? 4.0 : 2.0) * slope(x + k * step);
      spec.bed_elevation.push_back(-integral * step / 3.0);
      spec.initial_depth.push_back(h(length));
      spec.initial_discharge.push_back(0.0);
    }
    // Start at the level of the downstream end over the whole reach, then let the flow establish.
    for (int i = 0; i < spec.cells; ++i) {
      auto j = static_cast<std::size_t>(i);
      spec.initial_depth[j] = std::max(h(length) + spec.bed_elevation.back() - spec.bed_elevation[j], h((i + 0.5) * dx));
      spec.initial_discharge[j] = discharge;
    }
    Canal canal;
    ASSERT_TRUE(canal.add_reach(spec));
    canal.set_boundary(0, End::upstream, FixedDischargeBoundary::constant(discharge));
    canal.set_boundary(0, End::downstream, FixedLevelBoundary::depth(h(length)));
    ASSERT_TRUE(canal.advance_to(3000.0));
    double worst = 0.0;
    for (int i = 0; i < spec.cells; ++i)
      worst = std::max(worst, std::abs(canal.reach(0).depth(i) - h((i + 0.5) * dx)) / h((i + 0.5) * dx));
    std::printf("    %s: max relative depth error %.3e\n", section.is_rectangular() ? "rectangular" : "trapezoidal", worst);
    EXPECT_LT(worst, 0.005);
  }
}

// ---------------------------------------------------------------------------------------------
// Closed channel: walls at both ends, random bed, random depths with dry cells, random discharge.
// Volume must stay constant to round-off and no depth may become negative.

TEST(ClosedChannel, RandomStatesWithDryCellsConserveVolumeAndStayNonNegative) {
  std::mt19937_64 rng(20261122);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 120; ++trial) {
    ReachSpec spec = rectangular_reach(10.0, 40);
    if (trial % 2) spec.section = {0.3, 1.0 + unit(rng)};
    for (int i = 0; i < spec.cells; ++i) {
      spec.bed_elevation.push_back(0.3 * unit(rng));
      const double h = unit(rng) < 0.3 ? 0.0 : unit(rng);
      spec.initial_depth.push_back(h);
      spec.initial_discharge.push_back(h > 0.0 ? (unit(rng) - 0.5) * spec.section.area(h) * 2.0 : 0.0);
    }
    Canal canal;
    ASSERT_TRUE(canal.add_reach(spec));
    canal.set_boundary(0, End::upstream, std::make_shared<WallBoundary>());
    canal.set_boundary(0, End::downstream, std::make_shared<WallBoundary>());
    const double v0 = canal.reach(0).volume();
    for (int s = 0; s < 30; ++s) {
      ASSERT_TRUE(canal.step()) << "trial " << trial << " step " << s;
      const auto& a = canal.reach(0).area();
      ASSERT_GE(*std::min_element(a.begin(), a.end()), 0.0) << "trial " << trial << " step " << s;
    }
    EXPECT_LT(std::abs(canal.reach(0).volume() - v0) / v0, 1e-12) << "trial " << trial;
  }
}

}  // namespace
}  // namespace canalsim::solver
