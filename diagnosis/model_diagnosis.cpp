#include "diagnosis/model_diagnosis.hpp"

#include "core/format.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <complex>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <sstream>
#include <unsupported/Eigen/MatrixFunctions>

#include "diagnosis/catalog.hpp"
#include "reduced_models/identification.hpp"
#include "reduced_models/metrics.hpp"
#include "reduced_models/sensor_reading.hpp"

namespace canalsim::diagnosis {
namespace {

using reduced::ExperimentData;
using reduced::FitOptions;
using reduced::Model;
using reduced::ModelKind;

constexpr const char* kUpstream = "upstream_level_variation";
constexpr const char* kRegime = "flow_regime_switch";
constexpr const char* kWave = "wave_resonance";
constexpr const char* kQuantization = "sensor_quantization[y_dwe_mm]";


// Free-flow share of the samples by the paper's condition (8), with the gate position where it
// was recorded and the command otherwise.
double free_share(const std::vector<ExperimentData>& data) {
  std::size_t free = 0, total = 0;
  for (const auto& d : data) {
    if (!d.has_upstream_level()) continue;
    for (std::size_t k = 0; k < d.size(); ++k) {
      const double x = d.x_up_mm.empty() ? d.u_mm[k] : d.x_up_mm[k];
      if (x <= 0.0) continue;
      free += reduced::is_free_flow(d.y_up_mm[k], d.y_dwe_mm[k], x) ? 1 : 0;
      ++total;
    }
  }
  return total == 0 ? -1.0 : static_cast<double>(free) / static_cast<double>(total);
}

std::optional<ModelKind> nonlinear_form(ModelKind kind, bool free_flow) {
  switch (kind) {
    case ModelKind::liom: return free_flow ? ModelKind::nliom_f : ModelKind::nliom_s;
    case ModelKind::lfom: return free_flow ? ModelKind::nlfom_f : ModelKind::nlfom_s;
    default: return std::nullopt;
  }
}

// Samples [warm, n_fit) are the fitted part, [n_fit, n) the held-out part of a recording.
struct Split {
  std::size_t warm = 0, n_fit = 0, n = 0;
};

// A model's prediction of the primary channel, per recording (absolute mm).
using Predictions = std::vector<std::vector<double>>;

struct Scores {
  double fit_mse = 0.0, heldout_mse = 0.0;
  double fit_nrmse = 0.0, heldout_nrmse = 0.0;  // mean over recordings, %; NaN where not defined
};

// The mean Nrmse (eq. 19) over the recordings whose part varies: on levels that stay constant the
// index divides by zero and says nothing of the fit. NaN when no part varies.
class MeanNrmse {
 public:
  void add(const std::vector<double>& model, const std::vector<double>& data) {
    if (data.empty() || std::all_of(data.begin(), data.end(), [&](double v) { return v == data.front(); })) return;
    sum_ += reduced::nrmse_percent(model, data);
    ++count_;
  }
  double mean() const { return count_ > 0 ? sum_ / count_ : std::numeric_limits<double>::quiet_NaN(); }

 private:
  double sum_ = 0.0;
  int count_ = 0;
};

class ModelEngine {
 public:
  ModelEngine(const std::vector<Recording>& recordings, const ModelDiagnoseOptions& o) : o_(o) {
    for (const auto& rec : recordings) {
      data_.push_back(reduced::prepare_data(rec, o.data));
      if (rec.has(columns::regime)) regime_.push_back(rec.column(columns::regime));
      else regime_.emplace_back();
    }
    for (const auto& d : data_) {
      Split s;
      s.n = d.size();
      s.n_fit = static_cast<std::size_t>(std::round(o.fit_fraction * static_cast<double>(s.n)));
      s.warm = std::min(s.n_fit / 2, static_cast<std::size_t>(std::ceil(o.warmup_s / d.h - 1e-9)));
      // Both parts carry as many samples as a fit of the model needs (identification.cpp).
      const std::size_t needed = 2 * (reduced::parameter_names(o.kind).size() + 1);
      if (s.n_fit < needed || s.n - s.n_fit < needed) {
        throw InputError(d.source + ": " + std::to_string(s.n) + " samples: too few to fit " + reduced::model_name(o.kind) +
                         " on a fraction " + format_g(o.fit_fraction) + " of them and test it on the rest: expected at least " +
                         std::to_string(needed) + " in each part");
      }
      split_.push_back(s);
      heads_.push_back(reduced::leading_samples(d, s.n_fit));
    }
    fit_options_.actuation.quantum_mm = o.quantum_mm;
    fit_options_.actuation.gate_speed_mm_s = o.gate_speed_mm_s;
    fit_options_.threads = 1;
  }

