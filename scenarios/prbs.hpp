// Pseudo-random binary sequence (PRBS) inputs, as designed in the paper's Section 4.3.
//
// Generation (Section 4.3.1): an n-stage shift register with XOR feedback from the taps of a
// primitive polynomial runs through all 2^n - 1 non-zero states before repeating, so its output
// is a maximal-length sequence (m-sequence) of N = 2^n - 1 bits. We use the Fibonacci form:
// the register shifts right, the bit leaving stage 1 is the output, and the XOR of the tapped
// stages enters stage n. Taps for 2 to 20 stages are the standard table of primitive trinomials
// and pentanomials (e.g. x^9 + x^5 + 1 for the paper's n = 9; Xilinx XAPP052, or Wikipedia's
// "Linear-feedback shift register" table); a test checks every one has period 2^n - 1.
// The seed chooses the initial register (any non-zero state), so another seed gives a cyclic
// shift of the same m-sequence: a different realisation with the same maximal-length properties.
//
// Properties of an m-sequence (in +-1 form, bit 1 -> +1, bit 0 -> -1): one more 1 than 0 per
// period (balance), and the periodic autocorrelation R(0) = N, R(k) = -1 for 0 < k < N.
//
// Spectrum (Section 4.3.2): with clock period Tc, the power spectrum is a line spectrum at
// multiples of 1/(N Tc) under the envelope sinc^2(f Tc) = (sin(pi f Tc)/(pi f Tc))^2, which
// first vanishes at the clock frequency 1/Tc. Its -3 dB (half-power) bandwidth solves
// sinc^2(f Tc) = 1/2, f = 0.4429/Tc (computed numerically here); the paper's magnitude
// criterion |F| = max/sqrt(2) is the same point (5.58 rad/s read from its Figure 4; 5.566 rad/s
// for Tc = 0.5 s). The lowest excited frequency is 1/(N Tc), the period T = N Tc.
// The paper's design, n = 9 and Tc = 0.5 s, gives N = 511 and T = 255.5 s (the text prints
// 2555 s, a typo: 511 x 0.5 = 255.5). Its rule of thumb (eq. 18) f_c = 2.5 f_max relates the
// clock frequency to the highest frequency of interest.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "scenarios/signals.hpp"

namespace canalsim {

inline constexpr int prbs_min_stages = 2;
inline constexpr int prbs_max_stages = 20;

// Exponents of the primitive feedback polynomial for `stages` in [2, 20], highest first
// (x^9 + x^5 + 1 -> {9, 5}). Throws std::invalid_argument outside that range.
const std::vector<int>& maximal_length_taps(int stages);

// Fibonacci linear-feedback shift register with maximal-length taps.
class Lfsr {
 public:
  // `initial_state` must be non-zero and below 2^stages; throws std::invalid_argument otherwise.
  Lfsr(int stages, std::uint32_t initial_state);
  // Outputs the bit leaving stage 1 (0 or 1) and shifts the register once.
  int next();
  std::uint32_t state() const { return state_; }
  int stages() const { return stages_; }

 private:
  int stages_;
  std::uint32_t state_;
  std::uint32_t tap_mask_ = 0;  // bit (stages - t) set for each tap t
};

// Non-zero initial register derived from a seed (any value), spread over the 2^n - 1 states.
std::uint32_t initial_register_from_seed(int stages, std::uint64_t seed);

// One period (2^n - 1 bits, each 0 or 1) of the m-sequence from the seeded register.
std::vector<std::uint8_t> maximal_length_sequence(int stages, std::uint64_t seed);

// Design figures of a PRBS (paper Section 4.3). Frequencies in Hz; multiply by 2 pi for rad/s.
struct PrbsDesign {
  int stages = 0;
  std::size_t length = 0;            // N = 2^n - 1 bits
  double clock_period = 0.0;         // Tc [s]
  double period = 0.0;               // T = N Tc [s]
  double clock_frequency = 0.0;      // f_c = 1/Tc [Hz]
  double first_null = 0.0;           // first zero of the sinc^2 envelope, 1/Tc [Hz]
  double bandwidth_3db = 0.0;        // half-power point of the envelope [Hz]
  double lowest_frequency = 0.0;     // line spacing and lowest line, 1/(N Tc) [Hz]
  double max_frequency_of_interest = 0.0;  // f_c / 2.5, the paper's rule (18) [Hz]
};

// Throws std::invalid_argument for stages outside [2, 20] or clock_period <= 0.
PrbsDesign design_prbs(int stages, double clock_period);

// The x in (0, 1) with (sin(pi x)/(pi x))^2 = 1/2, by bisection (0.44295...).
double sinc_squared_half_power_point();

struct PrbsOptions {
  int stages = 9;               // n, range [2, 20]; N = 2^n - 1 bits
  double clock_period = 0.5;    // Tc [s], range (0, 3600]
  double amplitude = 0.005;     // [m], the signal is operating_point +- amplitude; finite
  double operating_point = 0.0; // [m]; the value before start_time; finite
  double start_time = 0.0;      // [s]; bit k covers [start + k Tc, start + (k+1) Tc); finite
  std::uint64_t seed = 1;       // chooses the initial register

  // Ok, or one line naming the field and its allowed range (core/status.hpp).
  [[nodiscard]] Status validate() const;
};

// operating_point + amplitude * (+1 for bit 1, -1 for bit 0), repeating with period N Tc.
class PrbsSignal final : public Signal {
 public:
  // Throws std::invalid_argument with validate()'s message when the options are invalid.
  explicit PrbsSignal(const PrbsOptions& options);
  double value(double t) const override;
  // The clock edges start + k Tc in (from, to] where the bit changes (the first edge, from the
  // operating point, when the first bit's level differs from it).
  std::vector<double> jumps(double from, double to) const override;

  const std::vector<std::uint8_t>& bits() const { return bits_; }
  PrbsDesign design() const { return design_prbs(options_.stages, options_.clock_period); }
  const PrbsOptions& options() const { return options_; }

 private:
  PrbsOptions options_;
  std::vector<std::uint8_t> bits_;
};

}  // namespace canalsim
