// The linearised Saint-Venant canal in the frequency domain (docs/linearization.md).
//
// At an experiment's steady state U* (the Newton solve of solver/steady_state.hpp) the
// discretised equations dU/dt = L(U, u) — cells, boundaries, structures, the reservoir's level
// and PID states — are linearised into
//
//   dx/dt = A x + B u,     y = C x + D u,        G(s) = C (sI − A)⁻¹ B + D,
//
// A = ∂L/∂U by coloured finite differences of the scheme (solver/rates_jacobian.hpp), B = ∂L/∂u
// for one input (the controlled gate's opening, the head inflow or an offtake), C and D for one
// output (a level sensor with its position and interpolation, the gate discharge, a check
// depth). The frequency response costs one complex sparse LU per frequency.
//
//   const Scenario lab = scenarios::builtin_scenario("lab");
//   LinearizeOptions options;                        // gate → y_dwe, default grid
//   const FrequencyResponse r = linearize(lab, *lab.find_experiment("op2"), options);
//   r.response[k], r.static_gain, r.poles, r.delay_s
#pragma once

#include <complex>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Sparse>

#include "core/status.hpp"
#include "linearize/fractional_fit.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::linearize {

enum class InputKind { gate, inflow, offtake };
struct InputChoice {
  InputKind kind = InputKind::gate;
  int offtake = 0;  // offtake: 1-based, counted over the pools in order
};

enum class OutputKind { y_dwe, y_dw, q, y_check };
struct OutputChoice {
  OutputKind kind = OutputKind::y_dwe;
  int check = 0;  // y_check: 1-based pool
};

// Parses "gate", "inflow", "offtake:I" / "y_dwe", "y_dw", "q", "y_checkI"; throws InputError
// naming `flag` and the allowed values.
InputChoice parse_input(const std::string& text, const std::string& flag);
OutputChoice parse_output(const std::string& text, const std::string& flag);
std::string to_string(const InputChoice& input);
std::string to_string(const OutputChoice& output);

// Log-spaced angular frequencies [rad/s]; count = 0 means the default grid (1e-4 to 0.5 of the
// grid's Nyquist frequency, 200 points).
struct FrequencyGrid {
  double low = 0.0;
  double high = 0.0;
  int count = 0;
};
// Parses "LO:HI:N" (rad/s); throws InputError naming `flag`.
FrequencyGrid parse_grid(const std::string& text, const std::string& flag);

// x' = A x + B u, y = C x + D u about the steady state. States: the canal's A and Q per cell
// (solver/rates_jacobian.hpp layout), then the reservoir's volume and PID integral when the head
// gate is fed by a reservoir. Input in m (gate) or m³/s; output in m or m³/s.
struct StateSpace {
  Eigen::SparseMatrix<double> A;
  Eigen::VectorXd B;
  Eigen::RowVectorXd C;
  double D = 0.0;
  double output_delay_s = 0.0;  // the level sensors' pure delay (scenario sensors.delay_s)
  int canal_unknowns = 0;
  // π min (c − |u|) / dx over the cells [rad/s]: the highest frequency whose slowest wave the
  // grid samples twice per wavelength.
  double nyquist = 0.0;
};

struct LinearizeOptions {
  InputChoice input;
  OutputChoice output;
  FrequencyGrid grid;
  int poles = 6;  // how many poles nearest the imaginary axis to report, [0, 50]
  // The grid (count 0: the default; else 0 < low <= high, 1 <= count <= 100000, low = high for
  // one point) and poles (core/status.hpp convention). The Nyquist limit is checked by linearize().
  Status validate() const;
};

struct FrequencyResponse {
  StateSpace system;
  std::string input_name, output_name, input_unit, output_unit;
  std::vector<double> omega;                       // [rad/s]
  std::vector<std::complex<double>> response;      // G(iω) [output unit per input unit]
  double static_gain = 0.0;                        // G(0); ±inf for an integrating system
  std::vector<std::complex<double>> poles;         // nearest the imaginary axis first [1/s]
  double delay_s = 0.0;                            // from the phase (delay_from_phase)
  std::string steady_state;                        // how the operating point was found
  // For an experiment driven by a PRBS: its band (prbs_band) and the LFOM fitted to G there
  // (fit_fractional_order, on 200 log-spaced frequencies of the band below the Nyquist frequency).
  std::optional<Band> band;
  std::optional<FractionalFit> band_fit;
};

// Builds the state-space model of `experiment`'s operating point (its input held at the
// operating opening). Throws InputError when the input or output does not exist in the scenario
// or the steady state is not found.
StateSpace linearize_system(const scenarios::Scenario& scenario, const scenarios::ExperimentSpec& experiment,
                            const InputChoice& input, const OutputChoice& output, std::string* steady_note = nullptr);

// G(iω_k) with one sparse complex LU per frequency (the pattern analysed once).
std::vector<std::complex<double>> frequency_response(const StateSpace& system, const std::vector<double>& omega);
// G(0) = D − C A⁻¹ B; ±infinity (sign of the low-frequency gain) when A is singular.
double static_gain(const StateSpace& system);
// The `count` eigenvalues of A with the largest real part (nearest the imaginary axis; dense
// eigen-solve, up to 3000 states).
std::vector<std::complex<double>> dominant_poles(const StateSpace& system, int count);
// The delay read from the phase: τ = −Δφ/Δω over the upper half (in log ω) of the grid, with the
// phase unwrapped — the slope the rational part of G leaves to a pure delay at high frequency.
double delay_from_phase(const std::vector<double>& omega, const std::vector<std::complex<double>>& response);

std::vector<double> log_grid(const FrequencyGrid& grid);

// The phase of G along the grid [deg], unwrapped: continuous through ±180°, so that a delay's
// phase falls without bound as it does.
std::vector<double> unwrapped_phase_degrees(const std::vector<std::complex<double>>& response);

// Everything `canalsim linearize` prints: the system, its response on the grid (validated
// against the Nyquist frequency), static gain, poles and delay.
FrequencyResponse linearize(const scenarios::Scenario& scenario, const scenarios::ExperimentSpec& experiment,
                            const LinearizeOptions& options);

}  // namespace canalsim::linearize
