// `canalsim dambreak`: the classic dam-break problem on a 20 m flat, frictionless, 1 m wide
// rectangular channel — Stoker's wet bed (h = 1 m | 0.1 m) or, with --dry, Ritter's dry bed
// (h = 1 m | 0). Runs the finite-volume solver and writes a CSV of the final state next to the
// closed-form solution (Toro 2001, ch. 4), and prints the volume balance.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include "cli/checks.hpp"
#include "cli/commands.hpp"
#include "core/progress.hpp"
#include "core/format.hpp"
#include "core/recording.hpp"
#include "scenarios/run_cost.hpp"
#include "solver/options.hpp"
#include "solver/canal.hpp"

namespace canalsim::cli {
namespace {

constexpr double kGravity = 9.81;
constexpr double kLength = 20.0, kDam = 10.0, kUpstreamDepth = 1.0;

// Exact depth: rarefaction fan h = (2 c_L − ξ)² / (9 g), then (wet bed) the middle state h_m of the
// shock relation 2 (c_L − c_m) = (h_m − h_R) sqrt(g (h_m + h_R) / (2 h_m h_R)), found by bisection.
double exact_depth(double x, double t, double h_right) {
  const double cl = std::sqrt(kGravity * kUpstreamDepth);
  const double xi = (x - kDam) / t;
  if (xi <= -cl) return kUpstreamDepth;
  const auto fan = [&](double s) { return (2.0 * cl - s) * (2.0 * cl - s) / (9.0 * kGravity); };
  if (h_right <= 0.0) return xi < 2.0 * cl ? fan(xi) : 0.0;
  double lo = h_right, hi = kUpstreamDepth;
  for (int k = 0; k < 200; ++k) {
    const double h = 0.5 * (lo + hi);
    const double f = 2.0 * (cl - std::sqrt(kGravity * h)) -
                     (h - h_right) * std::sqrt(kGravity * (h + h_right) / (2.0 * h * h_right));
    (f > 0.0 ? lo : hi) = h;
  }
  const double hm = 0.5 * (lo + hi), um = 2.0 * (cl - std::sqrt(kGravity * hm));
  if (xi < um - std::sqrt(kGravity * hm)) return fan(xi);
  return xi < hm * um / (hm - h_right) ? hm : h_right;
}

// The run's cost before it starts (scenarios/run_cost.hpp's ceilings): the fastest wave of the
// dam break is the Ritter front, 2 sqrt(g h0) (Toro 2001, ch. 4), so the solver takes about
// t (2 sqrt(g h0) + sqrt(g h0)) / (cfl dx) steps of every cell.
void check_dambreak_cost(int cells, double t_end, bool allow_long) {
  const double dx = kLength / cells;
  const double speed = 3.0 * std::sqrt(kGravity * kUpstreamDepth);
  const double steps = t_end * speed / (solver::SolverOptions{}.cfl * dx);
  const double updates = steps * cells, bytes = 1000.0 * cells;
  if (allow_long) return;
  if (bytes > scenarios::kMaxMemoryBytes) {
    throw InputError("--cells " + std::to_string(cells) + ": needs about " + format_g(bytes / 1e9, 3) +
                     " GB, expected at most " + format_g(scenarios::kMaxMemoryBytes / 1e9) + " GB (or pass --allow-long)");
  }
  if (updates > scenarios::kMaxCellUpdates) {
    throw InputError("--cells " + std::to_string(cells) + " --time " + format_g(t_end) + ": about " + format_g(steps, 3) +
                     " steps of " + std::to_string(cells) + " cells = " + format_g(updates, 3) +
                     " cell updates, expected at most " + format_g(scenarios::kMaxCellUpdates) +
                     " (fewer cells or a shorter time; or pass --allow-long)");
  }
}

void run_dambreak(int cells, double t_end, bool dry, const std::string& output, bool allow_long) {
  if (cells < 2) throw InputError("--cells " + std::to_string(cells) + ": expected an integer >= 2");
  if (!(t_end > 0.0) || !std::isfinite(t_end)) {
    std::ostringstream text;
    text << "--time " << t_end << ": expected a positive number of seconds";
    throw InputError(text.str());
  }
  check_output_file("-o", output);  // before the run, like every argument
  check_dambreak_cost(cells, t_end, allow_long);
  const double h_right = dry ? 0.0 : 0.1;

  // Setup: one reach, water at rest behind the dam at x = 10 m, transmissive ends.
  solver::ReachSpec spec;
  spec.name = dry ? "ritter" : "stoker";
  spec.length = kLength;
  spec.cells = cells;
  spec.section = {1.0, 0.0};
  for (int i = 0; i < cells; ++i)
    spec.initial_depth.push_back((i + 0.5) * kLength / cells < kDam ? kUpstreamDepth : h_right);
  solver::Canal canal;
  if (auto st = canal.add_reach(spec); !st) throw InputError(st.message());
  canal.set_boundary(0, solver::End::upstream, std::make_shared<solver::TransmissiveBoundary>());
  canal.set_boundary(0, solver::End::downstream, std::make_shared<solver::TransmissiveBoundary>());

  // Run.
  // In 100 chunks, for the progress line of a long run.
  ProgressLine progress("dam break, " + std::to_string(cells) + " cells");
  for (int k = 1; k <= 100; ++k) {
    if (auto st = canal.advance_to(k == 100 ? t_end : t_end * k / 100.0); !st) throw std::runtime_error("dam break: " + st.message());
    progress.report({k / 100.0, ""});
  }
  progress.finish();

  // Output: the final state and the exact depth at each cell centre.
  const solver::Reach& r = canal.reach(0);
  std::ostringstream csv;
  csv << "# problem: " << (dry ? "Ritter dry-bed" : "Stoker wet-bed") << " dam break\n"
      << "# time_s: " << format_g(t_end, 10) << "\n# cells: " << cells << "\n"
      << "x_m,depth_m,discharge_m3s,exact_depth_m\n";
  double l1 = 0.0;
  for (int i = 0; i < cells; ++i) {
    const double x = r.x_centre(i), exact = exact_depth(x, t_end, h_right);
    l1 += std::abs(r.depth(i) - exact) * r.cell_length();
    csv << format_g(x, 10) << ',' << format_g(r.depth(i), 10) << ',' << format_g(r.discharge()[static_cast<std::size_t>(i)], 10)
        << ',' << format_g(exact, 10) << '\n';
  }
  write_file_atomically(output, csv.str());

  const solver::VolumeBalance b = canal.total_balance();
  std::cout << "wrote " << std::filesystem::absolute(output).string() << " (" << cells << " cells, t = " << format_g(t_end)
            << " s, " << canal.statistics().steps << " steps)\n"
            << "L1 depth error vs exact: " << format_g(l1) << " m^2\n"
            << "volume balance [m^3]: storage change " << format_g(b.storage_change()) << ", inflow " << format_g(b.inflow)
            << ", outflow " << format_g(b.outflow) << ", error " << format_g(b.error()) << " (relative "
            << format_g(b.relative_error()) << ")\n";
}

}  // namespace

void add_dambreak_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("dambreak", "Run a Stoker (wet) or Ritter (--dry) dam break and write a CSV");
  struct Args {
    int cells = 400;
    double time = 1.5;
    bool dry = false;
    std::string output = "dambreak.csv";
    bool allow_long = false;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("--cells", args->cells, "Number of cells on the 20 m channel")
      ->capture_default_str()
      ->check(integer_in(2, 100000000, "a number of cells"));
  cmd->add_option("--time", args->time, "Simulated time [s]")->capture_default_str()->check(positive_number("a time in s"));
  cmd->add_flag("--dry", args->dry, "Dry bed downstream (Ritter) instead of 0.1 m (Stoker)");
  cmd->add_option("-o,--output", args->output, "CSV file to write")->capture_default_str();
  cmd->add_flag("--allow-long", args->allow_long, "Run past the cost ceilings (3e10 cell updates, 2 GB)");
  cmd->callback([args] { run_dambreak(args->cells, args->time, args->dry, args->output, args->allow_long); });
}

}  // namespace canalsim::cli
