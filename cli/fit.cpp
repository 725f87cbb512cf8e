// `canalsim fit --model M REC.csv... [--nominal] [--gamma 0:10:0.05] [--json FILE]`: fits a
// reduced model (paper Section 3) to recordings — the paper's IAE fit (eq. 20), by default polished
// by least squares with each recording's operating point estimated (--criterion) — prints a table of
// parameters, IAE and Nrmse (eq. 19) per recording, and optionally writes everything — parameters,
// indexes, fitted responses, γ curves — as JSON.
//
//   per recording : one fit each (on two threads), or with --gamma a γ sweep each (Figs. 8, 10)
//   --nominal     : also one model for all recordings, minimising IAE_c (eq. 21), and the
//                   uncertainty index Δp (eq. 22) of the per-recording parameters
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli/checks.hpp"
#include "cli/recording_format.hpp"
#include "core/format.hpp"
#include "core/json.hpp"
#include "core/text.hpp"
#include "cli/finite_figures.hpp"
#include "cli/commands.hpp"
#include "cli/freq_check.hpp"
#include "scenarios/builtin.hpp"
#include "reduced_models/identification.hpp"
#include "core/progress.hpp"
#include "core/recording.hpp"

namespace canalsim::cli {
namespace {

using namespace canalsim::reduced;

struct FitArguments {
  std::string model;
  std::vector<std::string> recordings;
  bool nominal = false;
  std::string gamma;
  std::string json;
  std::optional<double> upstream_level_mm;
  double quantum_mm = 0.0;
  double gate_speed_mm_s = 0.0;
  std::string memory = "short";
  std::string criterion = "ls";
  std::size_t memory_terms = 500;
  unsigned threads = 2;
  std::string bounds;  // NAME=LO:HI,...
  std::string start;   // NAME=V,...
  std::string freq_check;  // scenario the recordings were simulated from
  bool allow_long = false;
  RecordingFormat format;
};


std::string basename_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

nlohmann::json parameters_json(const Model& m) {
  nlohmann::json p;
  for (const auto& name : parameter_names(m.kind)) p[name] = get_parameter(m.p, name);
  if (uses_upstream_level(m.kind)) {
    p["head_ref_mm"] = m.p.head_ref_mm;
    p["K_paper"] = paper_gain(m);
    if (m.kind == ModelKind::hybrid) p["head_ref_sub_mm"] = m.p.head_ref_sub_mm;
  }
  return p;
}

// How sure the fit is: "std" per parameter (the units of "parameters"; null where not
// determined), its part due to the model's time step "numerical_std", "correlation" {names,
// matrix} (null for a parameter held fixed or not determined) and the autocorrelation
// "inflation" of the variances.
void add_statistics_json(nlohmann::json& j, const FitResult& r) {
  nlohmann::json std = nlohmann::json::object(), numerical = nlohmann::json::object(), matrix = nlohmann::json::array();
  for (std::size_t a = 0; a < r.parameter_names.size(); ++a) {
    std[r.parameter_names[a]] = json_number(r.std[a]);
    numerical[r.parameter_names[a]] = json_number(r.numerical_std[a]);
    nlohmann::json row = nlohmann::json::array();
    for (double rho : r.correlation[a]) row.push_back(json_number(rho));
    matrix.push_back(std::move(row));
  }
  j["std"] = std;
  j["numerical_std"] = numerical;
  j["correlation"] = {{"names", r.parameter_names}, {"matrix", matrix}};
  j["inflation"] = json_number(r.inflation);
}

nlohmann::json fit_json(const FitResult& r, const std::vector<ExperimentData>& data,
                        const std::vector<std::size_t>& which) {
  nlohmann::json j;
  j["parameters"] = parameters_json(r.model);
  j["iae_total"] = r.iae_total;
  j["evaluations"] = r.evaluations;
  j["converged"] = r.converged;
  j["message"] = r.message;
  nlohmann::json per = nlohmann::json::array();
  for (std::size_t i = 0; i < r.sources.size(); ++i) {
    const auto& d = data[which[i]];
    per.push_back({{"recording", r.sources[i]},
                   {"K_declared_units", r.model.p.K * declared_gain_factor(d)},
                   {"K_unit", declared_gain_unit(d) + (is_integrating(r.model.kind) ? "/s" : "")},
                   {"iae", r.iae[i]},
                   {"nrmse", r.nrmse[i]},
                   {"u0_mm", d.u0_mm},
                   {"y0_mm", d.y0_mm},
                   {"t_s", d.t_s},
                   {"y_dwe_mm", d.y_dwe_mm},
                   {"model_y_dwe_mm", r.response[i]}});
  }
  j["recordings"] = per;
  add_statistics_json(j, r);
  return j;
}

// "NAME=TEXT,NAME=TEXT" of --bounds / --start, each NAME one of the model's parameters.
std::vector<std::pair<std::string, std::string>> parse_assignments(const std::string& flag,
                                                                   const std::string& text,
                                                                   ModelKind kind,
                                                                   const std::string& example) {
  const auto names = parameter_names(kind);
  std::string expected;
  for (const auto& n : names) expected += (expected.empty() ? "" : ", ") + n;
  std::vector<std::pair<std::string, std::string>> out;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw InputError(flag + " '" + item + "': expected NAME=" + example + " (comma-separated)");
    }
    const std::string name = item.substr(0, eq);
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      throw InputError(flag + " '" + item + "': " + model_name(kind) + " has no parameter " + name +
                       " (expected " + expected + ")");
    }
    for (const auto& [seen, value] : out) {
      if (seen == name) throw InputError(flag + ": parameter " + name + " given twice");
    }
    out.emplace_back(name, item.substr(eq + 1));
    begin = end + 1;
  }
  return out;
}

