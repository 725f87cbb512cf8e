#include "cli/freq_check.hpp"

#include <cmath>
#include <complex>
#include <iostream>
#include <numeric>

#include "core/errors.hpp"
#include "core/format.hpp"
#include "core/recording.hpp"
#include "linearize/linearize.hpp"
#include "reduced_models/frequency.hpp"

namespace canalsim::cli {

std::vector<const scenarios::ExperimentSpec*> freq_check_experiments(const scenarios::Scenario& s,
                                                                      const std::vector<std::string>& recordings) {
  std::vector<const scenarios::ExperimentSpec*> experiments;
  for (const auto& file : recordings) {
    const std::string name = read_recording(file).meta("experiment");
    if (name.empty()) {
      throw InputError("--freq-check: " + file +
                       " names no experiment (no '# experiment:' metadata); expected a recording written by "
                       "`canalsim simulate` from scenario '" + s.name + "'");
    }
    const auto* e = s.find_experiment(name);
    if (!e) throw InputError("--freq-check: " + file + " comes from experiment '" + name + "', which scenario '" + s.name + "' does not have");
    experiments.push_back(e);
  }
  return experiments;
}

nlohmann::json print_freq_check(const scenarios::Scenario& s, const std::vector<const scenarios::ExperimentSpec*>& experiments,
                                const std::vector<reduced::FitResult>& fits, const std::vector<reduced::ExperimentData>& data) {
  nlohmann::json out = nlohmann::json::array();
  std::cout << "\nfrequency check against the linearised pool (gate -> y_dwe, docs/linearization.md):\n"
            << "  recording               band [rad/s]       model vs PDE rms   PDE band LFOM: lambda  rms    (lambda=1)\n";
  for (std::size_t j = 0; j < fits.size(); ++j) {
    const auto& e = *experiments[j];
    const linearize::FrequencyResponse pde = linearize::linearize(s, e, {});
    // The band: the PRBS's (as fitted by linearize), else from the recording's length and sampling.
    linearize::Band band = pde.band ? *pde.band : linearize::Band{2.0 * M_PI / data[j].duration(), M_PI / data[j].h};
    band.high = std::min(band.high, pde.system.nyquist);
    const std::vector<double> omega = linearize::log_grid({band.low, band.high, 200});
    const auto g = linearize::frequency_response(pde.system, omega);
    const auto& d = data[j];
    const double y_up = d.y_up_mm.empty() ? 0.0 : std::accumulate(d.y_up_mm.begin(), d.y_up_mm.end(), 0.0) / static_cast<double>(d.y_up_mm.size());
    const reduced::OperatingPoint point{d.u0_mm, d.y0_mm, y_up};
    double sum = 0.0;
    for (std::size_t k = 0; k < omega.size(); ++k) {
      sum += std::norm(reduced::frequency_response(fits[j].model, point, omega[k]) / g[k] - 1.0);
    }
    const double rms = std::sqrt(sum / static_cast<double>(omega.size()));
    const auto fit = linearize::fit_fractional_order(omega, g, band, linearize::delay_from_phase(omega, g));
    char line[256];
    std::snprintf(line, sizeof line, "  %-22s  %7.4g-%-8.4g  %8.1f %%          %6.3f   %6.1f %%  (%5.1f %%)\n",
                  fits[j].sources.front().substr(0, 22).c_str(), band.low, band.high, 100.0 * rms, fit.order,
                  100.0 * fit.rms_relative_error, 100.0 * fit.integer_rms_relative_error);
    std::cout << line;
    out.push_back({{"source", fits[j].sources.front()}, {"experiment", e.name},
                   {"band_rad_s", {band.low, band.high}}, {"model_vs_pde_rms_relative_error", rms},
                   {"pde_band_lfom", {{"K", fit.gain}, {"T", fit.time}, {"lambda", fit.order}, {"L_s", fit.delay},
                                      {"rms_relative_error", fit.rms_relative_error},
                                      {"lambda1_rms_relative_error", fit.integer_rms_relative_error}}}});
  }
  return out;
}

}  // namespace canalsim::cli
