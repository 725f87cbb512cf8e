#include "diagnosis/discrepancy.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <utility>

namespace canalsim::diagnosis {
namespace {

constexpr int frequency_points = 512;
constexpr double command_power_share = 0.9;
constexpr int refine_iterations = 20;
constexpr int screening_iterations = 3;

// A recording as the fit sees it: the command as its deviation from the operating point.
struct Series {
  std::vector<double> u, e;
  std::size_t n_fit = 0;
};

struct Filter {
  std::vector<double> a, b;  // a_1..a_na, b_0..b_{nb−1}; no b: the zero filter
  int d = 0;
};

// A filter's simulation with the offsets that suit it best on the fitted parts.
struct Evaluation {
  std::vector<double> offsets;
  double fit_sse = 0.0, heldout_sse = 0.0;
};

void check_inputs(const std::vector<DiscrepancyRecording>& recordings, double period_s, const DiscrepancyOptions& o) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("fit_discrepancy: " + what); };
  if (const Status status = o.validate(); !status) fail("options: " + status.message());
  if (!(period_s > 0.0)) fail("period_s must be > 0");
  if (recordings.empty()) fail("recordings: expected at least one");
  const auto finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  for (std::size_t i = 0; i < recordings.size(); ++i) {
    const auto& r = recordings[i];
    const std::string where = "recording " + std::to_string(i) + ": ";
    const std::string n = std::to_string(r.u.size());
    if (r.residual.size() != r.u.size()) fail(where + "residual has " + std::to_string(r.residual.size()) + " samples, u " + n);
    if (r.n_fit < 1 || r.n_fit >= r.u.size()) fail(where + "n_fit = " + std::to_string(r.n_fit) + ": expected 1.." + n + " - 1");
    if (!finite(r.u)) fail(where + "u: expected finite values");
    if (!finite(r.residual)) fail(where + "residual: expected finite values");
  }
}

std::vector<Series> deviations_from_operating_points(const std::vector<DiscrepancyRecording>& recordings) {
  std::vector<Series> out;
  for (const auto& r : recordings) {
    Series s{r.u, r.residual, r.n_fit};
    for (auto& v : s.u) v -= r.u.front();
    out.push_back(std::move(s));
  }
  return out;
}

// x(k) = Σ b_j ũ(k−d−j) − Σ a_i x(k−i), from rest: the filter driven by the command alone.
std::vector<double> simulate(const Filter& f, const std::vector<double>& u) {
  std::vector<double> x(u.size(), 0.0);
  for (std::size_t k = 0; k < u.size(); ++k) {
    double v = 0.0;
    for (std::size_t j = 0; j < f.b.size(); ++j) {
      const std::size_t lag = static_cast<std::size_t>(f.d) + j;
      if (k >= lag) v += f.b[j] * u[k - lag];
    }
    for (std::size_t i = 1; i <= f.a.size() && i <= k; ++i) v -= f.a[i - 1] * x[k - i];
    x[k] = v;
  }
  return x;
}

// All roots of A inside the unit circle (eigenvalues of the companion matrix).
bool stable(const std::vector<double>& a) {
  if (a.empty()) return true;
  const auto n = static_cast<Eigen::Index>(a.size());
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) companion(0, i) = -a[static_cast<std::size_t>(i)];
  for (Eigen::Index i = 1; i < n; ++i) companion(i, i - 1) = 1.0;
  return companion.eigenvalues().cwiseAbs().maxCoeff() < 1.0;
}

Evaluation evaluate(const Filter& f, const std::vector<Series>& series) {
  Evaluation ev;
  for (const auto& s : series) {
    const std::vector<double> x = simulate(f, s.u);
    double c = 0.0;
    for (std::size_t k = 0; k < s.n_fit; ++k) c += s.e[k] - x[k];
    c /= static_cast<double>(s.n_fit);
    for (std::size_t k = 0; k < s.e.size(); ++k) {
      const double r = s.e[k] - c - x[k];
      (k < s.n_fit ? ev.fit_sse : ev.heldout_sse) += r * r;
    }
    ev.offsets.push_back(c);
  }
  return ev;
}

// Normal equations of the widest ARX regression on the fitted parts (Ljung, Section 10.1),
//   e(k) = −Σ_{i=1}^{P} a_i e(k−i) + Σ_{j=0}^{L−1} β_j ũ(k−j) + c'_r,
// built once; each structure (na, nb, d) is a selection of its columns.
struct ArxNormalEquations {
  Eigen::MatrixXd gram;
  Eigen::VectorXd rhs;
  int poles = 0, lags = 0;
  std::size_t rows = 0;
};

