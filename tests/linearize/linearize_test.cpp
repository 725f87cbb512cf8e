// The linearisation (linearize/) against three truths it does not compute itself:
//  (a) the closed-form transfer function of a frictionless horizontal pool (Litrico & Fromion
//      2004; derived in docs/linearization.md §2);
//  (b) small-amplitude runs of the nonlinear simulator driven by sines (amplitude and phase of
//      the periodic response fitted by least squares);
//  (c) the static gain against two Newton steady states at neighbouring openings.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <functional>

#include "core/errors.hpp"
#include "linearize/linearize.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/scenario_toml.hpp"
#include "scenarios/simulate.hpp"
#include "solver/steady_state.hpp"
#include "testing/refusals.hpp"

namespace canalsim::linearize {
namespace {

using Complex = std::complex<double>;

double phase_error_degrees(Complex a, Complex b) { return std::abs(std::arg(a / b)) * 180.0 / M_PI; }

// --- (a) frictionless horizontal pool -----------------------------------------------------------

// A 10 m rectangular pool, 0.2 m wide, no friction, flat bed, 8 L/s imposed upstream, and a
// free weir downstream (crest 13.7 mm, C_w = 1.578 m^0.5/s): depth ≈ 0.1 m, V ≈ 0.4 m/s,
// C ≈ 0.99 m/s (Froude 0.40). The weir's linearised law q = κ a with κ = 1.5 Q/((h − p) B) ≈
// (C + V)/2 reflects about a quarter of an arriving wave, so the pool resonates, but mildly.
constexpr double kLength = 10.0, kWidth = 0.2, kInflow = 0.008, kCrest = 0.0137, kWeir = 1.578;
double pool_depth() { return kCrest + std::pow(kInflow / (kWeir * kWidth), 2.0 / 3.0); }

scenarios::Scenario frictionless_pool(double sensor_x, int cells) {
  const std::string toml = R"(
name = "frictionless"
[upstream]
kind = "discharge"
discharge_m3s = 0.008
[[pools]]
length_m = 10.0
bottom_width_m = 0.2
wall_height_m = 0.5
manning_n = 0.0
cells = )" + std::to_string(cells) + R"(
initial_depth_m = 0.1
[downstream]
kind = "weir"
weir_crest_m = 0.0137
weir_coefficient = 1.578
[sensors]
below_gate_sensor_x_m = )" + std::to_string(sensor_x) + R"(
[[experiments]]
name = "rest"
[experiments.input]
kind = "constant"
)";
  return scenarios::parse_scenario(toml, "frictionless.toml");
}

// Depth at x per unit upstream discharge (docs/linearization.md §2): modes e^{λ1 x}, e^{λ2 x}
// with λ1 = s/(C − V), λ2 = −s/(C + V), a = −(λ1 α e^{λ1 x} + λ2 β e^{λ2 x})/s; q(0) = 1 and the
// weir's q(L) = κ a(L).
Complex closed_form_depth(double omega, double x) {
  const double h = pool_depth(), g = 9.81, c = std::sqrt(g * h), v = kInflow / (kWidth * h);
  const double kappa = 1.5 * kInflow / ((h - kCrest) * kWidth);
  const Complex s(0.0, omega);
  const Complex l1 = s / (c - v), l2 = -s / (c + v);
  const Complex r = -std::exp((l2 - l1) * kLength) * (1.0 - kappa / (c + v)) / (1.0 + kappa / (c - v));
  const Complex beta = 1.0 / (1.0 + r), alpha = r * beta;
  return -(alpha * std::exp(l1 * x) / (c - v) - beta * std::exp(l2 * x) / (c + v)) / kWidth;
}

struct Errors {
  double gain = 0.0;   // worst |(|G| / |G_exact|) − 1|
  double phase = 0.0;  // worst phase difference [deg]
};

Errors closed_form_errors(int cells, double x, const std::vector<double>& omega, double* nyquist) {
  const scenarios::Scenario s = frictionless_pool(x, cells);
  const StateSpace sys = linearize_system(s, s.experiments.front(), {InputKind::inflow, 0}, {OutputKind::y_dw, 0});
  *nyquist = sys.nyquist;
  const auto g = frequency_response(sys, omega);
  Errors e;
  for (std::size_t k = 0; k < omega.size(); ++k) {
    const Complex exact = closed_form_depth(omega[k], x);
    e.gain = std::max(e.gain, std::abs(std::abs(g[k]) / std::abs(exact) - 1.0));
    e.phase = std::max(e.phase, phase_error_degrees(g[k], exact));
  }
  return e;
}

// Up to the frequency where the slower (upstream-running) wave has 100 cells per wavelength —
// 1.48 rad/s on 400 cells, the first 9 resonances of the pool.
TEST(FrictionlessPool, MatchesTheClosedFormUpToTheResolvedFrequency) {
  const int cells = 400;
  const double dx = kLength / cells, h = pool_depth(), c = std::sqrt(9.81 * h), v = kInflow / (kWidth * h);
  const double resolved = 2.0 * M_PI * (c - v) / (100.0 * dx);
  for (const double x : {0.5 * dx, 0.5 * dx + 200 * dx}) {  // cell centres at the upstream end and mid-pool
    double nyquist = 0.0;
    const Errors e = closed_form_errors(cells, x, log_grid({0.01, resolved, 150}), &nyquist);
    EXPECT_NEAR(nyquist, M_PI * (c - v) / dx, 1e-3 * nyquist);
    EXPECT_LT(e.gain, 0.01) << "x = " << x << " m, up to " << resolved << " rad/s";
    EXPECT_LT(e.phase, 1.0) << "x = " << x << " m, up to " << resolved << " rad/s";
  }
}

// Beyond that the difference is the discretisation's, and it falls as the grid is refined
// (second order: about 4 times per halving of dx).
TEST(FrictionlessPool, ConvergesToTheClosedFormUnderRefinement) {
  const std::vector<double> omega = log_grid({1.5, 3.0, 40});
  double nyquist = 0.0;
  const Errors coarse = closed_form_errors(400, 0.0125, omega, &nyquist);
  const Errors fine = closed_form_errors(800, 0.0125, omega, &nyquist);
  EXPECT_GT(coarse.gain / fine.gain, 3.0) << coarse.gain << " -> " << fine.gain;
  EXPECT_GT(coarse.phase / fine.phase, 3.0) << coarse.phase << " -> " << fine.phase;
}

// --- (b) small-amplitude nonlinear runs ---------------------------------------------------------

// Amplitude and phase of the sine at ω in a channel of a recording, in metres: least squares on
// [1, sin, cos] over [settle, settle + fitted) (normal equations, 3 x 3); the phasor b + i·c of
// b sin ωt + c cos ωt.
Complex sine_phasor_m(const Recording& rec, const std::string& channel, double omega, double settle, double fitted) {
  const auto& time = rec.column("t_s");
  const auto& y = rec.column(channel);
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < time.size(); ++k) {
    if (time[k] < settle || time[k] >= settle + fitted - 1e-9) continue;
    const Eigen::Vector3d basis(1.0, std::sin(omega * time[k]), std::cos(omega * time[k]));
    m += basis * basis.transpose();
    rhs += basis * y[k] * 1e-3;
  }
  const Eigen::Vector3d coefficients = m.ldlt().solve(rhs);
  return Complex(coefficients(1), coefficients(2));
}

