// `canalsim reproduce [--out DIR] [--plots-dir DIR]`: the paper's whole study (Gharab, Feliu-Batlle & Rivas-Perez
// 2019, Tables 1–8, Figures 4, 6, 8, 10) on recordings of the simulated laboratory canal.
//
//   1. simulate the lab experiments op1–op4, op1*, op2*, op3b, op4b (builtin scenario "lab") on two
//      threads;
//   2. run the study (study/study.hpp): fits, nominal models, γ sweeps, validation,
//      uncertainty indices, each table next to the paper's, and the generated conclusions;
//   3. write DIR/tables.json, DIR/tables.md and DIR/report.html (self-contained, opens offline), the
//      Bode section as DIR/bode.*, and with --plots-dir every figure as a standalone SVG file.
//
// Nothing is written until everything is computed; each file is written atomically and, if one
// fails, the ones already written (and DIR, when this run created it) are removed.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <system_error>

#include <unistd.h>
#include <vector>

#include "cli/checks.hpp"
#include "cli/plots_dir.hpp"
#include "core/files.hpp"
#include "core/format.hpp"
#include "cli/commands.hpp"
#include "study/bode.hpp"
#include "study/render.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/prbs.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/recording.hpp"
#include "scenarios/simulate.hpp"

namespace canalsim::cli {
namespace {

namespace fs = std::filesystem;

struct ReproduceArguments {
  std::string out = "reproduce";
  double gamma_step = 0.05;
  unsigned threads = 2;
  PlotsDirectory plots;
};

// Fails early (before minutes of work) when DIR cannot be created or written.
void check_output_directory(const fs::path& dir) {
  std::error_code ec;
  // The files it will hold are replaceable (not in /dev, /proc or /sys; not devices or FIFOs).
  for (const char* name : {"tables.json", "tables.md", "report.html", "bode.json", "bode.md", "bode.html"}) {
    if (const std::string problem = replaceable_file_problem(dir / name); !problem.empty()) {
      throw InputError("--out " + dir.string() + ": " + (dir / name).string() + " " + problem);
    }
  }
  if (fs::exists(dir, ec)) {
    if (!fs::is_directory(dir, ec)) throw InputError(dir.string() + ": --out exists and is not a directory");
    if (::access(dir.c_str(), W_OK) != 0) throw InputError(dir.string() + ": --out directory is not writable");
    return;
  }
  const fs::path parent = dir.has_parent_path() ? dir.parent_path() : fs::path(".");
  if (!fs::is_directory(parent, ec)) {
    throw InputError(dir.string() + ": cannot create --out directory: " + parent.string() +
                     " does not exist");
  }
  if (::access(parent.c_str(), W_OK) != 0) {
    throw InputError(dir.string() + ": cannot create --out directory: " + parent.string() +
                     " is not writable");
  }
}

std::map<std::string, Recording> simulate_lab(const std::vector<std::string>& names, unsigned threads,
                                              ProgressLine& progress) {
  const scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  for (const auto& n : names) {
    if (!lab.find_experiment(n)) throw InputError("builtin scenario lab: no experiment '" + n + "'");
  }
  std::vector<Recording> out(names.size());
  std::vector<std::atomic<int>> percent(names.size());
  parallel_for(names.size(), static_cast<int>(threads), [&](std::size_t i) {
    scenarios::SimulateOptions options;
    options.progress = [&, i](const ProgressReport& report) {
      percent[i] = static_cast<int>(100.0 * report.fraction);
      std::string line = "simulating the lab:";
      for (std::size_t k = 0; k < names.size(); ++k) {
        line += " " + names[k] + " " + std::to_string(percent[k].load()) + "%";
      }
      progress.report({-1.0, line});
    };
    try {
      out[i] = scenarios::simulate(lab, *lab.find_experiment(names[i]), options);
    } catch (const std::exception& e) {
      throw std::runtime_error("simulating lab/" + names[i] + ": " + e.what());
    }
    percent[i] = 100;
  });
  std::map<std::string, Recording> recordings;
  for (std::size_t i = 0; i < names.size(); ++i) recordings[names[i]] = std::move(out[i]);
  return recordings;
}

void run_reproduce(const ReproduceArguments& args) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path dir = args.out;
  check_output_directory(dir);
  args.plots.check();