double assignment_number(const std::string& flag, const std::string& name, const std::string& text) {
  double value = 0.0;
  if (!detail::parse_number(text, value)) {
    throw InputError(flag + " " + name + "=" + text + ": '" + text + "' is not a finite number");
  }
  return value;
}

// --bounds NAME=LO:HI,... and --start NAME=V,... into the fit options; the options' own
// validation then reports a start outside its bounds or bounds that exclude every model.
void apply_bounds_and_start(const FitArguments& args, ModelKind kind, FitBounds& bounds) {
  if (!args.bounds.empty()) {
    for (const auto& [name, text] : parse_assignments("--bounds", args.bounds, kind, "LO:HI")) {
      const auto colon = text.find(':');
      if (colon == std::string::npos) {
        throw InputError("--bounds " + name + "=" + text + ": expected LO:HI, e.g. " + name + "=0:5");
      }
      auto& spec = bounds[name];
      spec.lower = assignment_number("--bounds", name, text.substr(0, colon));
      spec.upper = assignment_number("--bounds", name, text.substr(colon + 1));
      if (spec.lower > spec.upper) {
        throw InputError("--bounds " + name + "=" + text + ": lower bound above upper bound");
      }
    }
  }
  if (!args.start.empty()) {
    for (const auto& [name, text] : parse_assignments("--start", args.start, kind, "V")) {
      bounds[name].initial = assignment_number("--start", name, text);
    }
  }
}

// The unit K is shown in: the recordings' declared units (docs/recording-format.md).
std::string gain_unit_text(ModelKind kind, const std::vector<ExperimentData>& data) {
  const std::string per_second = is_integrating(kind) ? "/s" : "";
  const std::string unit = declared_gain_unit(data.front());
  for (const auto& d : data) {
    if (declared_gain_unit(d) != unit || declared_gain_factor(d) != declared_gain_factor(data.front())) {
      return "K in each recording's declared units" + per_second;
    }
  }
  return "K in " + unit + per_second;
}

// A gain, time constant or order that ends on a bound was not identified within the bounds: the
// figures are printed, with a warning that says which (a delay or exponent of 0 is a model, not a
// limit, and is not warned about).
void warn_about_bounds(const FitResult& fit, const FitOptions& options, const std::string& stage) {
  for (const std::string name : {"K", "T", "T2", "Tz", "lambda", "K_sub"}) {
    const auto names = parameter_names(fit.model.kind);
    if (std::find(names.begin(), names.end(), name) == names.end()) continue;
    const ParameterSpec& spec = options.bounds[name];
    if (spec.fixed || spec.lower == spec.upper) continue;
    const double v = get_parameter(fit.model.p, name);
    const auto on = [&](double bound) { return std::isfinite(bound) && std::abs(v - bound) <= 1e-9 * std::max(1.0, std::abs(bound)); };
    if (!on(spec.lower) && !on(spec.upper)) continue;
    std::cerr << "canalsim: warning: " << stage << ": " << name << " = " << format_g(v) << " is at its "
              << (on(spec.lower) ? "lower" : "upper") << " bound: not identified within the bounds "
              << "(widen them with --bounds, or check the recording)\n";
  }
}