// Response of the simulator's y_dwe (no quantisation, no noise) to u = u_op + a sin ωt, fitted
// over whole periods after the transient: y ≈ y0 + a (Re G sin ωt + Im G cos ωt).
Complex simulated_response(const scenarios::Scenario& lab, const scenarios::ExperimentSpec& op, double omega,
                           double amplitude_m) {
  scenarios::ExperimentSpec e = op;
  const double period = 2.0 * M_PI / omega;
  const double settle = 60.0, fitted = period * std::ceil(30.0 / period);
  e.duration_s = settle + fitted;
  scenarios::SensorSpec sensors = lab.sensors;
  sensors.period_s = 0.02;
  sensors.resolution_mm = 0.0;
  sensors.noise_std_mm = 0.0;
  e.sensors = sensors;
  // The command, sampled every 2 ms at the middle of each hold interval (a zero-order hold then
  // delays it by nothing to first order).
  Recording drive;
  const double hold = 0.002;
  std::vector<double> t, u;
  for (double time = 0.0; time <= e.duration_s + hold; time += hold) {
    t.push_back(time);
    u.push_back(op.operating_opening_mm + amplitude_m * 1e3 * std::sin(omega * (time + 0.5 * hold)));
  }
  drive.set_column("t_s", t);
  drive.set_column("u_mm", u);
  drive.set_meta("operating_opening_mm", std::to_string(op.operating_opening_mm));
  scenarios::SimulateOptions options;
  options.drive.recording = &drive;
  const Recording rec = scenarios::simulate(lab, e, options);
  return sine_phasor_m(rec, "y_dwe_mm", omega, settle, fitted) / amplitude_m;
}

