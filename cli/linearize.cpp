// `canalsim linearize SCENARIO -e EXPERIMENT [--freq LO:HI:N] [--input gate|inflow|offtake:I]
// [--output y_dwe|y_dw|q|y_checkI] [--json F] [--csv F] [--plots-dir DIR]`: the frequency response of the
// linearised canal at the experiment's steady state (docs/linearization.md).
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/checks.hpp"
#include "cli/commands.hpp"
#include "cli/plots_dir.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/format.hpp"
#include "core/json.hpp"
#include "linearize/linearize.hpp"
#include "plot/composites.hpp"
#include "scenarios/builtin.hpp"

namespace canalsim::cli {
namespace {

struct LinearizeArguments {
  std::string scenario, experiment;
  std::string freq, input = "gate", output = "y_dwe";
  std::string json, csv;
  int poles = 6;
  PlotsDirectory plots;
};

std::string csv_text(const linearize::FrequencyResponse& r) {
  std::ostringstream out;
  out << "omega_rad_s,gain,phase_deg,real,imag\n";
  const auto phase = linearize::unwrapped_phase_degrees(r.response);
  for (std::size_t k = 0; k < r.omega.size(); ++k) {
    out << format_g(r.omega[k], 10) << ',' << format_g(std::abs(r.response[k]), 10) << ','
        << format_g(phase[k], 10) << ',' << format_g(r.response[k].real(), 10) << ','
        << format_g(r.response[k].imag(), 10) << '\n';
  }
  return out.str();
}

std::string json_text(const linearize::FrequencyResponse& r, const LinearizeArguments& args) {
  nlohmann::json j;
  j["scenario"] = args.scenario;
  j["experiment"] = args.experiment;
  j["input"] = {{"name", r.input_name}, {"unit", r.input_unit}};
  j["output"] = {{"name", r.output_name}, {"unit", r.output_unit}};
  j["operating_point"] = r.steady_state;
  j["states"] = r.system.A.rows();
  j["nyquist_rad_s"] = r.system.nyquist;
  j["static_gain"] = json_number(r.static_gain);
  j["delay_s"] = r.delay_s;
  j["sensor_delay_s"] = r.system.output_delay_s;
  for (const auto& p : r.poles) j["poles"].push_back({{"real", p.real()}, {"imag", p.imag()}});
  if (r.band_fit) {
    const auto& f = *r.band_fit;
    j["prbs_band"] = {{"low_rad_s", r.band->low}, {"high_rad_s", r.band->high}, {"points", f.points},
                      {"lfom", {{"K", f.gain}, {"T", f.time}, {"lambda", f.order}, {"L_s", f.delay},
                                {"rms_relative_error", f.rms_relative_error}}},
                      {"liom_rms_relative_error", f.integer_rms_relative_error}};
  }
  const auto phase = linearize::unwrapped_phase_degrees(r.response);
  for (std::size_t k = 0; k < r.omega.size(); ++k) {
    j["response"].push_back({{"omega_rad_s", r.omega[k]}, {"gain", json_number(std::abs(r.response[k]))},
                             {"phase_deg", phase[k]}, {"real", json_number(r.response[k].real())},
                             {"imag", json_number(r.response[k].imag())}});
  }
  return j.dump(1) + "\n";
}

void print_summary(const linearize::FrequencyResponse& r, const LinearizeArguments& args) {
  std::cout << args.scenario << " / " << args.experiment << ": " << r.output_name << " [" << r.output_unit
            << "] per " << r.input_name << " [" << r.input_unit << "], " << r.system.A.rows() << " states, "
            << r.steady_state << "\n";
  std::cout << "  static gain     " << format_g(r.static_gain) << "\n";
  std::cout << "  delay (phase)   " << format_g(r.delay_s) << " s\n";
  std::cout << "  Nyquist         " << format_g(r.system.nyquist) << " rad/s\n";
  if (r.band_fit) {
    const auto& f = *r.band_fit;
    std::cout << "  PRBS band       " << format_g(r.band->low, 3) << " to " << format_g(r.band->high, 3)
              << " rad/s: LFOM K e^(-Ls)/(T s^lambda + 1) fitted to G: K = " << format_g(f.gain, 4)
              << ", T = " << format_g(f.time, 4) << ", lambda = " << format_fixed(f.order, 3) << ", L = "
              << format_g(f.delay, 4) << " s, rms relative error " << format_fixed(100.0 * f.rms_relative_error, 2)
              << " % (lambda = 1: " << format_fixed(100.0 * f.integer_rms_relative_error, 2) << " %)\n";
  }
  std::cout << "  poles nearest the imaginary axis [1/s]:";
  for (const auto& p : r.poles) std::cout << "  " << format_g(p.real(), 4) << (p.imag() >= 0 ? "+" : "") << format_g(p.imag(), 4) << "i";
  std::cout << "\n  omega [rad/s]      gain    phase [deg]\n";
  const auto phase = linearize::unwrapped_phase_degrees(r.response);
  const std::size_t step = std::max<std::size_t>(1, r.omega.size() / 10);
  for (std::size_t k = 0; k < r.omega.size(); k += step) {
    std::cout << "  " << format_g(r.omega[k], 4) << "  " << format_g(std::abs(r.response[k]), 5) << "  "
              << format_fixed(phase[k], 1) << "\n";
  }
}

// The response as a Bode plot, named for its file: bode_EXPERIMENT_OUTPUT_per_INPUT.
plot::Figure bode_plot(const linearize::FrequencyResponse& r, const LinearizeArguments& args) {
  std::vector<double> gain_db;
  for (const auto& g : r.response) gain_db.push_back(20.0 * std::log10(std::abs(g)));
  std::optional<plot::Window> band;
  if (r.band) band = plot::Window{r.band->low, r.band->high};
  return plot::bode_figure(
      "bode_" + plot::file_stem(args.experiment) + "_" + plot::file_stem(args.output) + "_per_" + plot::file_stem(args.input),
      args.scenario + " / " + args.experiment + ": " + r.output_name + " [" + r.output_unit + "] per " + r.input_name + " [" +
          r.input_unit + "], linearised",
      r.omega, {{"PDE", gain_db, linearize::unwrapped_phase_degrees(r.response), "linearised canal"}}, band);
}

void run(const LinearizeArguments& args) {
  // Every flag is checked before the work.
  linearize::LinearizeOptions options;
  options.input = linearize::parse_input(args.input, "--input");
  options.output = linearize::parse_output(args.output, "--output");
  if (!args.freq.empty()) options.grid = linearize::parse_grid(args.freq, "--freq");
  options.poles = args.poles;
  check_outputs({{"--json", args.json}, {"--csv", args.csv}}, {{"--scenario", args.scenario}});
  args.plots.check();
  const scenarios::Scenario s = scenarios::load_scenario_or_builtin(args.scenario);
  const auto* e = s.find_experiment(args.experiment);
  if (!e) {
    std::string names;
    for (const auto& x : s.experiments) names += (names.empty() ? "" : ", ") + x.name;
    throw InputError("--experiment " + args.experiment + ": scenario '" + s.name + "' has no such experiment (experiments: " + names + ")");
  }
  const linearize::FrequencyResponse r = linearize::linearize(s, *e, options);
  for (const auto& g : r.response) {
    if (!std::isfinite(std::abs(g))) {
      throw InputError("--freq: the grid hits an undamped mode of the linearised canal (G(iω) infinite); move the grid");
    }
  }
  std::vector<FileContents> outputs;  // written together, all or nothing
  if (!args.json.empty()) outputs.emplace_back(args.json, json_text(r, args));
  if (!args.csv.empty()) outputs.emplace_back(args.csv, csv_text(r));
  const std::vector<plot::Figure> figures = args.plots.dir.empty() ? std::vector<plot::Figure>{} : std::vector{bode_plot(r, args)};
  outputs = args.plots.write(std::move(outputs), figures);
  print_summary(r, args);
}

}  // namespace

void add_linearize_command(CLI::App& app) {
  auto args = std::make_shared<LinearizeArguments>();
  auto* cmd = app.add_subcommand("linearize", "Frequency response of the linearised canal at an experiment's steady state");
  cmd->add_option("scenario", args->scenario, "Built-in scenario name (see `canalsim scenarios`) or TOML file")->required();
  cmd->add_option("--experiment,-e", args->experiment, "Experiment whose operating point is linearised")->required();
  cmd->add_option("--freq", args->freq, "Log grid LO:HI:N of angular frequencies [rad/s] (default: 1e-4 to 0.5 of the grid's Nyquist frequency, 200 points)");
  cmd->add_option("--input", args->input, "gate (the controlled gate's opening, m), inflow (m3/s) or offtake:I (m3/s)");
  cmd->add_option("--output", args->output, "y_dwe, y_dw (level sensors, m), q (controlled gate discharge, m3/s) or y_checkI (check depth of pool I, m)");
  cmd->add_option("--poles", args->poles, "How many poles nearest the imaginary axis to report")->check(integer_in(0, 50, "a number of poles"));
  cmd->add_option("--json", args->json, "Write the response, gain, poles and delay as JSON");
  cmd->add_option("--csv", args->csv, "Write omega_rad_s,gain,phase_deg,real,imag as CSV");
  args->plots.add_option(cmd, "bode_EXPERIMENT_OUTPUT_per_INPUT.svg (gain in dB and phase against log omega)");
  cmd->callback([args] { run(*args); });
}

}  // namespace canalsim::cli