  const std::vector<ExperimentData>& data() const { return data_; }

  // A gain in mm/mm times gain_factor() is in the recordings' declared units, gain_unit() (as
  // `canalsim fit` reports K, data.hpp); recordings that declare different units keep mm/mm.
  double gain_factor() const { return same_declared_units() ? reduced::declared_gain_factor(data_.front()) : 1.0; }
  std::string gain_unit() const { return same_declared_units() ? reduced::declared_gain_unit(data_.front()) : "mm/mm"; }
  const std::vector<std::vector<double>>& regimes() const { return regime_; }
  const std::vector<Split>& splits() const { return split_; }
  const Model& nominal() const { return nominal_; }
  const Predictions& nominal_predictions() const { return nominal_predictions_; }

  void fit_nominal() {
    nominal_ = reduced::fit_nominal(o_.kind, heads_, fit_options_).model;
    nominal_predictions_ = predict(nominal_);
    nominal_scores_ = score(nominal_predictions_);
  }

  Predictions predict(const Model& m) const {
    Predictions out;
    for (const auto& d : data_) out.push_back(reduced::simulate(m, d).y_dwe_mm);
    return out;
  }

  Scores score(const Predictions& p) const {
    Scores s;
    MeanNrmse fit_nrmse, heldout_nrmse;
    double fit_sq = 0.0, held_sq = 0.0;
    std::size_t fit_n = 0, held_n = 0;
    for (std::size_t i = 0; i < data_.size(); ++i) {
      const auto& y = data_[i].y_dwe_mm;
      const auto& sp = split_[i];
      for (std::size_t k = sp.warm; k < sp.n; ++k) {
        const double e = y[k] - p[i][k];
        if (k < sp.n_fit) {
          fit_sq += e * e;
          ++fit_n;
        } else {
          held_sq += e * e;
          ++held_n;
        }
      }
      auto part = [](const std::vector<double>& v, std::size_t a, std::size_t b) {
        return std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(a), v.begin() + static_cast<std::ptrdiff_t>(b));
      };
      fit_nrmse.add(part(p[i], sp.warm, sp.n_fit), part(y, sp.warm, sp.n_fit));
      heldout_nrmse.add(part(p[i], sp.n_fit, sp.n), part(y, sp.n_fit, sp.n));
    }
    s.fit_mse = fit_sq / static_cast<double>(std::max<std::size_t>(fit_n, 1));
    s.heldout_mse = held_sq / static_cast<double>(std::max<std::size_t>(held_n, 1));
    s.fit_nrmse = fit_nrmse.mean();
    s.heldout_nrmse = heldout_nrmse.mean();
    return s;
  }

  // Effective number of independent samples of the nominal fitted-part residual (for the BIC).
  double effective_fit_samples() const {
    double n_eff = 0.0;
    for (std::size_t i = 0; i < data_.size(); ++i) {
      const auto& sp = split_[i];
      std::vector<double> e;
      for (std::size_t k = sp.warm; k < sp.n_fit; ++k) e.push_back(data_[i].y_dwe_mm[k] - nominal_predictions_[i][k]);
      n_eff += effective_samples(e);
    }
    return std::max(n_eff, 2.0);
  }