TEST(LabCanal, MatchesSmallAmplitudeSineRunsOfTheNonlinearModel) {
  const scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  const scenarios::ExperimentSpec& op = *lab.find_experiment("op2");
  const StateSpace sys = linearize_system(lab, op, {InputKind::gate, 0}, {OutputKind::y_dwe, 0});
  const std::vector<double> omega = {0.1, 0.5, 2.0};
  const auto g = frequency_response(sys, omega);
  for (std::size_t k = 0; k < omega.size(); ++k) {
    const Complex simulated = simulated_response(lab, op, omega[k], 1e-4);  // ±0.1 mm
    EXPECT_NEAR(std::abs(g[k]) / std::abs(simulated), 1.0, 0.02) << "omega = " << omega[k];
    EXPECT_LT(phase_error_degrees(g[k], simulated), 2.0) << "omega = " << omega[k];
  }
}

// The pump's own lag adds a state: with a 2 s lag the reservoir's loop rings, and the linearised
// model must follow the nonlinear one where the lag moves the response.
TEST(LabCanal, WithALaggedPumpMatchesSmallAmplitudeSineRunsOfTheNonlinearModel) {
  scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  lab.upstream.pump_lag_s = 2.0;
  const scenarios::ExperimentSpec& op = *lab.find_experiment("op2");
  const StateSpace sys = linearize_system(lab, op, {InputKind::gate, 0}, {OutputKind::y_dwe, 0});
  const std::vector<double> omega = {0.1, 0.5};
  const auto g = frequency_response(sys, omega);
  const auto ideal = frequency_response(linearize_system(scenarios::builtin_scenario("lab"), op, {InputKind::gate, 0},
                                                         {OutputKind::y_dwe, 0}), omega);
  for (std::size_t k = 0; k < omega.size(); ++k) {
    const Complex simulated = simulated_response(lab, op, omega[k], 1e-4);  // ±0.1 mm
    EXPECT_NEAR(std::abs(g[k]) / std::abs(simulated), 1.0, 0.02) << "omega = " << omega[k];
    EXPECT_LT(phase_error_degrees(g[k], simulated), 2.0) << "omega = " << omega[k];
    std::printf("omega %.1f: lagged %.5f / %.2f deg, simulated %.5f / %.2f deg, ideal pump %.5f / %.2f deg\n", omega[k],
                std::abs(g[k]), std::arg(g[k]) * 180 / M_PI, std::abs(simulated), std::arg(simulated) * 180 / M_PI,
                std::abs(ideal[k]), std::arg(ideal[k]) * 180 / M_PI);
  }
  // The lag must matter where it is tested, or the comparison proves nothing about its rows.
  EXPECT_GT(std::abs(g[1] - ideal[1]) / std::abs(ideal[1]), 0.05);  // 0.5 rad/s, near the loop's own
}