  study::StudyOptions options;
  options.gamma = {0.0, 10.0, args.gamma_step};
  options.threads = args.threads;
  const PrbsDesign design = design_prbs(9, 0.5);  // the lab experiments' PRBS (paper Section 4.3)
  options.prbs_clock_s = design.clock_period;
  options.prbs_stages = design.stages;
  if (const Status status = options.validate(); !status) throw InputError(status.message());

  ProgressLine progress("canalsim reproduce");
  options.progress = progress.callback();
  const study::ExperimentRoles roles;
  progress.report({0.0, "simulating the lab experiments"}, true);
  const auto recordings = simulate_lab(roles.all(), args.threads, progress);
  progress.report({0.0, "fitting"}, true);
  const auto result = study::run_study(recordings, options, roles);
  progress.report({1.0, "writing the report"}, true);
  const std::string json = study::to_json(result).dump(1) + "\n";
  const std::string md = study::to_markdown(result);
  // The Bode section (docs/linearization.md §6): in report.html and in files of its own; the tables
  // stay as they were.
  const auto bode = study::bode_sections(scenarios::builtin_scenario("lab"), result);
  const std::string bode_json = study::bode_json(bode).dump(1) + "\n";
  const std::string bode_md = study::bode_markdown(bode);
  const std::string bode_html = study::bode_html(bode);
  const std::string html = study::to_html(result, recordings, options, study::bode_html_section(bode));
  std::vector<plot::Figure> figures;
  if (!args.plots.dir.empty()) {
    figures = study::report_figures(result, recordings, options);
    for (auto& f : study::bode_figures(bode)) figures.push_back(std::move(f));
  }
  progress.finish();

  // Write: all or nothing. A file that cannot be replaced restores the others' previous contents
  // (core/files.hpp); a directory this run created is removed again.
  std::error_code ec;
  const bool created = !fs::exists(dir, ec);
  if (created && !fs::create_directory(dir, ec)) {
    throw InputError(dir.string() + ": cannot create --out directory: " + ec.message());
  }
  std::vector<FileContents> files = {
      {dir / "tables.json", json}, {dir / "tables.md", md}, {dir / "report.html", html},
      {dir / "bode.json", bode_json}, {dir / "bode.md", bode_md}, {dir / "bode.html", bode_html}};
  try {
    files = args.plots.write(std::move(files), figures);
  } catch (...) {
    if (created) fs::remove(dir, ec);
    throw;
  }
  std::size_t holds = 0;
  for (const auto& c : result.claims) holds += c.holds ? 1 : 0;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "reproduced Tables 1-8 on the simulated lab canal in " << format_fixed(seconds, 1) << " s: " << holds
            << " of " << result.claims.size()
            << " of the paper's conclusions checked hold here\n";
  for (const auto& [file, text] : files) std::cout << "wrote " << file.string() << "\n";
}

}  // namespace

void add_reproduce_command(CLI::App& app) {
  auto args = std::make_shared<ReproduceArguments>();
  auto* cmd = app.add_subcommand(
      "reproduce", "Run the paper's study (Tables 1-8, Figures 4, 6, 8, 10) on the simulated lab canal "
                   "and compare with the published values");
  cmd->add_option("--out,-o", args->out,
                  "Output directory for tables.json, tables.md, report.html, bode.json, bode.md and bode.html")
      ->capture_default_str();
  args->plots.add_option(cmd, "responses_OP.svg and validation_OP.svg (one panel per model), gamma_MODEL.svg, "
                              "flow_regime_OP.svg, prbs_spectrum.svg and bode_OP.svg");
  cmd->add_option("--gamma-step", args->gamma_step, "Step of the gamma sweep over [0, 10]")
      ->capture_default_str()
      ->check(number_in(0.001, 10.0, "a step"));
  cmd->add_option("--threads", args->threads, "Worker threads")->capture_default_str()->check(thread_count());
  cmd->callback([args] { run_reproduce(*args); });
}

}  // namespace canalsim::cli