  // Fills the scores of an effect whose corrected predictions are `p` with `extra` parameters.
  EffectResult judge(const std::string& name, const Predictions& p, int extra, ParameterEstimate parameter,
                     bool material) const {
    EffectResult r;
    r.name = name;
    // A corrected model whose output leaves the finite numbers (a nonlinear form fitted to
    // recordings with outliers can diverge on the held-out part) explains nothing.
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (!std::all_of(p[i].begin(), p[i].end(), [](double v) { return std::isfinite(v); })) {
        r.note = "the corrected model's output diverges on " + data_[i].source;
        return r;
      }
    }
    r.parameter = std::move(parameter);
    r.material = material;
    const Scores after = score(p);
    r.nrmse_before = nominal_scores_.fit_nrmse;
    r.nrmse_after = after.fit_nrmse;
    r.heldout_nrmse_before = nominal_scores_.heldout_nrmse;
    r.heldout_nrmse_after = after.heldout_nrmse;
    r.cost_before = nominal_scores_.fit_mse;
    r.cost_after = after.fit_mse;
    r.heldout_cost_before = nominal_scores_.heldout_mse;
    r.heldout_cost_after = after.heldout_mse;
    r.score = 1.0 - after.heldout_mse / std::max(nominal_scores_.heldout_mse, 1e-300);
    r.delta_bic = bic_change(effective_fit_samples(), nominal_scores_.fit_mse, after.fit_mse, extra);
    // "Show the fit improve": the held-out Nrmse (mean over recordings) must rise too — the pooled
    // squared residual can fall through one recording while the others get worse.
    // Where no held-out part varies the index is not defined and the held-out cost decides.
    r.heldout_improves = std::isfinite(r.heldout_nrmse_before)
                             ? r.heldout_nrmse_after > r.heldout_nrmse_before  // one channel: y_dwe_mm
                             : after.heldout_mse < nominal_scores_.heldout_mse;
    const SignificanceRule rule{o_.min_score, o_.min_bic_gain, true};
    r.significant = is_significant(r, rule);
    r.set_aside = set_aside_reason(r, rule);
    judged_[name] = p;
    return r;
  }

  // The corrected predictions of a judged effect.
  const Predictions& predictions_of(const std::string& name) const { return judged_.at(name); }

  // The nominal model fitted afresh on the fitted parts with other actuation settings (a fresh
  // search, not a polish of the nominal fit: that fit has absorbed the effect into T and L).
  Model refit(const reduced::Actuation& actuation) const {
    FitOptions fo = fit_options_;
    fo.actuation = actuation;
    return reduced::fit_nominal(o_.kind, heads_, fo).model;
  }

  Model fit_kind(ModelKind kind) const { return reduced::fit_nominal(kind, heads_, fit_options_).model; }

  // Δu delayed by the nominal model's L and passed through its actuator: what reaches the pool.
  std::vector<double> delayed_input(std::size_t i) const {
    return reduced::delayed_input(data_[i], nominal_.actuation, nominal_.p.L);
  }

  const ModelDiagnoseOptions& options() const { return o_; }

 private:
  bool same_declared_units() const {
    for (const auto& d : data_) {
      if (reduced::declared_gain_unit(d) != reduced::declared_gain_unit(data_.front()) ||
          reduced::declared_gain_factor(d) != reduced::declared_gain_factor(data_.front())) {
        return false;
      }
    }
    return true;
  }

  const ModelDiagnoseOptions& o_;
  std::vector<ExperimentData> data_, heads_;
  std::vector<std::vector<double>> regime_;
  std::vector<Split> split_;
  FitOptions fit_options_;
  Model nominal_;
  Predictions nominal_predictions_;
  Scores nominal_scores_;
  mutable std::map<std::string, Predictions> judged_;
};

