// `canalsim prbs`: the design figures of a PRBS input (paper Section 4.3) and, with -o, the
// sequence itself as a CSV recording of the gate command increments (t_s, u_mm).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "cli/checks.hpp"

#include "core/format.hpp"
#include "cli/commands.hpp"
#include "scenarios/prbs.hpp"
#include "core/recording.hpp"

namespace canalsim::cli {
namespace {

struct PrbsArguments {
  int stages = 9;
  double clock_s = 0.5;
  double amplitude_mm = 5.0;
  std::uint64_t seed = 1;
  std::string output;
};


void check_arguments(const PrbsArguments& args) {
  if (args.stages < prbs_min_stages || args.stages > prbs_max_stages) {
    throw InputError("--stages " + std::to_string(args.stages) +
                     ": expected an integer from 2 to 20");
  }
  if (!(args.clock_s > 0.0) || !std::isfinite(args.clock_s) || args.clock_s > 3600.0) {
    throw InputError("--clock " + format_g(args.clock_s, 10) +
                     ": expected a clock period in seconds, > 0 and at most 3600");
  }
  if (!(args.amplitude_mm > 0.0) || !std::isfinite(args.amplitude_mm)) {
    throw InputError("--amplitude " + format_g(args.amplitude_mm, 10) +
                     ": expected a positive amplitude in mm");
  }
}

std::string line(const char* label, double hz) {
  char buffer[128];
  std::snprintf(buffer, sizeof buffer, "  %-24s %.6g Hz  (%.6g rad/s)\n", label, hz,
                2.0 * std::numbers::pi * hz);
  return buffer;
}

void print_design(const PrbsDesign& d, const PrbsArguments& args) {
  char buffer[160];
  std::cout << "PRBS design (paper Section 4.3)\n";
  std::snprintf(buffer, sizeof buffer, "  %-24s %d  (N = 2^n - 1 = %zu bits, seed %llu)\n",
                "stages n", d.stages, d.length, static_cast<unsigned long long>(args.seed));
  std::cout << buffer;
  std::snprintf(buffer, sizeof buffer, "  %-24s %.10g s  (clock frequency %.6g Hz)\n",
                "clock period Tc", d.clock_period, d.clock_frequency);
  std::cout << buffer;
  // %.10g: N Tc is exact (e.g. 1048575 x 0.5 = 524287.5 s) and %.6g would round it.
  std::snprintf(buffer, sizeof buffer, "  %-24s %.10g s\n", "period T = N Tc", d.period);
  std::cout << buffer;
  std::cout << line("first spectral null", d.first_null)
            << line("-3 dB band (sinc^2)", d.bandwidth_3db)
            << line("lowest frequency 1/T", d.lowest_frequency)
            << line("f_max (f_c = 2.5 f_max)", d.max_frequency_of_interest);
  std::snprintf(buffer, sizeof buffer, "  %-24s +-%.6g mm about the operating point\n",
                "amplitude", args.amplitude_mm);
  std::cout << buffer;
}

// One row per clock period over one period of the sequence.
std::string sequence_csv(const PrbsSignal& signal, const PrbsArguments& args) {
  Recording rec;
  const auto& bits = signal.bits();
  std::vector<double> t(bits.size()), u(bits.size());
  for (std::size_t k = 0; k < bits.size(); ++k) {
    t[k] = static_cast<double>(k) * args.clock_s;
    u[k] = signal.value(t[k]) * 1e3;  // m -> mm
  }
  rec.set_meta("signal", "prbs");
  rec.set_meta("stages", std::to_string(args.stages));
  rec.set_meta("clock_s", format_g(args.clock_s, 10));
  rec.set_meta("amplitude_mm", format_g(args.amplitude_mm, 10));
  rec.set_meta("seed", std::to_string(args.seed));
  rec.set_column(columns::time, std::move(t));
  rec.set_column(columns::gate_command, std::move(u));
  return format_recording(rec);
}

}  // namespace

void add_prbs_command(CLI::App& app) {
  auto args = std::make_shared<PrbsArguments>();
  auto* cmd = app.add_subcommand(
      "prbs", "Print the design of a maximal-length PRBS input (period, spectral null, -3 dB band, "
              "lowest frequency) and optionally write the sequence");
  cmd->add_option("--stages", args->stages, "shift-register stages n, 2..20 (N = 2^n - 1 bits)")
      ->check(integer_in(prbs_min_stages, prbs_max_stages, "a number of stages"))
      ->capture_default_str();
  cmd->add_option("--clock", args->clock_s, "clock period Tc in seconds, > 0")
      ->capture_default_str()
      ->check(number_in(kMinSamplePeriod, 3600.0, "a clock period in s"));
  cmd->add_option("--amplitude", args->amplitude_mm, "amplitude in mm (+- about the operating point)")
      ->check(number_in(1e-6, 1000.0, "an amplitude in mm"))
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "seed of the initial register")
      ->capture_default_str()
      ->check(seed_value());
  cmd->add_option("-o,--output", args->output, "write one period as CSV t_s,u_mm to this file");
  cmd->callback([args] {
    check_arguments(*args);
    check_output_file("-o", args->output);
    PrbsOptions options;
    options.stages = args->stages;
    options.clock_period = args->clock_s;
    options.amplitude = args->amplitude_mm * 1e-3;
    options.seed = args->seed;
    const PrbsSignal signal(options);
    // Write first, so a bad path fails before anything is printed.
    if (!args->output.empty()) write_file_atomically(args->output, sequence_csv(signal, *args));
    print_design(signal.design(), *args);
    if (!args->output.empty()) {
      std::cout << "wrote one period (" << signal.bits().size() << " bits) to " << args->output
                << '\n';
    }
  });
}

}  // namespace canalsim::cli