ArxNormalEquations arx_normal_equations(const std::vector<Series>& series, int poles, int lags) {
  ArxNormalEquations n{{}, {}, poles, lags, 0};
  const auto cols = static_cast<Eigen::Index>(poles + lags) + static_cast<Eigen::Index>(series.size());
  n.gram = Eigen::MatrixXd::Zero(cols, cols);
  n.rhs = Eigen::VectorXd::Zero(cols);
  Eigen::VectorXd phi(cols);
  for (std::size_t r = 0; r < series.size(); ++r) {
    const Series& s = series[r];
    for (std::size_t k = static_cast<std::size_t>(poles); k < s.n_fit; ++k) {
      phi.setZero();
      for (int i = 1; i <= poles; ++i) phi(i - 1) = -s.e[k - static_cast<std::size_t>(i)];
      for (int j = 0; j < lags && static_cast<std::size_t>(j) <= k; ++j) phi(poles + j) = s.u[k - static_cast<std::size_t>(j)];
      phi(poles + lags + static_cast<Eigen::Index>(r)) = 1.0;
      n.gram.selfadjointView<Eigen::Lower>().rankUpdate(phi);
      n.rhs += phi * s.e[k];
      ++n.rows;
    }
  }
  n.gram = n.gram.selfadjointView<Eigen::Lower>();
  return n;
}

std::optional<Filter> arx_filter(const ArxNormalEquations& n, int na, int nb, int d) {
  std::vector<Eigen::Index> columns;
  for (int i = 0; i < na; ++i) columns.push_back(i);
  for (int j = 0; j < nb; ++j) columns.push_back(n.poles + d + j);
  for (Eigen::Index c = n.poles + n.lags; c < n.gram.cols(); ++c) columns.push_back(c);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(n.gram(columns, columns));
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  const Eigen::VectorXd theta = ldlt.solve(n.rhs(columns));
  if (!theta.allFinite()) return std::nullopt;
  return Filter{{theta.data(), theta.data() + na}, {theta.data() + na, theta.data() + na + nb}, d};
}

// Gauss–Newton on the simulation error of the fitted parts, damped as Levenberg–Marquardt, the
// offsets projected out (each sensitivity taken less its mean over the fitted part): the ARX
// start is biased when the residual's noise is not A-filtered white noise (Ljung, Section 10.2).
// Sensitivities: ∂x/∂b_j = w(k−j), w = ũ(k−d)/A; ∂x/∂a_i = −z(k−i), z = x/A.
Filter refine(Filter f, const std::vector<Series>& series, int iterations) {
  const std::size_t na = f.a.size(), p = na + f.b.size();
  double cost = evaluate(f, series).fit_sse, lambda = 1e-3;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    Eigen::MatrixXd h = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(p));
    Eigen::VectorXd g = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(p));
    for (const auto& s : series) {
      const std::vector<double> x = simulate(f, s.u), w = simulate(Filter{f.a, {1.0}, f.d}, s.u),
                                z = simulate(Filter{f.a, {1.0}, 0}, x);
      Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(s.n_fit), static_cast<Eigen::Index>(p));
      Eigen::VectorXd res(static_cast<Eigen::Index>(s.n_fit));
      for (std::size_t k = 0; k < s.n_fit; ++k) {
        const auto row = static_cast<Eigen::Index>(k);
        for (std::size_t i = 1; i <= na && i <= k; ++i) jac(row, static_cast<Eigen::Index>(i - 1)) = z[k - i];
        for (std::size_t j = 0; j < f.b.size() && j <= k; ++j) jac(row, static_cast<Eigen::Index>(na + j)) = -w[k - j];
        res(row) = s.e[k] - x[k];
      }
      jac.rowwise() -= jac.colwise().mean();
      res.array() -= res.mean();
      h += jac.transpose() * jac;
      g += jac.transpose() * res;
    }
    bool improved = false;
    for (int attempt = 0; attempt < 8; ++attempt) {
      Eigen::MatrixXd damped = h;
      damped.diagonal() *= 1.0 + lambda;
      const Eigen::VectorXd step = damped.ldlt().solve(-g);
      Filter trial = f;
      for (std::size_t i = 0; i < p; ++i) (i < na ? trial.a[i] : trial.b[i - na]) += step(static_cast<Eigen::Index>(i));
      const double trial_cost = step.allFinite() && stable(trial.a) ? evaluate(trial, series).fit_sse : cost;
      if (trial_cost < cost) {
        improved = cost - trial_cost > 1e-12 * cost;
        f = trial;
        cost = trial_cost;
        lambda *= 0.1;
        break;
      }
      lambda *= 10.0;
    }
    if (!improved) break;
  }
  return f;
}