// Standard deviation of θ from a parabola through three (θ, MSE) points around the minimum:
// MSE(θ) ≈ MSE_min + a (θ − θ*)², so var θ ≈ MSE_min / (N_eff a) (Gauss–Newton curvature of a
// least-squares cost). 0 when the points do not bracket a minimum.
double parabola_std(double t0, double c0, double t1, double c1, double t2, double c2, double n_eff) {
  const double d01 = (c1 - c0) / (t1 - t0), d12 = (c2 - c1) / (t2 - t1);
  const double a = (d12 - d01) / (t2 - t0);
  if (!(a > 0.0)) return 0.0;
  return std::sqrt(std::max(std::min({c0, c1, c2}), 1e-300) / (n_eff * a));
}

EffectResult not_expressible(const std::string& name, const std::string& why) {
  EffectResult r;
  r.name = name;
  r.note = why;
  r.score = 0.0;
  return r;
}

EffectResult gate_rate_limit(const ModelEngine& e) {
  // θ = 1/v (s/mm): θ = 0 is the ideal gate, and the response is close to linear in θ.
  const std::vector<double> speeds = {1.0, 1.6, 2.5, 4.0, 6.3, 10.0, 16.0, 25.0, 40.0};
  std::vector<double> theta, cost;
  std::vector<Model> models;
  for (double v : speeds) {
    reduced::Actuation a = e.nominal().actuation;
    a.gate_speed_mm_s = v;
    models.push_back(e.refit(a));
    theta.push_back(1.0 / v);
    cost.push_back(e.score(e.predict(models.back())).fit_mse);
  }
  const auto best = static_cast<std::size_t>(std::min_element(cost.begin(), cost.end()) - cost.begin());
  double v = speeds[best];
  Model chosen = models[best];
  double std_v = 0.0;
  if (best > 0 && best + 1 < speeds.size()) {
    // Between grid points: the vertex of the parabola through the best point and its neighbours
    // (one more refit, kept only if it fits better).
    const double t0 = theta[best - 1], t1 = theta[best], t2 = theta[best + 1];
    const double c0 = cost[best - 1], c1 = cost[best], c2 = cost[best + 1];
    const double num = (t1 - t0) * (t1 - t0) * (c1 - c2) - (t1 - t2) * (t1 - t2) * (c1 - c0);
    const double den = (t1 - t0) * (c1 - c2) - (t1 - t2) * (c1 - c0);
    if (den != 0.0) {
      const double vertex = std::clamp(t1 - 0.5 * num / den, std::min(t0, t2), std::max(t0, t2));
      reduced::Actuation a = e.nominal().actuation;
      a.gate_speed_mm_s = 1.0 / vertex;
      const Model m = e.refit(a);
      if (e.score(e.predict(m)).fit_mse < c1) {
        chosen = m;
        v = a.gate_speed_mm_s;
      }
    }
    const double sd_theta = parabola_std(t0, c0, t1, c1, t2, c2, e.effective_fit_samples());
    std_v = sd_theta * v * v;  // dv = v² dθ
  }
  return e.judge("gate_rate_limit", e.predict(chosen), 1,
                 {"speed", "mm/s", v, std_v}, is_material(*effect_from_name("gate_rate_limit"), v));
}