// --- (c) static gain -------------------------------------------------------------------------------

double steady_end_depth(const scenarios::Scenario& s, scenarios::ExperimentSpec e, double opening_mm) {
  e.operating_opening_mm = opening_mm;
  e.input.kind = scenarios::InputKind::constant;
  scenarios::BuiltCanal b = scenarios::build_canal(s, e);
  b.canal.set_time(0.0);
  solver::SteadyStateOptions options;
  options.depth_tolerance = 1e-12;
  EXPECT_TRUE(solver::solve_steady_state(b.canal, options).status);
  const solver::Reach& last = b.canal.reach(b.canal.reach_count() - 1);
  return b.canal.sample(b.canal.reach_count() - 1, last.length() - 0.5 * last.cell_length(), solver::Quantity::depth);
}

TEST(LabCanal, StaticGainMatchesNeighbouringSteadyStates) {
  const scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  for (const char* name : {"op1", "op2", "op4"}) {
    const scenarios::ExperimentSpec& op = *lab.find_experiment(name);
    const double gain = static_gain(linearize_system(lab, op, {InputKind::gate, 0}, {OutputKind::y_dwe, 0}));
    const double delta_mm = 0.2;
    const double difference = (steady_end_depth(lab, op, op.operating_opening_mm + delta_mm) -
                               steady_end_depth(lab, op, op.operating_opening_mm - delta_mm)) /
                              (2.0 * delta_mm * 1e-3);
    EXPECT_NEAR(gain / difference, 1.0, 1e-3) << name << ": linearised " << gain << ", Newton " << difference;
  }
}

// --- bad input -------------------------------------------------------------------------------------

TEST(Choices, BadInputsNameTheFlagAndWhatIsAllowed) {
  EXPECT_THROW(parse_grid("0:1:10", "--freq"), InputError);
  EXPECT_THROW(parse_grid("1:2:0", "--freq"), InputError);
  EXPECT_THROW(parse_grid("2:1:10", "--freq"), InputError);
  EXPECT_THROW(parse_input("valve", "--input"), InputError);
  EXPECT_THROW(parse_output("y_check0", "--output"), InputError);
  const scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  EXPECT_TRUE(testing::refuses_input(
      [&] { (void)linearize_system(lab, lab.experiments.front(), {InputKind::inflow, 0}, {OutputKind::y_dwe, 0}); },
      "--input inflow"));
  LinearizeOptions options;
  options.grid = {1.0, 1e4, 10};
  EXPECT_TRUE(options.validate());
  EXPECT_THROW(linearize(lab, lab.experiments.front(), options), InputError);  // beyond Nyquist
  options.grid = {0.0, 1.0, 10};
  EXPECT_EQ(options.validate().field(), "grid.low");
  options.grid = {};
  options.poles = 51;
  EXPECT_EQ(options.validate().message(), "poles = 51: expected an integer in [0, 50]");
}

}  // namespace
}  // namespace canalsim::linearize

namespace canalsim::linearize {
namespace {

// The band fit recovers a known fractional model (G = K e^{−iωL}/(T (iω)^λ + 1)) exactly.
TEST(FractionalFit, RecoversAKnownFractionalModel) {
  const Band band = prbs_band(9, 0.5);
  EXPECT_NEAR(band.low, 2.0 * M_PI / 255.5, 1e-12);
  EXPECT_NEAR(band.high, 2.0 * M_PI * 0.443 / 0.5, 1e-12);
  const std::vector<double> omega = log_grid({band.low, band.high, 60});
  for (const double lambda : {0.45, 0.8, 1.0}) {
    std::vector<std::complex<double>> g;
    for (double w : omega) {
      const auto s_lambda = std::pow(w, lambda) * std::exp(std::complex<double>(0.0, lambda * M_PI / 2.0));
      g.push_back(0.5 * std::exp(std::complex<double>(0.0, -w * 4.0)) / (2.0 * s_lambda + 1.0));
    }
    const FractionalFit f = fit_fractional_order(omega, g, band, 4.5);
    EXPECT_NEAR(f.order, lambda, 1e-3);
    EXPECT_NEAR(f.gain, 0.5, 1e-3);
    EXPECT_NEAR(f.time, 2.0, 1e-2);
    EXPECT_NEAR(f.delay, 4.0, 1e-3);
    EXPECT_LT(f.rms_relative_error, 1e-4);
    if (lambda < 0.9) {
      EXPECT_GT(f.integer_rms_relative_error, 10.0 * f.rms_relative_error + 1e-3);
    }
  }
}

}  // namespace
}  // namespace canalsim::linearize