// BIC (Schwarz 1978) of a filter's simulation error on the fitted parts: n log(SSE/n) + k log n,
// k the filter's coefficients and the offsets.
double bic(const Filter& f, const std::vector<Series>& series) {
  double n = 0.0;
  for (const auto& s : series) n += static_cast<double>(s.n_fit);
  const double sse = std::max(evaluate(f, series).fit_sse, std::numeric_limits<double>::min());
  const double k = static_cast<double>(f.a.size() + f.b.size() + series.size());
  return n * std::log(sse / n) + k * std::log(n);
}

// Every structure from its ARX start, screened after a few Gauss–Newton steps (the ARX start is
// biased, by an amount that depends on the structure: the equation error is the noise filtered by
// A); for each order (na, nb) the best delay is refined fully, and the least BIC wins.
// No stable structure: the zero filter.
Filter select_structure(const std::vector<Series>& series, const DiscrepancyOptions& o, int max_delay) {
  const ArxNormalEquations normal = arx_normal_equations(series, o.max_poles, max_delay + o.max_numerator);
  if (normal.rows <= static_cast<std::size_t>(normal.gram.cols())) return {};
  Filter best;
  double best_bic = std::numeric_limits<double>::infinity();
  for (int na = 0; na <= o.max_poles; ++na) {
    for (int nb = 1; nb <= o.max_numerator; ++nb) {
      std::optional<Filter> screened;
      double screened_bic = std::numeric_limits<double>::infinity();
      for (int d = 0; d <= max_delay; ++d) {
        const std::optional<Filter> f = arx_filter(normal, na, nb, d);
        if (!f || !stable(f->a)) continue;
        Filter g = refine(*f, series, screening_iterations);
        if (const double b = bic(g, series); b < screened_bic) { screened_bic = b; screened = std::move(g); }
      }
      if (!screened) continue;
      Filter refined = refine(*screened, series, refine_iterations);
      if (const double b = bic(refined, series); b < best_bic) { best_bic = b; best = std::move(refined); }
    }
  }
  return best;
}

std::complex<double> response(const Filter& f, double omega) {
  std::complex<double> num = 0.0, den = 1.0;
  for (std::size_t j = 0; j < f.b.size(); ++j) num += f.b[j] * std::polar(1.0, -omega * static_cast<double>(j));
  for (std::size_t i = 1; i <= f.a.size(); ++i) den += f.a[i - 1] * std::polar(1.0, -omega * static_cast<double>(i));
  return num / den * std::polar(1.0, -omega * f.d);
}

// The frequency below which command_power_share of the power of the commands (each less its
// mean) lies: periodograms summed over the recordings on the response's grid.
double command_band(const std::vector<Series>& series, double period_s) {
  std::vector<double> power(frequency_points, 0.0);
  for (const auto& s : series) {
    double mean = 0.0;
    for (double v : s.u) mean += v / static_cast<double>(s.u.size());
    for (int j = 0; j < frequency_points; ++j) {
      const std::complex<double> turn = std::polar(1.0, -std::numbers::pi * j / (frequency_points - 1));
      std::complex<double> phase = 1.0, sum = 0.0;
      for (double v : s.u) { sum += (v - mean) * phase; phase *= turn; }
      power[static_cast<std::size_t>(j)] += std::norm(sum);
    }
  }
  double total = 0.0, running = 0.0;
  for (double v : power) total += v;
  const double nyquist = 0.5 / period_s;
  for (int j = 0; j < frequency_points; ++j) {
    running += power[static_cast<std::size_t>(j)];
    if (running >= command_power_share * total) return nyquist * j / (frequency_points - 1);
  }
  return nyquist;
}

