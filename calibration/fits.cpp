#include "calibration/fits.hpp"

#include <cmath>
#include <numeric>

namespace canalsim::calibration {
namespace {

// Paper eq. (19): 100 (1 - ||y - ŷ|| / ||y - mean(y)||).
double nrmse_percent(const std::vector<double>& data, const std::vector<double>& model) {
  const double mean = std::accumulate(data.begin(), data.end(), 0.0) / static_cast<double>(std::max<std::size_t>(data.size(), 1));
  double e = 0.0, v = 0.0;
  for (std::size_t k = 0; k < data.size(); ++k) {
    e += (data[k] - model[k]) * (data[k] - model[k]);
    v += (data[k] - mean) * (data[k] - mean);
  }
  return v > 0.0 ? 100.0 * (1.0 - std::sqrt(e / v)) : 0.0;
}

double rms(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) s += (a[k] - b[k]) * (a[k] - b[k]);
  return a.empty() ? 0.0 : std::sqrt(s / static_cast<double>(a.size()));
}

// Calls f(recorded channel, its name, recording name, prediction) for every compared channel.
template <typename F>
void for_each_compared(const ReplayProblem& problem, const std::vector<Channels>& prediction, F f) {
  for (std::size_t i = 0; i < problem.replays().size(); ++i) {
    const Replay& r = problem.replays()[i];
    for (const auto& [channel, y] : r.data) {
      if (!prediction[i].count(channel) || !problem.weights().weight.count(channel)) continue;
      f(r, channel, y, i);
    }
  }
}

}  // namespace

void add_fits(const ReplayProblem& problem, const std::vector<Channels>& before, const std::vector<Channels>& after,
              bool validation, Calibration& c) {
  for_each_compared(problem, after, [&](const Replay& r, const std::string& channel, const std::vector<double>& y, std::size_t i) {
    if (!before[i].count(channel)) return;
    const auto& b = before[i].at(channel);
    const auto& a = after[i].at(channel);
    c.fits.push_back({r.name, channel, validation, rms(y, b), rms(y, a), nrmse_percent(y, b), nrmse_percent(y, a)});
    const auto regime = after[i].find(columns::regime);
    c.series.push_back({r.name, channel, validation, r.t, y, b, a, r.u,
                        regime == after[i].end() ? std::vector<double>{} : regime->second});
  });
}

void restate_fits(const ReplayProblem& problem, const std::vector<Channels>& prediction, bool validation, FitSide side,
                  Calibration& c) {
  for_each_compared(problem, prediction, [&](const Replay& r, const std::string& channel, const std::vector<double>& y, std::size_t i) {
    const auto& m = prediction[i].at(channel);
    for (ChannelFit& f : c.fits) {
      if (f.recording != r.name || f.channel != channel || f.validation != validation) continue;
      (side == FitSide::before ? f.rms_before : f.rms_after) = rms(y, m);
      (side == FitSide::before ? f.nrmse_before : f.nrmse_after) = nrmse_percent(y, m);
    }
    for (Series& s : c.series) {
      if (s.recording != r.name || s.channel != channel || s.validation != validation) continue;
      (side == FitSide::before ? s.nominal : s.calibrated) = m;
    }
  });
}

}  // namespace canalsim::calibration