// --upstream-level stands in for a y_up_mm column: given where every recording has one, it would
// be ignored without a word.
void require_upstream_level_used(const std::optional<double>& level, const std::vector<ExperimentData>& data,
                                 const std::string& command) {
  if (!level) return;
  for (const auto& d : data) {
    if (d.y_up_is_constant_option) return;
  }
  throw InputError(command + " --upstream-level " + format_g(*level) +
                   ": every recording has a y_up_mm column, which is used instead (the flag is for recordings without one)");
}

// A model whose error is more than ten times the recording's own variation (Nrmse below
// -1000 %, eq. 19, or not a number) is not a fit: it diverged (an exponent the bounds or --gamma held where the
// model is unstable), and printing its parameters would present it as one.
void require_model_follows(const FitResult& fit, const std::string& stage) {
  for (std::size_t i = 0; i < fit.nrmse.size(); ++i) {
    if (fit.nrmse[i] >= -1000.0) continue;
    const auto figure = [](double v, const char* unit) {
      return std::isfinite(v) ? format_g(v, 3) + unit : std::string("not finite");
    };
    throw InputError(stage + ": the best model found does not follow " + fit.sources[i] + " (Nrmse " +
                     figure(fit.nrmse[i], " %") + ", IAE " + figure(fit.iae[i], " mm s") +
                     "): it diverges within the bounds given (widen --bounds or the --gamma grid)");
  }
}

// Fits that would run for minutes are refused before they start (identification.hpp,
// estimate_fit_operations), as simulate and diagnose refuse long runs.
void check_fit_cost(ModelKind kind, const std::vector<ExperimentData>& data, const FitOptions& options,
                    const std::optional<GammaGrid>& grid, const FitArguments& args) {
  if (args.allow_long) return;
  const double per_recording = grid ? static_cast<double>(grid->values().size()) : 1.0;
  const double fits = per_recording * (args.nominal ? 2.0 : 1.0);
  const double operations = estimate_fit_operations(kind, data, options, fits);
  if (operations <= kMaxFitOperations) return;
  std::size_t samples = 0;
  for (const auto& d : data) samples += d.size();
  throw InputError("fit: " + model_name(kind) + " on " + std::to_string(data.size()) + " recording(s) of " +
                   std::to_string(samples) + " samples" + (grid ? " over " + args.gamma : std::string()) + " is about " +
                   format_g(operations, 3) + " model operations, expected at most " + format_g(kMaxFitOperations, 3) +
                   " (about two minutes): shorter recordings (canalsim resample --period), a coarser --gamma grid; "
                   "or pass --allow-long");
}

// Table labels: the recordings' file names, or their whole paths where two share a file name.
std::vector<std::string> recording_labels(const std::vector<std::string>& sources) {
  std::vector<std::string> labels;
  for (const auto& s : sources) labels.push_back(basename_of(s));
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (std::count(labels.begin(), labels.end(), labels[i]) > 1) {
      for (std::size_t j = 0; j < labels.size(); ++j) {
        if (basename_of(sources[j]) == basename_of(sources[i])) labels[j] = sources[j];
      }
    }
  }
  return labels;
}

// One row of a fit table: K is shown times `gain_factor`, i.e. in the recording's declared units.
struct TableRow {
  std::string label;
  const FitResult* fit;
  double gain_factor = 1.0;
};

// A parameter as "value ± std" (core/format.hpp's format_estimate; "(± n/a)" where the std is
// 0 or not finite: held fixed, or not determined by the recording).
std::string estimate_cell(const FitResult& r, std::size_t j, double factor) {
  const double value = get_parameter(r.model.p, r.parameter_names[j]) * factor;
  return j < r.std.size() ? format_estimate(value, r.std[j] * factor) : format_g(value, 4);
}

