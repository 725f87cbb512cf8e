// `canalsim resample IN.csv -o OUT.csv --period P`: a recording with jittered (or simply other)
// time stamps onto a uniform period P, anti-aliased (core/resample.hpp: windowed-sinc low-pass,
// Blackman window; the gate command held), so that fit and diagnose can read it.
#include <iostream>
#include <memory>
#include <string>

#include "cli/checks.hpp"
#include "cli/commands.hpp"
#include "core/format.hpp"
#include "core/progress.hpp"
#include "core/recording.hpp"
#include "core/resample.hpp"

namespace canalsim::cli {
namespace {

struct ResampleArguments {
  std::string input;
  std::string output;
  double period_s = 0.0;
  bool allow_long = false;
};

void run_resample(const ResampleArguments& args) {
  check_outputs({{"-o", args.output}}, {{"recording", args.input}});
  const Recording in = read_unevenly_sampled_recording(args.input);
  ResampleOptions options;
  options.period_s = args.period_s;
  options.allow_large = args.allow_long;
  ProgressLine progress("resampling " + args.input);
  options.progress = progress.callback();
  const Recording out = resample(in, options);
  progress.finish();
  write_recording(args.output, out);
  std::cout << "wrote " << args.output << " (" << out.size() << " samples, " << format_g(args.period_s)
            << " s, from " << in.size() << ")\n";
}

}  // namespace

void add_resample_command(CLI::App& app) {
  auto args = std::make_shared<ResampleArguments>();
  auto* cmd = app.add_subcommand(
      "resample", "Resample a recording with uneven time stamps onto a uniform period (anti-aliased)");
  cmd->add_option("recording", args->input, "Recording CSV (t_s increasing, any spacing)")->required();
  cmd->add_option("-o,--output", args->output, "Output recording CSV")->required();
  cmd->add_option("--period", args->period_s, "New sampling period in s (e.g. 0.125)")
      ->required()
      ->check(number_in(1e-6, 1e6, "a period in s"));
  cmd->add_flag("--allow-long", args->allow_long,
                "Resample past the ceilings on rows written (5e6), fine-grid samples (5e7) and filter work (2e10)");
  cmd->callback([args] { run_resample(*args); });
}

}  // namespace canalsim::cli