namespace canalsim::linearize {
namespace {

// Eight pools, gates between them, orifice offtakes, an end pump: the static gains of the
// head inflow and of an offtake on a check depth against Newton steady states of the built
// canal with the inflow (or the offtake's setting) moved by ±1 %.
double steady_check_depth(const scenarios::Scenario& s, const std::function<void(scenarios::BuiltCanal&)>& change,
                          int pool) {
  scenarios::ExperimentSpec e = s.experiments.front();
  e.input.kind = scenarios::InputKind::constant;
  e.events.clear();
  scenarios::BuiltCanal b = scenarios::build_canal(s, e);
  change(b);
  b.canal.set_time(0.0);
  solver::SteadyStateOptions options;
  options.depth_tolerance = 1e-12;
  EXPECT_TRUE(solver::solve_steady_state(b.canal, options).status);
  return b.check_depth(pool);
}

TEST(AsceCanal2, StaticGainsMatchNeighbouringSteadyStates) {
  const scenarios::Scenario s = scenarios::builtin_scenario("asce2");
  const scenarios::ExperimentSpec& e = *s.find_experiment("steady");
  {
    const double q = s.upstream.discharge_m3s, dq = 0.01 * q;
    const double gain = static_gain(linearize_system(s, e, {InputKind::inflow, 0}, {OutputKind::y_check, 8}));
    const double difference = (steady_check_depth(s, [&](scenarios::BuiltCanal& b) { *b.head_inflow = q + dq; }, 7) -
                               steady_check_depth(s, [&](scenarios::BuiltCanal& b) { *b.head_inflow = q - dq; }, 7)) /
                              (2.0 * dq);
    EXPECT_NEAR(gain / difference, 1.0, 1e-3) << "inflow -> y_check8: " << gain << " vs " << difference;
  }
  {
    // Offtake 3 (pool 3's orifice): its setting as the discharge it passes at design.
    const auto& o = s.pools[2].offtakes.front();
    const double q = o.discharge_m3s, dq = 0.01 * q;
    auto set = [&](double value) {
      return [value](scenarios::BuiltCanal& b) {
        scenarios::EventSpec event;
        event.pool = 3;
        event.offtake = 1;
        event.offtake_m3s = value;
        scenarios::apply_event(b, event);
      };
    };
    const double gain = static_gain(linearize_system(s, e, {InputKind::offtake, 3}, {OutputKind::y_check, 3}));
    const double difference = (steady_check_depth(s, set(q + dq), 2) - steady_check_depth(s, set(q - dq), 2)) / (2.0 * dq);
    EXPECT_NEAR(gain / difference, 1.0, 1e-3) << "offtake 3 -> y_check3: " << gain << " vs " << difference;
  }
}

}  // namespace
}  // namespace canalsim::linearize