EffectResult sensor_quantization(const ModelEngine& e) {
  // Real sensors have offsets: the lattice r·k + origin need not pass through zero
  // (reduced_models/sensor_reading.hpp, shared with the least-squares fit).
  std::vector<const reduced::ExperimentData*> data;
  for (const auto& d : e.data()) data.push_back(&d);
  const reduced::SensorLattice lattice = reduced::recorded_lattice(data);
  const double r = lattice.step;
  const double modelled = e.nominal().actuation.quantum_mm;
  if (r == 0.0) return not_expressible(kQuantization, "the recorded levels lie on no lattice");
  if (r <= 1.5 * modelled) {
    return not_expressible(kQuantization,
                           "the recorded lattice (" + format_g(r) + " mm) is the modelled resolution");
  }
  // The corrected prediction is the nominal model's level read by the coarser sensor: its
  // expected reading given the model's own spread (catalog.hpp, expected_reading; docs/diagnosis.md
  // §4), not the rounded level. (Refitting the model with the coarse rounding in its cost makes the
  // cost piecewise flat and the fit worse, not better.)
  Model m = e.nominal();
  m.actuation.quantum_mm = 0.0;
  Predictions p = e.predict(m);
  double sq = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (std::size_t k = e.splits()[i].warm; k < e.splits()[i].n_fit; ++k) {
      sq += std::pow(e.data()[i].y_dwe_mm[k] - p[i][k], 2);
      ++n;
    }
  }
  const double spread = std::sqrt(std::max(sq / static_cast<double>(std::max<std::size_t>(n, 1)) - r * r / 12.0, 0.01 * r * r));
  for (auto& series : p) {
    for (double& y : series) y = lattice.origin + expected_reading(y - lattice.origin, r, spread);
  }
  EffectResult res = e.judge(kQuantization, p, 1, {"resolution", "mm", r, 0.0},
                             is_material(*effect_from_name(kQuantization), r));
  // A lattice is seen directly in the data, not through a better prediction (quantising a model
  // that is slightly off can move its output to the wrong step): every level on the lattice,
  // coarser than the modelled resolution, is the evidence.
  res.score = std::max(res.score, 0.95);
  res.significant = res.material;
  return res;
}

EffectResult upstream_level_variation(const ModelEngine& e) {
  const ModelKind kind = e.options().kind;
  for (const auto& d : e.data()) {
    if (!d.has_upstream_level() || d.y_up_is_constant_option) {
      return not_expressible(kUpstream, d.source + " has no recorded y_up_mm");
    }
  }
  const double share = free_share(e.data());
  const auto nl = nonlinear_form(kind, share > 0.5);
  if (!nl && reduced::is_integrating(kind)) {
    return not_expressible(kUpstream, "model " + reduced::model_name(kind) + " has no upstream-level form");
  }
  if (!nl) return not_expressible(kUpstream, "model " + reduced::model_name(kind) + " already uses y_up");
  Model m = e.fit_kind(*nl);
  const int extra = static_cast<int>(reduced::parameter_names(*nl).size() - reduced::parameter_names(kind).size());
  return e.judge(kUpstream, e.predict(m), std::max(extra, 1),
                 {"gamma", "-", m.p.gamma, 0.0}, std::abs(m.p.gamma) >= 0.1);
}

EffectResult flow_regime_switch(const ModelEngine& e) {
  const ModelKind kind = e.options().kind;
  if (kind == ModelKind::hybrid) return not_expressible(kRegime, "the hybrid model already switches");
  if (reduced::is_integrating(kind)) {
    return not_expressible(kRegime, "the switching (hybrid) model is a lag, not an integrator like " +
                                        reduced::model_name(kind));
  }
  for (const auto& d : e.data()) {
    if (!d.has_upstream_level()) return not_expressible(kRegime, d.source + " has no y_up_mm for conditions (8)/(10)");
  }
  const double share = free_share(e.data());
  if (share < 0.05 || share > 0.95) {
    return not_expressible(kRegime, "the recordings stay in one regime (free flow in " +
                                        format_g(std::round(100.0 * share)) + "% of the samples)");
  }
  Model m = e.fit_kind(ModelKind::hybrid);
  const int extra = static_cast<int>(reduced::parameter_names(ModelKind::hybrid).size() -
                                     reduced::parameter_names(kind).size());
  const double k = m.p.K == 0.0 ? 1.0 : m.p.K;
  const bool material = std::abs(m.p.K_sub / k - 1.0) >= 0.1 || std::abs(m.p.gamma_sub - m.p.gamma) >= 0.1;
  return e.judge(kRegime, e.predict(m), std::max(extra, 1),
                 {"K_sub", e.gain_unit(), m.p.K_sub * e.gain_factor(), 0.0}, material);
}