void print_table(const std::string& title, const std::vector<std::string>& names,
                 const std::vector<TableRow>& rows) {
  // Cells first: the columns are as wide as their widest estimate.
  std::vector<std::vector<std::string>> cells;
  std::vector<std::size_t> widths;
  for (const auto& n : names) widths.push_back(std::max<std::size_t>(n.size(), 10));
  for (const auto& row : rows) {
    cells.emplace_back();
    for (std::size_t j = 0; j < names.size(); ++j) {
      cells.back().push_back(estimate_cell(*row.fit, j, names[j] == "K" ? row.gain_factor : 1.0));
      widths[j] = std::max(widths[j], text_width(cells.back().back()));
    }
  }
  std::cout << title << "\n";
  std::size_t width = std::string("recording").size();
  for (const auto& row : rows) width = std::max(width, row.label.size());
  std::cout << "  " << "recording" << std::string(width - 9, ' ');
  for (std::size_t j = 0; j < names.size(); ++j) std::cout << "  " << std::string(widths[j] - names[j].size(), ' ') << names[j];
  std::cout << "  " << std::string(10 - 3, ' ') << "IAE" << "     Nrmse  autocorr\n";
  char buffer[64];
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& [label, r, gain_factor] = rows[i];
    std::cout << "  " << label << std::string(width - label.size(), ' ');
    for (std::size_t j = 0; j < names.size(); ++j) {
      std::cout << "  " << std::string(widths[j] - text_width(cells[i][j]), ' ') << cells[i][j];
    }
    std::snprintf(buffer, sizeof buffer, "  %10.4g  %7.2f%%", r->iae.front(), r->nrmse.front());
    std::cout << buffer << "  " << std::setw(8) << format_figure(r->inflation, 1, "x")
              << (r->converged ? "" : "  (" + r->message + ")") << "\n";
  }
  std::cout << "  (± one standard deviation, autocorr the factor the residuals' autocorrelation widened the "
               "variances by; n/a: held fixed or not determined)\n";
}

// Δp (eq. 22) is relative to the nominal value: undefined when that is 0 (γ = 0 in particular), so
// say so rather than print "inf%" (the study's markdown tables write "∞ (nominal 0)").
std::string uncertainty_text(double dp, double nominal) {
  if (nominal == 0.0 || !std::isfinite(dp)) return "undefined (nominal 0)";
  return format_fixed(100.0 * dp, 2) + "%";
}

// The fits of one run: one per recording and, with --nominal, one over all of them, each with
// its gamma sweep when --gamma asked for one.
struct Fits {
  std::vector<FitResult> each;
  std::vector<GammaSweep> sweeps;
  std::optional<FitResult> nominal;
  std::optional<GammaSweep> nominal_sweep;
};

std::vector<std::size_t> every_index(std::size_t n) {
  std::vector<std::size_t> all(n);
  for (std::size_t j = 0; j < n; ++j) all[j] = j;
  return all;
}

// --gamma's grid, refused for a model without gamma; --memory checked.
std::optional<GammaGrid> gamma_grid(const FitArguments& args, ModelKind kind) {
  std::optional<GammaGrid> grid;
  if (!args.gamma.empty()) {
    grid = GammaGrid::parse(args.gamma);
    if (!uses_gamma(kind)) {
      throw InputError("--gamma: model " + model_name(kind) +
                       " has no gamma (the sweep applies to nliom-f, nlfom-f, nliom-s, nlfom-s, hybrid)");
    }
  }
  if (args.memory != "short" && args.memory != "full") throw InputError("--memory " + args.memory + ": expected short or full");
  return grid;
}

std::vector<ExperimentData> read_experiments(const FitArguments& args, ModelKind kind) {
  DataOptions data_options;
  data_options.upstream_level_mm = args.upstream_level_mm;
  std::vector<ExperimentData> data;
  for (const auto& file : args.recordings) {
    data.push_back(prepare_data(args.format.read(file), data_options));
    if (uses_upstream_level(kind)) require_upstream_level(data.back(), model_name(kind));
  }
  require_upstream_level_used(args.upstream_level_mm, data, "fit");
  return data;
}

