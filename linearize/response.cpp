// The frequency response, static gain, poles and delay of a StateSpace (linearize.hpp), the
// frequency grid and the parsing of the command's choices.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdlib>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseLU>

#include "core/errors.hpp"
#include "core/format.hpp"
#include "linearize/klu_complex.hpp"
#include "linearize/linearize.hpp"

namespace canalsim::linearize {
namespace {

using Complex = std::complex<double>;

// Strict whole-string number parsing (no trailing characters).
bool parse_number(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(*value);
}

bool parse_positive_int(const std::string& text, int* value) {
  if (text.empty() || text.size() > 9 || !std::all_of(text.begin(), text.end(), ::isdigit)) return false;
  *value = std::atoi(text.c_str());
  return *value > 0;
}

}  // namespace

InputChoice parse_input(const std::string& text, const std::string& flag) {
  if (text == "gate") return {InputKind::gate, 0};
  if (text == "inflow") return {InputKind::inflow, 0};
  int index = 0;
  if (text.rfind("offtake:", 0) == 0 && parse_positive_int(text.substr(8), &index)) return {InputKind::offtake, index};
  throw InputError(flag + " = '" + text + "': expected gate, inflow or offtake:I (I = 1, 2, ...)");
}

OutputChoice parse_output(const std::string& text, const std::string& flag) {
  if (text == "y_dwe") return {OutputKind::y_dwe, 0};
  if (text == "y_dw") return {OutputKind::y_dw, 0};
  if (text == "q") return {OutputKind::q, 0};
  int index = 0;
  if (text.rfind("y_check", 0) == 0 && parse_positive_int(text.substr(7), &index)) return {OutputKind::y_check, index};
  throw InputError(flag + " = '" + text + "': expected y_dwe, y_dw, q or y_checkI (I = 1, 2, ...)");
}

std::string to_string(const InputChoice& in) {
  switch (in.kind) {
    case InputKind::gate: return "gate";
    case InputKind::inflow: return "inflow";
    case InputKind::offtake: return "offtake:" + std::to_string(in.offtake);
  }
  return "?";
}

std::string to_string(const OutputChoice& out) {
  switch (out.kind) {
    case OutputKind::y_dwe: return "y_dwe";
    case OutputKind::y_dw: return "y_dw";
    case OutputKind::q: return "q";
    case OutputKind::y_check: return "y_check" + std::to_string(out.check);
  }
  return "?";
}

FrequencyGrid parse_grid(const std::string& text, const std::string& flag) {
  const auto first = text.find(':'), second = text.find(':', first == std::string::npos ? 0 : first + 1);
  FrequencyGrid g;
  const auto bad = [&](const std::string& why) {
    return InputError(flag + " = '" + text + "': " + why + "; expected LO:HI:N with 0 < LO <= HI [rad/s] and N >= 1");
  };
  if (first == std::string::npos || second == std::string::npos) throw bad("not of the form LO:HI:N");
  if (!parse_number(text.substr(0, first), &g.low) || !parse_number(text.substr(first + 1, second - first - 1), &g.high)) {
    throw bad("LO and HI must be numbers");
  }
  const std::string count = text.substr(second + 1);
  if (!parse_positive_int(count, &g.count)) throw bad("N must be a whole number >= 1 (the grid is empty)");
  if (!(g.low > 0.0) || !(g.high > 0.0)) throw bad("the frequencies must be positive");
  if (g.high < g.low) throw bad("HI is below LO");
  if (g.count > 100000) throw bad("N is above 100000");
  if (g.count == 1 && g.high != g.low) throw bad("one point needs LO = HI");
  return g;
}

std::vector<double> log_grid(const FrequencyGrid& g) {
  std::vector<double> omega(static_cast<std::size_t>(g.count));
  const double a = std::log(g.low), b = std::log(g.high);
  for (int k = 0; k < g.count; ++k) {
    omega[static_cast<std::size_t>(k)] = g.count == 1 ? g.low : std::exp(a + (b - a) * k / (g.count - 1));
  }
  return omega;
}

std::vector<Complex> frequency_response(const StateSpace& sys, const std::vector<double>& omega) {
  // M(ω) = iω I − A on A's pattern (which holds every diagonal entry, linearize.cpp): the
  // pattern is analysed once, each frequency refactorises (KLU, complex) and solves M x = B;
  // G = C x + D, times the sensors' delay e^{−iωτ}.
  const auto& a = sys.A;  // compressed, column major
  const int size = static_cast<int>(a.rows());
  std::vector<int> column_start(a.outerIndexPtr(), a.outerIndexPtr() + size + 1);
  std::vector<int> row(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
  std::vector<Complex> values(static_cast<std::size_t>(a.nonZeros()));
  std::vector<std::size_t> diagonal;
  for (int j = 0; j < size; ++j) {
    for (int k = column_start[static_cast<std::size_t>(j)]; k < column_start[static_cast<std::size_t>(j) + 1]; ++k) {
      values[static_cast<std::size_t>(k)] = -a.valuePtr()[k];
      if (row[static_cast<std::size_t>(k)] == j) diagonal.push_back(static_cast<std::size_t>(k));
    }
  }
  const std::vector<Complex> minus_a = values;
  KluComplexSolver solver(size, std::move(column_start), std::move(row));
  std::vector<Complex> g, x(static_cast<std::size_t>(size)), b(x.size());
  for (int k = 0; k < size; ++k) b[static_cast<std::size_t>(k)] = sys.B(k);
  const double b_norm = sys.B.lpNorm<Eigen::Infinity>();
  // ‖M x − b‖∞ relative to ‖M‖∞‖x‖∞ + ‖b‖∞ (a backward error).
  auto backward_error = [&] {
    std::vector<Complex> r(b);
    double m_norm = 0.0, x_norm = 0.0;
    std::vector<double> row_sum(x.size(), 0.0);
    for (int j = 0; j < size; ++j) {
      x_norm = std::max(x_norm, std::abs(x[static_cast<std::size_t>(j)]));
      for (int k = a.outerIndexPtr()[j]; k < a.outerIndexPtr()[j + 1]; ++k) {
        const auto i = static_cast<std::size_t>(a.innerIndexPtr()[k]);
        r[i] -= values[static_cast<std::size_t>(k)] * x[static_cast<std::size_t>(j)];
        row_sum[i] += std::abs(values[static_cast<std::size_t>(k)]);
      }
    }
    double r_norm = 0.0;
    for (std::size_t i = 0; i < r.size(); ++i) {
      r_norm = std::max(r_norm, std::abs(r[i]));
      m_norm = std::max(m_norm, row_sum[i]);
    }
    return r_norm / (m_norm * x_norm + b_norm + 1e-300);
  };
  g.reserve(omega.size());
  for (double w : omega) {
    for (std::size_t k : diagonal) values[k] = minus_a[k] + Complex(0.0, w);
    // The last frequency's pivots first (no allocation, no search); fresh pivots when they do
    // not give a backward-stable solution.
    bool solved = false;
    if (solver.refactorize(values)) {
      x = b;
      solver.solve(x);
      solved = backward_error() < 1e-12;
    }
    if (!solved) {
      if (!solver.factorize(values)) {
        g.emplace_back(INFINITY, 0.0);  // iω is an eigenvalue of A (an undamped mode)
        continue;
      }
      x = b;
      solver.solve(x);
    }
    Complex y = sys.D;
    for (int k = 0; k < size; ++k) {
      if (sys.C(k) != 0.0) y += sys.C(k) * x[static_cast<std::size_t>(k)];
    }
    g.push_back(y * std::exp(Complex(0.0, -w * sys.output_delay_s)));
  }
  return g;
}

double static_gain(const StateSpace& sys) {
  Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu;
  lu.compute(sys.A);
  if (lu.info() == Eigen::Success) {
    const Eigen::VectorXd x = lu.solve(sys.B);
    const double gain = sys.D - sys.C.dot(x);
    // A numerically singular A (an integrator) leaves a huge or non-finite solution.
    if (std::isfinite(gain) && x.allFinite() && x.norm() < 1e12 * (1.0 + sys.B.norm())) return gain;
  }
  // Integrating: the sign of the gain at a very low frequency.
  const double w = 1e-9;
  const Complex low = frequency_response(sys, {w}).front();
  return std::copysign(INFINITY, -low.imag());
}

std::vector<Complex> dominant_poles(const StateSpace& sys, int count) {
  if (count <= 0 || sys.A.rows() > 3000) return {};
  const Eigen::MatrixXd dense(sys.A);
  Eigen::EigenSolver<Eigen::MatrixXd> solver(dense, false);
  if (solver.info() != Eigen::Success) return {};
  std::vector<Complex> poles(solver.eigenvalues().begin(), solver.eigenvalues().end());
  std::sort(poles.begin(), poles.end(), [](Complex a, Complex b) {
    return a.real() != b.real() ? a.real() > b.real() : a.imag() > b.imag();
  });
  // One of each conjugate pair (the one with Im >= 0).
  std::vector<Complex> kept;
  for (Complex p : poles) {
    if (p.imag() < -1e-12 * std::abs(p)) continue;
    kept.push_back(p);
    if (static_cast<int>(kept.size()) == count) break;
  }
  return kept;
}

std::vector<double> unwrapped_phase_degrees(const std::vector<Complex>& g) {
  std::vector<double> phase(g.size());
  for (std::size_t k = 0; k < g.size(); ++k) {
    phase[k] = std::arg(g[k]) * 180.0 / M_PI;
    if (k > 0) {
      while (phase[k] - phase[k - 1] > 180.0) phase[k] -= 360.0;
      while (phase[k] - phase[k - 1] < -180.0) phase[k] += 360.0;
    }
  }
  return phase;
}

double delay_from_phase(const std::vector<double>& omega, const std::vector<Complex>& g) {
  if (omega.size() < 3) return 0.0;
  std::vector<double> phase = unwrapped_phase_degrees(g);
  for (double& p : phase) p *= M_PI / 180.0;
  // Least-squares slope over the upper half of the grid in log ω.
  const double middle = std::sqrt(omega.front() * omega.back());
  double sw = 0, sp = 0, sww = 0, swp = 0, count = 0;
  for (std::size_t k = 0; k < omega.size(); ++k) {
    if (omega[k] < middle || !std::isfinite(phase[k])) continue;
    sw += omega[k];
    sp += phase[k];
    sww += omega[k] * omega[k];
    swp += omega[k] * phase[k];
    ++count;
  }
  const double denominator = count * sww - sw * sw;
  if (count < 2 || !(denominator > 0.0)) return 0.0;
  return -(count * swp - sw * sp) / denominator;
}

Status LinearizeOptions::validate() const {
  Validator v;
  v.require(poles >= 0 && poles <= 50, "poles", poles, "an integer in [0, 50]");
  if (grid.count != 0) {
    v.require(grid.low > 0.0, "grid.low", grid.low, "a frequency > 0 rad/s")
        .require(grid.high >= grid.low, "grid.high", grid.high, "a frequency >= grid.low")
        .require(grid.count >= 1 && grid.count <= 100000, "grid.count", grid.count, "1..100000 (0: the default grid)")
        .require(grid.count != 1 || grid.high == grid.low, "grid.count", grid.count, "more than 1 when grid.low < grid.high");
  }
  return v.status();
}

FrequencyResponse linearize(const scenarios::Scenario& s, const scenarios::ExperimentSpec& e,
                            const LinearizeOptions& options) {
  if (const Status status = options.validate(); !status) throw InputError(status.message());
  FrequencyResponse r;
  r.system = linearize_system(s, e, options.input, options.output, &r.steady_state);
  const double nyquist = r.system.nyquist;
  FrequencyGrid grid = options.grid;
  if (grid.count == 0) grid = {1e-4 * nyquist, 0.5 * nyquist, 200};
  if (grid.high > nyquist) {
    throw InputError("--freq: HI = " + format_g(grid.high) + " rad/s is beyond the grid's Nyquist frequency " +
                     format_g(nyquist) + " rad/s (π min (c − |u|)/dx); expected HI <= " + format_g(nyquist));
  }
  r.omega = log_grid(grid);
  r.response = frequency_response(r.system, r.omega);
  r.static_gain = static_gain(r.system);
  r.poles = dominant_poles(r.system, options.poles);
  r.delay_s = delay_from_phase(r.omega, r.response);
  if (e.input.kind == scenarios::InputKind::prbs) {
    Band band = prbs_band(e.input.prbs_stages, e.input.prbs_clock_s);
    band.high = std::min(band.high, nyquist);
    if (band.high > band.low) {
      // A grid of its own (the fit must not depend on the user's), fine enough to unwrap the
      // phase of the delay for the fit's delay hint.
      const std::vector<double> omega = log_grid({band.low, band.high, 200});
      const auto g = frequency_response(r.system, omega);
      r.band = band;
      r.band_fit = fit_fractional_order(omega, g, band, delay_from_phase(omega, g));
    }
  }
  r.input_name = to_string(options.input);
  r.output_name = to_string(options.output);
  r.input_unit = options.input.kind == InputKind::gate ? "m" : "m3/s";
  r.output_unit = options.output.kind == OutputKind::q ? "m3/s" : "m";
  return r;
}

}  // namespace canalsim::linearize