namespace canalsim::linearize {
namespace {

// On the frictionless pool every limiter slope sits on its kink (a flat steady state): the
// nonlinear scheme's small-amplitude response there is what the centred-kink rule has to match.
// The inflow follows Q + a sin ωt through events every 10 ms (each holding the mid-interval value).
TEST(FrictionlessPool, TheCentredKinkRuleMatchesTheNonlinearSchemeAtAFlatState) {
  const int cells = 400;
  const double x = 0.5 * kLength / cells + 200 * kLength / cells;
  scenarios::Scenario s = frictionless_pool(x, cells);
  const StateSpace sys = linearize_system(s, s.experiments.front(), {InputKind::inflow, 0}, {OutputKind::y_dw, 0});
  for (const double omega : {0.2, 0.8}) {
    scenarios::ExperimentSpec e = s.experiments.front();
    const double amplitude = 0.01 * kInflow, hold = 0.01, period = 2.0 * M_PI / omega;
    const double settle = 150.0, fitted = period * std::ceil(40.0 / period);
    e.duration_s = settle + fitted;
    for (double t = 0.0; t < e.duration_s; t += hold) {
      scenarios::EventSpec event;
      event.t_s = t;
      event.inflow_m3s = kInflow + amplitude * std::sin(omega * (t + 0.5 * hold));
      e.events.push_back(event);
    }
    scenarios::SensorSpec sensors = s.sensors;
    sensors.period_s = 0.02;
    sensors.resolution_mm = 0.0;
    e.sensors = sensors;
    const Recording rec = scenarios::simulate(s, e);
    const Complex simulated = sine_phasor_m(rec, "y_dw_mm", omega, settle, fitted) / amplitude;
    const Complex linear = frequency_response(sys, {omega}).front();
    EXPECT_NEAR(std::abs(linear) / std::abs(simulated), 1.0, 0.02) << "omega " << omega << ": " << linear << " vs " << simulated;
    EXPECT_LT(phase_error_degrees(linear, simulated), 2.0) << "omega " << omega << ": " << linear << " vs " << simulated;
  }
}

}  // namespace
}  // namespace canalsim::linearize

namespace canalsim::linearize {
namespace {

// With the generalised minmod limiter the lab pool's nearly linear level profile puts most
// slopes on minmod's switch between d₋ and d₊ (a kink): a one-sided finite difference there gave
// a static gain of 0.207 where the steady states give 0.524; the centred-kink rule gives it back.
TEST(LabCanal, StaticGainWithTheMinmodLimiterMatchesNeighbouringSteadyStates) {
  scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  lab.numerics.van_leer_limiter = false;
  const scenarios::ExperimentSpec& op = *lab.find_experiment("op2");
  const double gain = static_gain(linearize_system(lab, op, {InputKind::gate, 0}, {OutputKind::y_dwe, 0}));
  const double difference = (steady_end_depth(lab, op, op.operating_opening_mm + 0.2) -
                             steady_end_depth(lab, op, op.operating_opening_mm - 0.2)) / 0.4e-3;
  EXPECT_NEAR(gain / difference, 1.0, 1e-3) << "linearised " << gain << ", Newton " << difference;
}

// On 400 cells Newton stalls at minmod's kinks (docs/numerics.md): the operating point is then
// the stall, accepted as an experiment's start is, rather than a failure ("no steady state at the
// operating point"). Measured: gain 0.523904 against van
// Leer's 0.523833 on the same grid (the two limiters differ by O(dx²) in smooth flow).
TEST(LabCanal, LinearisesMinmodOnAFineGridAtItsStalledSteadyState) {
  scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  lab.pools.front().cells = 400;
  lab.numerics.van_leer_limiter = false;
  const scenarios::ExperimentSpec& op = *lab.find_experiment("op2");
  std::string note;
  const double minmod = static_gain(linearize_system(lab, op, {InputKind::gate, 0}, {OutputKind::y_dwe, 0}, &note));
  EXPECT_NE(note.find("stalled"), std::string::npos) << note;
  lab.numerics.van_leer_limiter = true;
  const double van_leer = static_gain(linearize_system(lab, op, {InputKind::gate, 0}, {OutputKind::y_dwe, 0}));
  EXPECT_NEAR(minmod / van_leer, 1.0, 2e-3) << "minmod " << minmod << ", van Leer " << van_leer;
}

}  // namespace
}  // namespace canalsim::linearize