FitOptions fit_options(const FitArguments& args, ModelKind kind, ProgressLine& progress) {
  FitOptions options;
  options.actuation.quantum_mm = args.quantum_mm;
  options.actuation.gate_speed_mm_s = args.gate_speed_mm_s;
  options.simulation.gl.memory = args.memory == "full" ? GlMemory::full : GlMemory::short_memory;
  options.simulation.gl.memory_terms = args.memory_terms;
  options.criterion = args.criterion == "iae" ? Criterion::iae : Criterion::least_squares;
  options.threads = args.threads;
  options.progress = progress.callback();
  apply_bounds_and_start(args, kind, options.bounds);
  if (const Status status = options.validate(); !status) {
    throw InputError((args.bounds.empty() && args.start.empty() ? "" : "--bounds/--start: ") + status.message());
  }
  return options;
}

Fits fit_all(ModelKind kind, const std::vector<ExperimentData>& data, const FitOptions& options,
             const std::optional<GammaGrid>& grid, bool with_nominal, ProgressLine& progress) {
  Fits f;
  if (grid) {
    for (const auto& experiment : data) {
      f.sweeps.push_back(gamma_sweep(kind, {experiment}, options, *grid));
      f.each.push_back(f.sweeps.back().best_fit);
      progress.report({-1.0, "gamma sweep done for " + experiment.source});
    }
  } else {
    f.each = fit_each(kind, data, options);
  }
  if (with_nominal) {
    if (grid) {
      f.nominal_sweep = gamma_sweep(kind, data, options, *grid);
      f.nominal = f.nominal_sweep->best_fit;
    } else {
      f.nominal = fit_nominal(kind, data, options);
    }
    progress.report({-1.0, "nominal model done"});
  }
  return f;
}

// Nothing is printed unless every figure is a number and every model follows its recording; a
// parameter at its bound is a warning.
void require_printable(const Fits& f, ModelKind kind, const std::vector<ExperimentData>& data, const FitOptions& options,
                       ProgressLine& progress) {
  for (std::size_t j = 0; j < f.each.size(); ++j) {
    require_model_follows(f.each[j], "fit of " + model_name(kind) + " to " + f.each[j].sources.front());
    require_finite_figures(fit_json(f.each[j], data, {j}), "fit of " + model_name(kind) + " to " + f.each[j].sources.front());
  }
  if (f.nominal) require_model_follows(*f.nominal, "nominal fit of " + model_name(kind));
  progress.finish();
  for (const auto& fit : f.each) warn_about_bounds(fit, options, "fit of " + model_name(kind) + " to " + fit.sources.front());
  if (f.nominal) {
    warn_about_bounds(*f.nominal, options, "nominal fit of " + model_name(kind));
    require_finite_figures(fit_json(*f.nominal, data, every_index(data.size())), "nominal fit of " + model_name(kind));
  }
}

// The per-recording table, and with a nominal model its table and the uncertainty indices
// (eq. 22), which it returns.
std::map<std::string, double> print_fits(const FitArguments& args, ModelKind kind, const Fits& f,
                                         const std::vector<ExperimentData>& data, const std::optional<GammaGrid>& grid) {
  const auto names = parameter_names(kind);
  std::vector<TableRow> rows;
  const auto labels = recording_labels(args.recordings);
  for (std::size_t j = 0; j < f.each.size(); ++j) rows.push_back({labels[j], &f.each[j], declared_gain_factor(data[j])});
  const std::string criterion = args.criterion == "iae" ? "IAE fit" : "IAE fit polished by least squares";
  print_table(model_name(kind) + " fits (" + criterion + "; " + gain_unit_text(kind, data) + ", IAE in mm s, Nrmse eq. 19" +
                  (grid ? ", gamma by best Nrmse over " + args.gamma : std::string()) + ")",
              names, rows);
  std::map<std::string, double> dp;
  if (!f.nominal) return dp;
  std::vector<FitResult> per(f.nominal->sources.size());
  std::vector<TableRow> nominal_rows;
  for (std::size_t j = 0; j < per.size(); ++j) {
    per[j].model = f.nominal->model;
    per[j].iae = {f.nominal->iae[j]};
    per[j].nrmse = {f.nominal->nrmse[j]};
    per[j].parameter_names = f.nominal->parameter_names;
    per[j].std = f.nominal->std;
    per[j].inflation = f.nominal->inflation;
    per[j].converged = f.nominal->converged;
    per[j].message = f.nominal->message;
    nominal_rows.push_back({"nominal @ " + labels[j], &per[j], declared_gain_factor(data[j])});
  }
  print_table("nominal model (minimises IAE_c, eq. 21; IAE_c = " + format_fixed(f.nominal->iae_total, 4) + ")", names,
              nominal_rows);
  std::vector<Model> models;
  for (const auto& fit : f.each) models.push_back(fit.model);
  dp = uncertainty_indices(models, f.nominal->model);
  std::cout << "  uncertainty index dp (eq. 22):";
  for (const auto& n : names) std::cout << "  " << n << " " << uncertainty_text(dp[n], get_parameter(f.nominal->model.p, n));
  std::cout << "\n";
  return dp;
}

