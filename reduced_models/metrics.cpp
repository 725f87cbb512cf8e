#include "reduced_models/metrics.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace canalsim::reduced {
namespace {

void check(const std::vector<double>& a, const std::vector<double>& b, const char* what) {
  if (a.size() != b.size() || a.empty()) {
    throw std::invalid_argument(std::string(what) + ": model has " + std::to_string(a.size()) +
                                " samples, data " + std::to_string(b.size()));
  }
}

}  // namespace

double nrmse_percent(const std::vector<double>& model, const std::vector<double>& data) {
  check(model, data, "nrmse_percent");
  double mean = 0.0;
  for (double v : data) mean += v;
  mean /= static_cast<double>(data.size());
  double num = 0.0, den = 0.0;
  for (std::size_t k = 0; k < data.size(); ++k) {
    num += (model[k] - data[k]) * (model[k] - data[k]);
    den += (data[k] - mean) * (data[k] - mean);
  }
  if (den == 0.0) return num == 0.0 ? 100.0 : -std::numeric_limits<double>::infinity();
  return 100.0 * (1.0 - std::sqrt(num / den));
}

double iae(const std::vector<double>& model, const std::vector<double>& data, double h) {
  check(model, data, "iae");
  double s = 0.0;
  for (std::size_t k = 0; k < data.size(); ++k) s += std::abs(model[k] - data[k]);
  return s * h;
}

double iae_combined(const std::vector<std::vector<double>>& models,
                    const std::vector<std::vector<double>>& data, const std::vector<double>& h) {
  if (models.size() != data.size() || data.size() != h.size()) {
    throw std::invalid_argument("iae_combined: models, data and h differ in count");
  }
  double s = 0.0;
  for (std::size_t j = 0; j < data.size(); ++j) s += iae(models[j], data[j], h[j]);
  return s;
}

double uncertainty_index(const std::vector<double>& p_j, double p_c) {
  double worst = 0.0;
  for (double p : p_j) {
    const double d = std::abs(p - p_c);
    if (d == 0.0) continue;
    if (p_c == 0.0) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, d / std::abs(p_c));
  }
  return worst;
}

std::map<std::string, double> uncertainty_indices(const std::vector<Model>& per_recording,
                                                  const Model& nominal) {
  std::map<std::string, double> out;
  for (const auto& name : parameter_names(nominal.kind)) {
    std::vector<double> values;
    for (const auto& m : per_recording) values.push_back(get_parameter(m.p, name));
    out[name] = uncertainty_index(values, get_parameter(nominal.p, name));
  }
  return out;
}

}  // namespace canalsim::reduced
