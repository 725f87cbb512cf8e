// Stage 1 of a fit (identification.hpp): the delay search of the linear counterpart model.
#include <algorithm>
#include <cmath>

#include "reduced_models/fit_problem.hpp"

namespace canalsim::reduced::detail {

Model Problem::delay_grid() {
  std::vector<double> Ts, lambdas{1.0};
  const auto& Tspec = options_.bounds.T;
  if (Tspec.fixed) Ts = {*Tspec.initial};
  else if (Tspec.initial) Ts = {*Tspec.initial};
  else for (double T : {0.3, 1.0, 3.0}) Ts.push_back(std::clamp(T, Tspec.lower, Tspec.upper));
  if (is_fractional(kind_)) {
    const auto& ls = options_.bounds.lambda;
    if (ls.fixed || ls.initial) lambdas = {*ls.initial};
    else lambdas = {std::clamp(0.5, ls.lower, ls.upper), std::clamp(0.9, ls.lower, ls.upper)};
  }
  const auto& Lspec = options_.bounds.L;
  const double h0 = data_.front()->h;
  Model best = base_;
  double best_cost = kInf;
  for (double T : Ts) {
    for (double lambda : lambdas) {
      Model m = base_;
      m.p.K = 1.0;
      m.p.T = T;
      m.p.lambda = lambda;
      if (kind_ == ModelKind::sopd) {
        const auto& t2 = options_.bounds.T2;
        m.p.T2 = t2.initial ? *t2.initial : std::clamp(T / 3.0, t2.lower, t2.upper);
      }
      m.p.L = Lspec.fixed ? *Lspec.initial : 0.0;
      m.actuation.quantum_mm = 0.0;
      std::vector<std::vector<double>> g;
      for (const auto* d : data_) {
        auto y = simulate(m, *d, options_.simulation).y_dwe_mm;
        ++simulations_;
        for (double& v : y) v -= d->y0_mm;
        g.push_back(std::move(y));
      }
      ++evaluations_;
      long first = static_cast<long>(std::ceil(Lspec.lower / h0 - 1e-9));
      long last = static_cast<long>(std::floor(Lspec.upper / h0 + 1e-9));
      if (Lspec.fixed) first = last = 0;
      for (long shift = first; shift <= last; ++shift) {
        double gr = 0.0, gg = 0.0;
        for (std::size_t j = 0; j < data_.size(); ++j) {
          const auto s = static_cast<std::size_t>(std::lround(static_cast<double>(shift) * h0 / data_[j]->h));
          const auto& gj = g[j];
          const auto& rj = residual_[j];
          for (std::size_t k = s; k < gj.size(); ++k) {
            gr += gj[k - s] * rj[k];
            gg += gj[k - s] * gj[k - s];
          }
        }
        if (gg == 0.0) continue;
        const double K = std::clamp(gr / gg, options_.bounds.K.lower, options_.bounds.K.upper);
        double total = 0.0;
        for (std::size_t j = 0; j < data_.size(); ++j) {
          const auto s = static_cast<std::size_t>(std::lround(static_cast<double>(shift) * h0 / data_[j]->h));
          const auto& gj = g[j];
          const auto& rj = residual_[j];
          double acc = 0.0;
          for (std::size_t k = 0; k < gj.size(); ++k) {
            acc += std::abs((k >= s ? K * gj[k - s] : 0.0) - rj[k]);
          }
          total += acc * data_[j]->h;
        }
        if (total < best_cost) {
          best_cost = total;
          best = m;
          best.p.K = K;
          best.p.L = Lspec.fixed ? *Lspec.initial : static_cast<double>(shift) * h0;
        }
      }
    }
  }
  best.actuation = base_.actuation;
  return best;
}

}  // namespace canalsim::reduced::detail