nlohmann::json fits_json(const FitArguments& args, ModelKind kind, const Fits& f, const std::vector<ExperimentData>& data,
                         const std::optional<GammaGrid>& grid, const std::map<std::string, double>& dp) {
  nlohmann::json out;
  out["model"] = model_name(kind);
  out["options"] = {{"quantum_mm", args.quantum_mm},
                    {"gate_speed_mm_s", args.gate_speed_mm_s},
                    {"gl_memory", args.memory},
                    {"gl_memory_terms", args.memory_terms},
                    {"cost", "IAE (eq. 20); nominal IAE_c (eq. 21)"}};
  if (grid) out["options"]["gamma_grid"] = {grid->first, grid->last, grid->step};
  nlohmann::json each = nlohmann::json::array();
  for (std::size_t j = 0; j < f.each.size(); ++j) {
    auto fit = fit_json(f.each[j], data, {j});
    if (grid) fit["gamma_sweep"] = {{"gamma", f.sweeps[j].gamma}, {"nrmse", f.sweeps[j].nrmse}, {"iae", f.sweeps[j].iae}};
    each.push_back(std::move(fit));
  }
  out["fits"] = each;
  if (f.nominal) {
    auto n = fit_json(*f.nominal, data, every_index(data.size()));
    if (f.nominal_sweep) {
      n["gamma_sweep"] = {{"gamma", f.nominal_sweep->gamma}, {"nrmse", f.nominal_sweep->nrmse}, {"iae", f.nominal_sweep->iae}};
    }
    out["nominal"] = n;
    out["uncertainty_index"] = dp;
  }
  return out;
}

void run_fit(const FitArguments& args) {
  std::vector<NamedFile> inputs = named_files("recording", args.recordings);
  inputs.push_back({"--freq-check", args.freq_check});
  check_outputs({{"--json", args.json}}, inputs);  // written after all the fits
  const ModelKind kind = require_model_kind(args.model);
  const std::optional<GammaGrid> grid = gamma_grid(args, kind);
  // --freq-check: the scenario and each recording's experiment, before any fit.
  std::optional<scenarios::Scenario> check_scenario;
  std::vector<const scenarios::ExperimentSpec*> check_experiments;
  if (!args.freq_check.empty()) {
    check_scenario = scenarios::load_scenario_or_builtin(args.freq_check);
    check_experiments = freq_check_experiments(*check_scenario, args.recordings);
  }
  const std::vector<ExperimentData> data = read_experiments(args, kind);

  ProgressLine progress("canalsim fit");
  const FitOptions options = fit_options(args, kind, progress);
  check_fit_cost(kind, data, options, grid, args);
  const Fits fits = fit_all(kind, data, options, grid, args.nominal, progress);
  require_printable(fits, kind, data, options, progress);
  const std::map<std::string, double> dp = print_fits(args, kind, fits, data, grid);
  nlohmann::json freq_check;
  if (check_scenario) freq_check = print_freq_check(*check_scenario, check_experiments, fits.each, data);

  if (args.json.empty()) return;
  nlohmann::json out = fits_json(args, kind, fits, data, grid, dp);
  if (check_scenario) out["freq_check"] = freq_check;
  write_file_atomically(args.json, out.dump(1) + "\n");
  std::cout << "wrote " << args.json << "\n";
}

}  // namespace

