#include "scenarios/prbs.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace canalsim {
namespace {

// Primitive polynomials x^n + ... + 1 (exponents other than 0), n = 2..20.
const std::array<std::vector<int>, prbs_max_stages + 1> primitive_taps = {{
    {},
    {},
    {2, 1},
    {3, 2},
    {4, 3},
    {5, 3},
    {6, 5},
    {7, 6},
    {8, 6, 5, 4},
    {9, 5},
    {10, 7},
    {11, 9},
    {12, 11, 10, 4},
    {13, 12, 11, 8},
    {14, 13, 12, 2},
    {15, 14},
    {16, 15, 13, 4},
    {17, 14},
    {18, 11},
    {19, 18, 17, 14},
    {20, 17},
}};

void check_stages(int stages) {
  if (stages < prbs_min_stages || stages > prbs_max_stages) {
    throw std::invalid_argument("stages: expected an integer in [2, 20], got " +
                                std::to_string(stages));
  }
}

// SplitMix64 (Steele, Lea & Flood 2014): a well-mixed 64-bit hash of the seed.
std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

double sinc_squared(double x) {
  if (x == 0.0) return 1.0;
  const double s = std::sin(std::numbers::pi * x) / (std::numbers::pi * x);
  return s * s;
}

}  // namespace

const std::vector<int>& maximal_length_taps(int stages) {
  check_stages(stages);
  return primitive_taps[static_cast<std::size_t>(stages)];
}

Lfsr::Lfsr(int stages, std::uint32_t initial_state) : stages_(stages), state_(initial_state) {
  for (int tap : maximal_length_taps(stages)) tap_mask_ |= 1u << (stages - tap);
  if (initial_state == 0 || initial_state >= (1u << stages)) {
    throw std::invalid_argument("LFSR: initial state must be in [1, 2^stages - 1]");
  }
}

int Lfsr::next() {
  const int out = static_cast<int>(state_ & 1u);
  // Parity of the tapped stages enters stage n.
  const std::uint32_t feedback = static_cast<std::uint32_t>(std::popcount(state_ & tap_mask_) & 1);
  state_ = (state_ >> 1) | (feedback << (stages_ - 1));
  return out;
}

std::uint32_t initial_register_from_seed(int stages, std::uint64_t seed) {
  check_stages(stages);
  const std::uint64_t states = (std::uint64_t{1} << stages) - 1;  // non-zero states
  return static_cast<std::uint32_t>(1 + splitmix64(seed) % states);
}

std::vector<std::uint8_t> maximal_length_sequence(int stages, std::uint64_t seed) {
  Lfsr lfsr(stages, initial_register_from_seed(stages, seed));
  std::vector<std::uint8_t> bits((std::size_t{1} << stages) - 1);
  for (auto& bit : bits) bit = static_cast<std::uint8_t>(lfsr.next());
  return bits;
}

double sinc_squared_half_power_point() {
  double lo = 0.0, hi = 1.0;  // sinc^2 falls monotonically from 1 to 0 on [0, 1]
  for (int i = 0; i < 200 && hi - lo > 1e-16; ++i) {
    const double mid = 0.5 * (lo + hi);
    (sinc_squared(mid) > 0.5 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

PrbsDesign design_prbs(int stages, double clock_period) {
  check_stages(stages);
  if (!(clock_period > 0.0) || !std::isfinite(clock_period)) {
    throw std::invalid_argument("clock_period: expected a value > 0 s");
  }
  PrbsDesign d;
  d.stages = stages;
  d.length = (std::size_t{1} << stages) - 1;
  d.clock_period = clock_period;
  d.period = static_cast<double>(d.length) * clock_period;
  d.clock_frequency = 1.0 / clock_period;
  d.first_null = 1.0 / clock_period;
  d.bandwidth_3db = sinc_squared_half_power_point() / clock_period;
  d.lowest_frequency = 1.0 / d.period;
  d.max_frequency_of_interest = d.clock_frequency / 2.5;
  return d;
}

Status PrbsOptions::validate() const {
  return Validator()
      .require(stages >= prbs_min_stages && stages <= prbs_max_stages, "stages", stages, "an integer in [2, 20]")
      .require(std::isfinite(clock_period) && clock_period > 0.0 && clock_period <= 3600.0, "clock_period",
               clock_period, "a value in (0, 3600] s")
      .require(std::isfinite(amplitude), "amplitude", amplitude, "a finite value")
      .require(std::isfinite(operating_point), "operating_point", operating_point, "a finite value")
      .require(std::isfinite(start_time), "start_time", start_time, "a finite value")
      .status();
}

PrbsSignal::PrbsSignal(const PrbsOptions& options) : options_(options) {
  if (const Status status = options.validate(); !status) throw std::invalid_argument("PRBS: " + status.message());
  bits_ = maximal_length_sequence(options.stages, options.seed);
}

double PrbsSignal::value(double t) const {
  if (t < options_.start_time) return options_.operating_point;
  // The simulator's sample times (multiples of 0.13 s, say) land on clock edges only up to
  // round-off; a billionth of a clock period of slack keeps an edge sample on the new bit.
  const double clocks = (t - options_.start_time) / options_.clock_period + 1e-9;
  const auto k = static_cast<std::uint64_t>(std::floor(clocks)) % bits_.size();
  return options_.operating_point + (bits_[k] ? options_.amplitude : -options_.amplitude);
}

std::vector<double> PrbsSignal::jumps(double from, double to) const {
  std::vector<double> out;
  const double tc = options_.clock_period;
  // The first edge at or after `from` (floor, not ceil: `from` itself is excluded below).
  const double first = std::max(0.0, std::floor((from - options_.start_time) / tc));
  for (auto k = static_cast<std::uint64_t>(first);; ++k) {
    const double edge = options_.start_time + static_cast<double>(k) * tc;
    if (edge > to) break;
    if (edge <= from) continue;
    const double before = k == 0 ? options_.operating_point : value(edge - 0.5 * tc);
    if (value(edge) != before) out.push_back(edge);
  }
  return out;
}

}  // namespace canalsim