// Least-squares fit of residual ≈ a z1 + b z2 over the fitted parts; returns (a, b, mse).
struct ModeFit {
  double a = 0.0, b = 0.0, mse = 0.0;
};

EffectResult wave_resonance(const ModelEngine& e) {
  const auto& data = e.data();
  const auto& splits = e.splits();
  const auto& nominal = e.nominal_predictions();
  std::vector<std::vector<double>> inputs, residuals;
  for (std::size_t i = 0; i < data.size(); ++i) {
    inputs.push_back(e.delayed_input(i));
    std::vector<double> r(data[i].size());
    for (std::size_t k = 0; k < r.size(); ++k) r[k] = data[i].y_dwe_mm[k] - nominal[i][k];
    residuals.push_back(std::move(r));
  }
  const double h = data.front().h;
  const double f_low = 0.01, f_high = std::min(1.0, 0.25 / h);
  const std::vector<double> dampings = {0.02, 0.05, 0.1, 0.2};
  constexpr int kFrequencies = 60;
  struct Best {
    double f = 0, zeta = 0, mse = std::numeric_limits<double>::infinity(), a = 0, b = 0;
  } best;
  std::vector<double> profile_f, profile_mse;  // best MSE per frequency (over damping)
  auto regressors = [&](std::size_t i, double f, double zeta) {
    const auto mode = damped_mode_response(inputs[i], data[i].h, f, zeta);
    std::vector<double> high(mode.low_pass.size());
    for (std::size_t k = 0; k < high.size(); ++k) high[k] = mode.low_pass[k] - inputs[i][k];
    return std::make_pair(mode.band_pass, high);  // zero static gain: the nominal gain stays
  };
  for (int j = 0; j < kFrequencies; ++j) {
    const double f = f_low * std::pow(f_high / f_low, static_cast<double>(j) / (kFrequencies - 1));
    double best_here = std::numeric_limits<double>::infinity();
    for (double zeta : dampings) {
      Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
      Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
      double rr = 0.0;
      std::size_t n = 0;
      std::vector<std::pair<std::vector<double>, std::vector<double>>> z;
      for (std::size_t i = 0; i < data.size(); ++i) {
        z.push_back(regressors(i, f, zeta));
        for (std::size_t k = splits[i].warm; k < splits[i].n_fit; ++k) {
          const Eigen::Vector2d x(z[i].first[k], z[i].second[k]);
          A += x * x.transpose();
          rhs += x * residuals[i][k];
          rr += residuals[i][k] * residuals[i][k];
          ++n;
        }
      }
      if (n == 0 || std::abs(A.determinant()) < 1e-300) continue;
      const Eigen::Vector2d ab = A.ldlt().solve(rhs);
      const double mse = (rr - ab.dot(rhs)) / static_cast<double>(n);
      best_here = std::min(best_here, mse);
      if (mse < best.mse) best = {f, zeta, mse, ab[0], ab[1]};
    }
    profile_f.push_back(f);
    profile_mse.push_back(best_here);
  }
  if (!std::isfinite(best.mse)) return not_expressible(kWave, "no mode could be fitted");
  Predictions corrected = nominal;
  double contribution_sq = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < data.size(); ++i) {
    const auto [bp, hp] = regressors(i, best.f, best.zeta);
    for (std::size_t k = 0; k < corrected[i].size(); ++k) {
      const double add = best.a * bp[k] + best.b * hp[k];
      corrected[i][k] += add;
      if (k >= splits[i].warm && k < splits[i].n_fit) {
        contribution_sq += add * add;
        ++count;
      }
    }
  }
  const auto at = static_cast<std::size_t>(std::find(profile_f.begin(), profile_f.end(), best.f) - profile_f.begin());
  double std_f = 0.0;
  if (at > 0 && at + 1 < profile_f.size()) {
    const double sd_log = parabola_std(std::log(profile_f[at - 1]), profile_mse[at - 1], std::log(profile_f[at]),
                                       profile_mse[at], std::log(profile_f[at + 1]), profile_mse[at + 1],
                                       e.effective_fit_samples());
    std_f = sd_log * best.f;
  }
  // Material: the mode moves the level by more than a sensor step (0.05 mm) on average.
  const double rms = std::sqrt(contribution_sq / static_cast<double>(std::max<std::size_t>(count, 1)));
  return e.judge(kWave, corrected, 4, {"frequency", "Hz", best.f, std_f}, rms >= 0.05);
}

