#include "reduced_models/models.hpp"

#include "core/format.hpp"

#include "core/laws.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/recording.hpp"
#include "reduced_models/zoh.hpp"

namespace canalsim::reduced {
namespace {


double mean_free_head(const ExperimentData& d) {
  double s = 0.0;
  for (double v : d.y_up_mm) s += v;
  return d.y_up_mm.empty() ? 0.0 : s / static_cast<double>(d.y_up_mm.size());
}

double mean_submerged_head(const ExperimentData& d) {
  if (d.y_up_mm.empty()) return 0.0;
  double s = 0.0;
  for (std::size_t k = 0; k < d.size(); ++k) s += std::max(d.y_up_mm[k] - d.y_dwe_mm[k], 0.0);
  return s / static_cast<double>(d.size());
}

bool uses_submerged_head(ModelKind kind) {
  return kind == ModelKind::nliom_s || kind == ModelKind::nlfom_s;
}

}  // namespace

std::string model_name(ModelKind kind) {
  switch (kind) {
    case ModelKind::liom: return "liom";
    case ModelKind::sopd: return "sopd";
    case ModelKind::lfom: return "lfom";
    case ModelKind::nliom_f: return "nliom-f";
    case ModelKind::nlfom_f: return "nlfom-f";
    case ModelKind::nliom_s: return "nliom-s";
    case ModelKind::nlfom_s: return "nlfom-s";
    case ModelKind::hybrid: return "hybrid";
    case ModelKind::id: return "id";
    case ModelKind::idz: return "idz";
  }
  return "?";
}

std::vector<ModelKind> all_model_kinds() {
  return {ModelKind::liom,    ModelKind::sopd,    ModelKind::lfom,    ModelKind::nliom_f,
          ModelKind::nlfom_f, ModelKind::nliom_s, ModelKind::nlfom_s, ModelKind::hybrid,
          ModelKind::id,      ModelKind::idz};
}

std::optional<ModelKind> parse_model_kind(const std::string& name) {
  std::string key;
  for (char ch : name) {
    key += ch == '_' ? '-' : static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  }
  for (auto kind : all_model_kinds()) {
    if (model_name(kind) == key) return kind;
  }
  return std::nullopt;
}

ModelKind require_model_kind(const std::string& name, const std::string& option) {
  if (const auto kind = parse_model_kind(name)) return *kind;
  std::string expected;
  for (auto kind : all_model_kinds()) expected += (expected.empty() ? "" : ", ") + model_name(kind);
  throw InputError(option + " " + name + ": unknown model (expected " + expected + ")");
}

bool is_fractional(ModelKind kind) {
  return kind == ModelKind::lfom || kind == ModelKind::nlfom_f || kind == ModelKind::nlfom_s ||
         kind == ModelKind::hybrid;
}
bool uses_upstream_level(ModelKind kind) {
  return !(kind == ModelKind::liom || kind == ModelKind::sopd || kind == ModelKind::lfom ||
           is_integrating(kind));
}
bool is_integrating(ModelKind kind) { return kind == ModelKind::id || kind == ModelKind::idz; }
bool uses_gamma(ModelKind kind) { return uses_upstream_level(kind); }
bool is_linear_time_invariant(ModelKind kind) { return !uses_upstream_level(kind); }

Status Actuation::validate() const {
  return Validator()
      .require(gate_speed_mm_s >= 0.0 && std::isfinite(gate_speed_mm_s), "gate_speed_mm_s", gate_speed_mm_s,
               ">= 0 (0 = off)")
      .require(quantum_mm >= 0.0 && std::isfinite(quantum_mm), "quantum_mm", quantum_mm, ">= 0 (0 = off)")
      .status();
}

std::vector<std::string> parameter_names(ModelKind kind) {
  switch (kind) {
    case ModelKind::liom: return {"K", "T", "L"};
    case ModelKind::sopd: return {"K", "T", "T2", "L"};
    case ModelKind::lfom: return {"K", "T", "lambda", "L"};
    case ModelKind::nliom_f:
    case ModelKind::nliom_s: return {"K", "T", "gamma", "L"};
    case ModelKind::nlfom_f:
    case ModelKind::nlfom_s: return {"K", "T", "lambda", "gamma", "L"};
    case ModelKind::hybrid: return {"K", "T", "lambda", "gamma", "L", "K_sub", "gamma_sub"};
    case ModelKind::id: return {"K", "L"};
    case ModelKind::idz: return {"K", "Tz", "L"};
  }
  return {};
}

double get_parameter(const ModelParameters& p, const std::string& name) {
  if (name == "K") return p.K;
  if (name == "T") return p.T;
  if (name == "T2") return p.T2;
  if (name == "lambda") return p.lambda;
  if (name == "gamma") return p.gamma;
  if (name == "L") return p.L;
  if (name == "K_sub") return p.K_sub;
  if (name == "gamma_sub") return p.gamma_sub;
  if (name == "Tz") return p.Tz;
  throw std::invalid_argument("unknown model parameter '" + name + "'");
}

void set_parameter(ModelParameters& p, const std::string& name, double value) {
  if (name == "K") p.K = value;
  else if (name == "T") p.T = value;
  else if (name == "T2") p.T2 = value;
  else if (name == "lambda") p.lambda = value;
  else if (name == "gamma") p.gamma = value;
  else if (name == "L") p.L = value;
  else if (name == "K_sub") p.K_sub = value;
  else if (name == "gamma_sub") p.gamma_sub = value;
  else if (name == "Tz") p.Tz = value;
  else throw std::invalid_argument("unknown model parameter '" + name + "'");
}

Status validate(const Model& model) {
  const auto& p = model.p;
  Validator check;
  for (const auto& name : parameter_names(model.kind)) {
    const double value = get_parameter(p, name);
    check.require(std::isfinite(value), "p." + name, value, "a finite value");
  }
  return check.require(p.T >= 0.0, "p.T", p.T, ">= 0 s")
      .require(model.kind != ModelKind::sopd || p.T2 >= 0.0, "p.T2", p.T2, ">= 0 s")
      .require(!is_fractional(model.kind) || p.lambda > 0.0, "p.lambda", p.lambda, "> 0")
      .require(p.L >= 0.0, "p.L", p.L, ">= 0 s")
      .require(model.kind != ModelKind::idz || p.Tz >= 0.0, "p.Tz", p.Tz, ">= 0 s")
      .require(p.head_ref_mm >= 0.0, "p.head_ref_mm", p.head_ref_mm, ">= 0 (0 = from data)")
      .require(p.head_ref_sub_mm >= 0.0, "p.head_ref_sub_mm", p.head_ref_sub_mm, ">= 0")
      .nested("actuation", model.actuation.validate())
      .status();
}

double free_flow_limit_mm(double y_dwe_mm, double x_up_mm) { return laws::free_flow_limit_level(y_dwe_mm, x_up_mm); }

bool is_free_flow(double y_up_mm, double y_dwe_mm, double x_up_mm) {
  return y_up_mm > free_flow_limit_mm(y_dwe_mm, x_up_mm);
}

std::vector<double> rate_limit(const std::vector<double>& u_mm, double h, double speed_mm_s) {
  std::vector<double> x(u_mm.size());
  if (u_mm.empty()) return x;
  if (speed_mm_s <= 0.0) return u_mm;
  const double step = speed_mm_s * h;
  x[0] = u_mm[0];
  for (std::size_t k = 1; k < u_mm.size(); ++k) {
    x[k] = laws::rate_limited_move(x[k - 1], u_mm[k], step);
  }
  return x;
}

double quantise(double y, double r) { return laws::quantise(y, r); }

void set_head_references(Model& model, const std::vector<const ExperimentData*>& data) {
  if (!uses_upstream_level(model.kind)) return;
  auto mean_over = [&](double (*head)(const ExperimentData&)) {
    double s = 0.0;
    std::size_t n = 0;
    for (const auto* d : data) {
      if (!d->has_upstream_level()) continue;
      s += head(*d) * static_cast<double>(d->size());
      n += d->size();
    }
    return n ? s / static_cast<double>(n) : 0.0;
  };
  const bool submerged = uses_submerged_head(model.kind);
  if (model.p.head_ref_mm == 0.0) {
    model.p.head_ref_mm = mean_over(submerged ? mean_submerged_head : mean_free_head);
  }
  if (model.kind == ModelKind::hybrid && model.p.head_ref_sub_mm == 0.0) {
    model.p.head_ref_sub_mm = mean_over(mean_submerged_head);
  }
  // A zero mean head (e.g. y_up below y_dwe throughout) would divide by zero: use 1 mm.
  if (model.p.head_ref_mm <= 0.0) model.p.head_ref_mm = 1.0;
  if (model.kind == ModelKind::hybrid && model.p.head_ref_sub_mm <= 0.0) model.p.head_ref_sub_mm = 1.0;
}

double paper_gain(const Model& model) {
  if (!uses_gamma(model.kind)) return model.p.K;
  return model.p.K / std::pow(model.p.head_ref_mm, model.p.gamma);
}

void fractional_delay(const std::vector<double>& x, double delay_samples, std::vector<double>& out) {
  blended_delay(x, delay_samples, delay_samples - std::floor(delay_samples), out);
}

void blended_delay(const std::vector<double>& x, double delay_samples, double frac,
                   std::vector<double>& out) {
  const std::size_t n = x.size();
  out.assign(n, 0.0);
  const auto d = static_cast<std::ptrdiff_t>(std::floor(delay_samples));
  // out[k] = (1 − frac) x[k − d] + frac x[k − d − 1]
  for (std::size_t k = 0; k < n; ++k) {
    const std::ptrdiff_t i = static_cast<std::ptrdiff_t>(k) - d;
    double v = 0.0;
    if (i >= 0 && i < static_cast<std::ptrdiff_t>(n)) v += (1.0 - frac) * x[static_cast<std::size_t>(i)];
    if (i - 1 >= 0 && i - 1 < static_cast<std::ptrdiff_t>(n)) v += frac * x[static_cast<std::size_t>(i - 1)];
    out[k] = v;
  }
}

std::vector<double> input_deviation(const ExperimentData& data, const Actuation& actuation) {
  std::vector<double> du = rate_limit(data.u_mm, data.h, actuation.gate_speed_mm_s);
  for (double& v : du) v -= data.u0_mm;
  return du;
}

bool is_integer_order(const Model& model) {
  return !is_fractional(model.kind) || model.p.lambda == 1.0;
}

std::optional<double> delay_interpolation_weight(const Model& model, double h, double frac) {
  if (is_integrating(model.kind)) return frac;
  if (model.kind == ModelKind::sopd || !is_linear_time_invariant(model.kind)) return std::nullopt;
  return is_integer_order(model) ? zoh_delay_weight(model.p.T, h, frac) : frac;
}

std::vector<double> delayed_input(const ExperimentData& data, const Actuation& actuation, double L) {
  const std::vector<double> du = input_deviation(data, actuation);
  std::vector<double> out;
  fractional_delay(du, L / data.h, out);
  return out;
}

SimulationResult simulate(const Model& model_in, const ExperimentData& data,
                          const SimulationOptions& options) {
  if (const Status status = validate(model_in); !status) {
    throw std::invalid_argument("simulate " + model_name(model_in.kind) + ": " + status.message());
  }
  if (const Status status = options.validate(); !status) {
    throw std::invalid_argument("simulation options: " + status.message());
  }
  Model model = model_in;
  const ModelKind kind = model.kind;
  if (uses_upstream_level(kind)) {
    require_upstream_level(data, model_name(kind));
    set_head_references(model, {&data});
  }
  const auto& p = model.p;
  const std::size_t n = data.size();
  const double h = data.h;
  SimulationResult result;
  std::vector<double> x(n, 0.0);
  const double y0 = data.y0_mm;
  // The gain of the input term over interval k, given the model's deviation x_k at its start.
  IntervalGain gain = [&](std::size_t, double) { return p.K; };
  switch (kind) {
    case ModelKind::nliom_f:
    case ModelKind::nlfom_f:
      gain = [&](std::size_t k, double) {
        return p.K * std::pow(std::max(data.y_up_mm[k], 0.0) / p.head_ref_mm, p.gamma);
      };
      break;
    case ModelKind::nliom_s:
    case ModelKind::nlfom_s:
      gain = [&](std::size_t k, double x_k) {
        const double head = std::max(data.y_up_mm[k] - (y0 + x_k), 0.0);
        return p.K * std::pow(head / p.head_ref_mm, p.gamma);
      };
      break;
    case ModelKind::hybrid: {
      std::vector<double> gate;
      if (model.actuation.gate_speed_mm_s > 0.0 || data.x_up_mm.empty()) {
        gate = rate_limit(data.u_mm, h, model.actuation.gate_speed_mm_s);
      } else {
        gate = data.x_up_mm;
      }
      result.regime.assign(n, 0);
      gain = [&, gate = std::move(gate)](std::size_t k, double x_k) {
        const double y_dwe = y0 + x_k, y_up = data.y_up_mm[k];
        const bool free = is_free_flow(y_up, y_dwe, gate[k]);
        result.regime[k] = free ? 1 : 0;
        if (free) return p.K * std::pow(std::max(y_up, 0.0) / p.head_ref_mm, p.gamma);
        return p.K_sub * std::pow(std::max(y_up - y_dwe, 0.0) / p.head_ref_sub_mm, p.gamma_sub);
      };
      break;
    }
    default: break;
  }

  if (is_integrating(kind)) {
    // Rectangle rule on the held input: exact for a command held between samples (a delayed
    // step gives the sampled ramp K A (t − t_step − L) exactly, for any fractional L). IDZ adds
    // the direct gain K·Tz of its zero (ID: Tz = 0).
    const auto dud = delayed_input(data, model.actuation, p.L);
    const double Tz = kind == ModelKind::idz ? p.Tz : 0.0;
    double integral = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      if (k > 0) integral += h * dud[k - 1];
      x[k] = p.K * (integral + Tz * dud[k]);
    }
  } else if (is_integer_order(model)) {
    const std::vector<double> du = input_deviation(data, model.actuation);
    const DelayedHold input(du, p.L / h);
    if (kind == ModelKind::sopd) {
      solve_zoh_two_lags(input, p.T, p.T2, h, x.data());
    } else if (is_linear_time_invariant(kind)) {
      solve_zoh_lag(input, p.T, h, nullptr, x.data());
    } else {
      solve_zoh_lag(input, p.T, h, &gain, x.data());
    }
    if (is_linear_time_invariant(kind)) {
      for (double& v : x) v *= p.K;
    }
  } else {
    // Grünwald–Letnikov (gl.hpp). Its step k integrates over [t_k, t_{k+1}] with the input's
    // mean over that interval (for the held, delayed command: the linear interpolation of the
    // samples, delayed_input) and its x_k approximates the level at t_{k+1}: the level at t_k is
    // x_{k−1}, where the submerged models and the hybrid read their own level.
    const auto dud = delayed_input(data, model.actuation, p.L);
    std::vector<double> xs(n, 0.0);
    const OnlineForcing f = [&](std::size_t k, const double* xg) {
      return gain(k, k > 0 ? xg[k - 1] : 0.0) * dud[k];
    };
    solve_fractional_lag(n, p.T, p.lambda, h, options.gl, f, xs.data());
    for (std::size_t k = 1; k < n; ++k) x[k] = xs[k - 1];
  }
  result.y_dwe_mm.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    result.y_dwe_mm[k] = quantise(y0 + x[k], model.actuation.quantum_mm);
  }
  return result;
}

}  // namespace canalsim::reduced