// Peak of |E| and the contiguous band around it within 3 dB, its edges interpolated between grid
// points; "static" when the peak is at 0 Hz and the band covers the command's band.
void describe_response(const Filter& f, double period_s, DiscrepancyModel& m) {
  const double step_hz = 0.5 / period_s / (frequency_points - 1);
  std::vector<double> gain(frequency_points);
  for (int j = 0; j < frequency_points; ++j) {
    gain[static_cast<std::size_t>(j)] = std::abs(response(f, std::numbers::pi * j / (frequency_points - 1)));
  }
  const auto peak = static_cast<std::size_t>(std::max_element(gain.begin(), gain.end()) - gain.begin());
  const double edge = gain[peak] / std::numbers::sqrt2;
  std::size_t lo = peak, hi = peak;
  while (lo > 0 && gain[lo - 1] >= edge) --lo;
  while (hi + 1 < gain.size() && gain[hi + 1] >= edge) ++hi;
  // Grid index where |E| crosses the edge between `inside` and its neighbour `outside`.
  const auto crossing = [&](std::size_t inside, std::size_t outside) {
    const double t = (gain[inside] - edge) / (gain[inside] - gain[outside]);
    return static_cast<double>(inside) + t * (static_cast<double>(outside) - static_cast<double>(inside));
  };
  m.peak_hz = step_hz * static_cast<double>(peak);
  m.band_low_hz = lo > 0 ? step_hz * crossing(lo, lo - 1) : 0.0;
  m.band_high_hz = step_hz * (hi + 1 < gain.size() ? crossing(hi, hi + 1) : static_cast<double>(hi));
  m.form = peak == 0 && m.band_high_hz >= m.command_band_hz ? "static" : "dynamic";
}

}  // namespace

Status DiscrepancyOptions::validate() const {
  return Validator()
      .require(max_poles >= 0 && max_poles <= 4, "max_poles", max_poles, "0..4")
      .require(max_numerator >= 1 && max_numerator <= 8, "max_numerator", max_numerator, "1..8")
      .require(max_delay_s >= 0.0 && max_delay_s <= 60.0, "max_delay_s", max_delay_s, "[0, 60]")
      .require(min_heldout_gain > 0.0 && min_heldout_gain < 1.0, "min_heldout_gain", min_heldout_gain, "(0, 1)")
      .status();
}

DiscrepancyModel fit_discrepancy(const std::string& channel, const std::vector<DiscrepancyRecording>& recordings,
                                 double period_s, const DiscrepancyOptions& o) {
  check_inputs(recordings, period_s, o);
  const std::vector<Series> series = deviations_from_operating_points(recordings);
  // Delays on the sample grid, each leaving some command inside every fitted part.
  std::size_t shortest_fit = series.front().n_fit;
  for (const auto& s : series) shortest_fit = std::min(shortest_fit, s.n_fit);
  const int max_delay = static_cast<int>(std::min(std::floor(o.max_delay_s / period_s + 1e-9),
                                                  static_cast<double>(shortest_fit - 1)));
  const Filter filter = select_structure(series, o, max_delay);

  // Judged on the held-out parts: against no correction, and against the offsets alone.
  const Evaluation offsets_only = evaluate(Filter{}, series), filtered = evaluate(filter, series);
  double before = 0.0, held = 0.0;
  for (const auto& s : series) {
    for (std::size_t k = s.n_fit; k < s.e.size(); ++k) before += s.e[k] * s.e[k];
    held += static_cast<double>(s.e.size() - s.n_fit);
  }
  DiscrepancyModel m;
  m.channel = channel;
  m.command_band_hz = command_band(series, period_s);
  m.heldout_rms_before = m.heldout_rms_after = std::sqrt(before / held);
  if (!(before > 0.0)) return m;
  m.offsets_share_removed = 1.0 - offsets_only.heldout_sse / before;
  const bool beats_offsets = filtered.heldout_sse <= (1.0 - o.min_heldout_gain) * offsets_only.heldout_sse;
  if (!filter.b.empty() && 1.0 - filtered.heldout_sse / before >= o.min_heldout_gain && beats_offsets) {
    m.found = true;
    m.poles = static_cast<int>(filter.a.size());
    m.numerator = static_cast<int>(filter.b.size());
    m.delay_s = filter.d * period_s;
    m.a = filter.a;
    m.b = filter.b;
    m.offsets = filtered.offsets;
    m.static_gain = response(filter, 0.0).real();
    m.heldout_rms_after = std::sqrt(filtered.heldout_sse / held);
    m.heldout_share_removed = 1.0 - filtered.heldout_sse / before;
    describe_response(filter, period_s, m);
  } else if (m.offsets_share_removed >= o.min_heldout_gain) {
    m.form = "static";
    m.offsets = offsets_only.offsets;
    m.heldout_rms_after = std::sqrt(offsets_only.heldout_sse / held);
    m.heldout_share_removed = m.offsets_share_removed;
  }
  return m;
}

}  // namespace canalsim::diagnosis