EffectResult evaluate(const std::string& name, const ModelEngine& e) {
  if (name == "gate_rate_limit") return gate_rate_limit(e);
  if (name == kQuantization) return sensor_quantization(e);
  if (name == kUpstream) return upstream_level_variation(e);
  if (name == kRegime) return flow_regime_switch(e);
  if (name == kWave) return wave_resonance(e);
  const std::string kind = name.substr(0, name.find('['));
  if (kind == "sensor_drift" || kind == "command_drift") {
    return not_expressible(name, "a reduced model fitted to the whole record has no time-varying term for it");
  }
  const std::string absorbed = kind == "sensor_delay" || kind == "command_delay"  ? "the delay L"
                               : kind == "sensor_offset" || kind == "level_datum" ? "the operating point y0"
                                                                                   : "the gain and time constant";
  return not_expressible(name, "a reduced model absorbs it into " + absorbed + " (not identifiable)");
}

std::vector<RecordingResiduals> residual_sets(const ModelEngine& e, const Predictions& p) {
  std::vector<RecordingResiduals> out;
  for (std::size_t i = 0; i < e.data().size(); ++i) {
    const auto& d = e.data()[i];
    const std::size_t warm = e.splits()[i].warm;
    auto tail = [warm](const std::vector<double>& v) {
      return v.empty() ? v : std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(warm), v.end());
    };
    RecordingResiduals r;
    r.name = d.source;
    r.operating_point_mm = d.u0_mm;
    r.period_s = d.h;
    r.t = tail(d.t_s);
    for (double& t : r.t) t -= d.t_s.front();
    r.u = tail(d.u_mm);
    r.level = tail(d.y_dwe_mm);
    r.regime = tail(e.regimes()[i]);
    r.primary = columns::level_downstream_end;
    std::vector<double> res(r.level.size());
    const auto model = tail(p[i]);
    for (std::size_t k = 0; k < res.size(); ++k) res[k] = r.level[k] - model[k];
    r.residuals[r.primary] = std::move(res);
    r.nrmse_percent = reduced::nrmse_percent(model, r.level);
    out.push_back(std::move(r));
  }
  return out;
}

// The reduced-model half of the pipeline (pipeline.hpp).
class ModelExplainer final : public Explainer {
 public:
  ModelExplainer(const std::vector<Recording>& recordings, const ModelDiagnoseOptions& options)
      : engine_(recordings, options) {}

  std::vector<RecordingResiduals> nominal_residuals() override {
    engine_.fit_nominal();
    return residual_sets(engine_, engine_.nominal_predictions());
  }
  double sensor_resolution() const override { return engine_.options().quantum_mm; }
  EffectResult explain(const std::string& candidate) override { return evaluate(candidate, engine_); }
  std::vector<RecordingResiduals> residuals_with(const std::string& effect) const override {
    return residual_sets(engine_, prediction_with(effect));
  }
  std::vector<RecordingSeries> series_with(const std::string& effect) const override {
    const Predictions& corrected = prediction_with(effect);
    std::vector<RecordingSeries> out;
    for (std::size_t i = 0; i < engine_.data().size(); ++i) {
      const auto& data = engine_.data()[i];
      out.push_back(RecordingSeries{data.source, data.t_s, data.u_mm, data.y_dwe_mm,
                                    engine_.nominal_predictions()[i], corrected[i], engine_.splits()[i].n_fit});
    }
    return out;
  }

 private:
  const Predictions& prediction_with(const std::string& effect) const {
    return effect.empty() ? engine_.nominal_predictions() : engine_.predictions_of(effect);
  }
  ModelEngine engine_;
};

}  // namespace