void add_fit_command(CLI::App& app) {
  auto args = std::make_shared<FitArguments>();
  auto* cmd = app.add_subcommand(
      "fit", "Fit a reduced model (liom, sopd, lfom, nliom-f, nlfom-f, nliom-s, nlfom-s, hybrid, id, idz) "
             "to recordings (the paper's IAE fit, polished by least squares unless --criterion iae)");
  cmd->add_option("--model,-m", args->model, "Model to fit")->required();
  cmd->add_option("recordings", args->recordings, "Recording CSV files (t_s, u_mm, y_dwe_mm; "
                                                  "y_up_mm for the nonlinear models)")
      ->required();  // a missing file is reported by the reader, naming it, like every file error
  cmd->add_flag("--nominal", args->nominal,
                "Also fit one nominal model to all recordings (IAE_c, Gharab et al. 2019, eq. 21) and report dp (eq. 22)");
  cmd->add_option("--gamma", args->gamma,
                  "Sweep gamma over first:last:step (e.g. 0:10:0.05) and keep the best Nrmse");
  cmd->add_option("--json", args->json, "Write parameters, IAE, Nrmse and responses as JSON");
  args->format.add_options(cmd);
  // Flag values are checked here so that errors name the flag, not the library's option field.
  cmd->add_option("--upstream-level", args->upstream_level_mm,
                  "Constant upstream level in mm for recordings without y_up_mm")
      ->check(positive_number("a level in mm"));
  cmd->add_option("--quantum", args->quantum_mm,
                  "Sensor resolution in mm included in the model output (Gharab et al. 2019, eq. 17; 0 = off)")
      ->check(number_in(0.0, 100.0, "a resolution in mm"));
  cmd->add_option("--gate-speed", args->gate_speed_mm_s,
                  "Gate speed in mm/s for the rate limit (Gharab et al. 2019, eq. 16; 0 = off)")
      ->check(number_in(0.0, 1e6, "a speed in mm/s"));
  cmd->add_option("--memory", args->memory, "GL memory: short (N terms, paper) or full")
      ->capture_default_str();
  cmd->add_option("--memory-terms", args->memory_terms, "N for the short memory (paper: 500)")
      ->capture_default_str()
      ->check(integer_in(1, 100000000, "a number of terms"));
  cmd->add_option("--criterion", args->criterion,
                  "ls: the paper's IAE fit polished by least squares with each recording's operating point "
                  "estimated (efficient on real recordings: docs/reduced-models.md, \"Delay precision\"); iae: the "
                  "paper's criterion alone (as `reproduce` uses)")
      ->capture_default_str()
      ->check(CLI::IsMember({"ls", "iae"}));
  cmd->add_option("--bounds", args->bounds,
                  "Parameter bounds NAME=LO:HI,... (e.g. T=1:600,L=0:30; names as in the table)");
  cmd->add_option("--start", args->start, "Starting values NAME=V,... (e.g. T=120,L=4)");
  cmd->add_option("--threads", args->threads, "Worker threads")->capture_default_str()->check(thread_count());
  cmd->add_option("--freq-check", args->freq_check,
                  "Scenario the recordings were simulated from: compare each fitted model's frequency response "
                  "with the linearised pool's over the PRBS band (docs/linearization.md)");
  cmd->add_flag("--allow-long", args->allow_long, "Fit past the ceiling on the estimated work (about two minutes)");
  cmd->callback([args, cmd] {
    // A flag that does not apply to the model or memory chosen would be ignored without a word.
    if (cmd->count("--memory-terms") > 0 && args->memory == "full") {
      throw InputError("fit --memory-terms: applies to --memory short (the full memory keeps every term)");
    }
    const ModelKind kind = require_model_kind(args->model);
    for (const char* flag : {"--memory", "--memory-terms"}) {
      if (cmd->count(flag) > 0 && !is_fractional(kind)) {
        throw InputError(std::string("fit ") + flag + ": model " + model_name(kind) +
                         " has no fractional order (the Grünwald–Letnikov memory applies to lfom, nlfom-f, nlfom-s and hybrid)");
      }
    }
    if (cmd->count("--upstream-level") > 0 && !uses_upstream_level(kind)) {
      throw InputError("fit --upstream-level: model " + model_name(kind) +
                       " does not use the upstream level (nliom-f, nlfom-f, nliom-s, nlfom-s and hybrid do)");
    }
    run_fit(*args);
  });
}

}  // namespace canalsim::cli
