// The γ grid and sweep of identification.hpp (the paper's Figures 8 and 10).
#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "core/format.hpp"
#include "core/parallel.hpp"
#include "reduced_models/fit_problem.hpp"

namespace canalsim::reduced {

std::vector<double> GammaGrid::values() const {
  std::vector<double> out;
  const auto count = static_cast<std::size_t>(std::floor((last - first) / step + 1e-9)) + 1;
  for (std::size_t i = 0; i < count; ++i) out.push_back(first + static_cast<double>(i) * step);
  return out;
}

Status GammaGrid::validate() const {
  return Validator()
      .require(std::isfinite(first), "first", first, "a finite value")
      .require(std::isfinite(last), "last", last, "a finite value")
      .require(std::isfinite(step) && step > 0.0, "step", step, "a finite value > 0")
      .require(last >= first, "last", last, ">= first = " + format_g(first))
      .require(last - first <= 1e5 * step, "step", step, "a step giving at most 100000 values")
      .status();
}

GammaGrid GammaGrid::parse(const std::string& text) {
  GammaGrid g;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> g.first >> c1 >> g.last >> c2 >> g.step) || c1 != ':' || c2 != ':' ||
      !(in >> std::ws).eof()) {
    throw InputError("--gamma '" + text + "': expected first:last:step, e.g. 0:10:0.05");
  }
  if (const Status status = g.validate(); !status) throw InputError("--gamma '" + text + "': " + status.message());
  return g;
}

GammaSweep gamma_sweep(ModelKind kind, const std::vector<ExperimentData>& data,
                       const FitOptions& options, const GammaGrid& grid) {
  if (!uses_gamma(kind)) {
    throw InputError("gamma sweep: model " + model_name(kind) + " has no gamma parameter");
  }
  if (const Status status = grid.validate(); !status) throw InputError("gamma grid: " + status.message());
  if (const Status status = options.validate(); !status) throw InputError("fit options: " + status.message());
  GammaSweep sweep;
  sweep.gamma = grid.values();
  const std::size_t n = sweep.gamma.size();
  sweep.nrmse.assign(n, 0.0);
  sweep.iae.assign(n, 0.0);
  std::vector<FitResult> fits(n);
  // The grid is cut into one contiguous chunk per thread; inside a chunk each fit warm-starts
  // from its neighbour's, so the results depend on the thread count but not on scheduling.
  const std::size_t chunks = std::max<std::size_t>(1, std::min<std::size_t>(options.threads, n));
  ProgressCounter progress(options.progress, n);
  parallel_for(chunks, static_cast<int>(chunks), [&](std::size_t chunk) {
    const std::size_t begin = n * chunk / chunks, end = n * (chunk + 1) / chunks;
    std::optional<Model> previous;
    for (std::size_t i = begin; i < end; ++i) {
      FitOptions o = options;
      o.threads = 1;
      o.progress = nullptr;  // the sweep reports each γ done (below), not the stages of its fits
      o.bounds.gamma = {std::min(o.bounds.gamma.lower, sweep.gamma[i]),
                        std::max(o.bounds.gamma.upper, sweep.gamma[i]), sweep.gamma[i], true};
      if (kind == ModelKind::hybrid) o.bounds.gamma_sub = o.bounds.gamma;
      if (!previous) {
        fits[i] = fit_nominal(kind, data, o);
      } else {
        Model start = *previous;
        start.p.gamma = sweep.gamma[i];
        if (kind == ModelKind::hybrid) start.p.gamma_sub = sweep.gamma[i];
        // Neighbouring γ: polish the previous fit (small steps, one optimiser run).
        fits[i] = detail::refit_impl(start, detail::pointers(data), o, 0.2, 0);
      }
      previous = fits[i].model;
      progress.finished("γ values of the " + model_name(kind) + " sweep");
    }
  });
  for (std::size_t i = 0; i < n; ++i) {
    double mean = 0.0;
    for (double v : fits[i].nrmse) mean += v;
    sweep.nrmse[i] = mean / static_cast<double>(fits[i].nrmse.size());
    sweep.iae[i] = fits[i].iae_total;
    if (sweep.nrmse[i] > sweep.nrmse[sweep.best]) sweep.best = i;
  }
  sweep.best_fit = fits[sweep.best];
  // The fits polished from a neighbour (IAE, no offsets) leave their statistics to the best one.
  if (sweep.best_fit.std.empty()) {
    FitOptions o = options;
    o.bounds.gamma = {sweep.gamma[sweep.best], sweep.gamma[sweep.best], sweep.gamma[sweep.best], true};
    if (kind == ModelKind::hybrid) o.bounds.gamma_sub = o.bounds.gamma;
    detail::add_fit_statistics(sweep.best_fit, detail::pointers(data), o, false, nullptr);
  }
  return sweep;
}

}  // namespace canalsim::reduced