std::vector<std::string> model_effect_names() {
  std::vector<std::string> names;
  // A reduced model predicts y_dwe_mm alone: the catalog's per-channel effects on that channel.
  for (const Effect& e : effects_for({columns::level_downstream_end})) names.push_back(e.name());
  names.emplace_back(kUpstream);
  names.emplace_back(kRegime);
  names.emplace_back(kWave);
  return names;
}

Status ModelDiagnoseOptions::validate() const {
  Validator check;
  check.require(fit_fraction > 0.1 && fit_fraction < 0.9, "fit_fraction", fit_fraction, "in (0.1, 0.9)");
  check.require(min_score > 0.0 && min_score < 1.0, "min_score", min_score, "in (0, 1)");
  check.require(min_bic_gain >= 0.0, "min_bic_gain", min_bic_gain, ">= 0");
  check.require(none_noise_factor > 0.0, "none_noise_factor", none_noise_factor, "> 0");
  check.require(warmup_s >= 0.0, "warmup_s", warmup_s, ">= 0");
  check.require(quantum_mm >= 0.0, "quantum_mm", quantum_mm, ">= 0");
  check.require(gate_speed_mm_s >= 0.0, "gate_speed_mm_s", gate_speed_mm_s, ">= 0");
  check.nested("tests", tests.validate());
  check.nested("locate", locate.validate());
  const auto known = model_effect_names();
  std::string names;
  for (const auto& k : known) names += (names.empty() ? "" : ", ") + k;
  for (const auto& c : candidates) {
    check.require(std::find(known.begin(), known.end(), model_effect_name(c)) != known.end(), "candidates",
                  "unknown effect '" + c + "' (expected one of " + names + ")");
  }
  return check.status();
}

std::string model_effect_name(const std::string& name) {
  const EffectKind* kind = kind_named(name);
  return kind && kind->scope == Scope::each_level_channel ? name + "[" + columns::level_downstream_end + "]" : name;
}

ModeResponse damped_mode_response(const std::vector<double>& x, double h, double frequency_hz, double damping) {
  const double w = 2.0 * std::numbers::pi * frequency_hz;
  // Augmented exponential exp([[A, B], [0, 0]] h) gives Φ = e^{Ah} and Γ = ∫₀ʰ e^{Aτ} dτ B.
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  M(0, 1) = 1.0;
  M(1, 0) = -w * w;
  M(1, 1) = -2.0 * damping * w;
  M(1, 2) = w * w;
  const Eigen::Matrix3d E = (M * h).exp();
  const Eigen::Matrix2d Phi = E.topLeftCorner<2, 2>();
  const Eigen::Vector2d Gamma = E.topRightCorner<2, 1>();
  ModeResponse r;
  r.low_pass.resize(x.size());
  r.band_pass.resize(x.size());
  Eigen::Vector2d s = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < x.size(); ++k) {
    r.low_pass[k] = s[0];
    r.band_pass[k] = 2.0 * damping / w * s[1];
    s = Phi * s + Gamma * x[k];
  }
  return r;
}

Diagnosis diagnose_model(const std::vector<Recording>& recordings, const ModelDiagnoseOptions& options) {
  if (const Status status = options.validate(); !status) throw InputError("diagnose --model: " + status.message());
  if (recordings.empty()) throw InputError("diagnose --model: no recordings");
  std::vector<std::string> candidates = options.candidates.empty() ? model_effect_names() : options.candidates;
  for (auto& c : candidates) c = model_effect_name(c);
  ModelExplainer explainer(recordings, options);  // throws InputError naming a recording it cannot use
  PipelineSettings settings;
  settings.none_noise_factor = options.none_noise_factor;
  settings.tests = options.tests;
  settings.locate = options.locate;
  settings.progress = options.progress;
  return run_pipeline(explainer, candidates, settings);
}

}  // namespace canalsim::diagnosis
