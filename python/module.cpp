// The compiled half of the Python package (`canalsim._canalsim`): each function calls the library
// the command line calls, with the command line's defaults, and hands back plain Python values
// (lists, numpy arrays, JSON text). canalsim/__init__.py turns them into DataFrames and result
// objects (docs/python.md). A recording crosses as a dict {names, columns, metadata, source}; one
// coming from Python is read back through the CSV parser, so it meets every check a file does.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "calibration/calibrate.hpp"
#include "calibration/report.hpp"
#include "calibration/scenario_file.hpp"
#include "core/declared_units.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/recording.hpp"
#include "diagnosis/baseline.hpp"
#include "diagnosis/calibrated_scenario.hpp"
#include "diagnosis/diagnose.hpp"
#include "diagnosis/report.hpp"
#include "linearize/linearize.hpp"
#include "python/interrupt.hpp"
#include "reduced_models/data.hpp"
#include "reduced_models/frequency.hpp"
#include "reduced_models/identification.hpp"
#include "reduced_models/models.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/scenario_toml.hpp"
#include "scenarios/simulate.hpp"
#include "scenarios/staggered.hpp"

namespace py = pybind11;

namespace canalsim::python {
namespace {

// ---------------------------------------------------------------------------------------------
// Recordings

py::array_t<double> to_array(const std::vector<double>& values) {
  return py::array_t<double>(static_cast<py::ssize_t>(values.size()), values.data());
}

py::dict recording_dict(const Recording& r) {
  py::list columns;
  for (const auto& c : r.columns) columns.append(to_array(c));
  py::dict d;
  d["names"] = r.names;
  d["columns"] = columns;
  d["metadata"] = r.metadata;
  d["source"] = r.source;
  return d;
}

// A recording from Python, checked as a file is: serialised and parsed by the CSV reader
// (uniform increasing time, finite values, the required columns, the user's column names).
Recording recording_from_dict(const py::dict& d, const std::map<std::string, std::string>& column_names = {}) {
  Recording r;
  r.source = d["source"].cast<std::string>();
  r.names = d["names"].cast<std::vector<std::string>>();
  r.metadata = d["metadata"].cast<std::vector<std::pair<std::string, std::string>>>();
  for (const auto& column : d["columns"]) r.columns.push_back(column.cast<std::vector<double>>());
  for (const auto& c : r.columns) {
    if (c.size() != r.columns.front().size()) throw InputError(r.source + ": columns of different lengths");
  }
  RecordingReadOptions options;
  options.column_names = column_names;
  return parse_recording(format_recording(r), r.source, options);
}

std::vector<Recording> recordings_from(const py::list& dicts, bool in_mm) {
  std::vector<Recording> out;
  for (const auto& d : dicts) {
    out.push_back(recording_from_dict(d.cast<py::dict>()));
    if (in_mm) out.back() = in_millimetres(std::move(out.back()));
  }
  return out;
}

py::dict read_recording_file(const std::string& path, const std::map<std::string, std::string>& column_names) {
  RecordingReadOptions options;
  options.column_names = column_names;
  return recording_dict(read_recording(path, options));
}

void write_recording_file(const py::dict& d, const std::string& path) {
  write_file_atomically(path, format_recording(recording_from_dict(d)));
}

// ---------------------------------------------------------------------------------------------
// Scenarios: TOML text and the name it came from; keys as the files and the calibration name
// them ("pools[1].manning_n", 1-based).

scenarios::Scenario parse(const std::string& text, const std::string& source) {
  return scenarios::parse_scenario(text, source);
}

const scenarios::ExperimentSpec& experiment_of(const scenarios::Scenario& s, const std::string& name) {
  if (const auto* e = s.find_experiment(name)) return *e;
  std::string names;
  for (const auto& x : s.experiments) names += (names.empty() ? "" : ", ") + x.name;
  throw InputError(s.name + ": no experiment '" + name + "' (experiments: " + names + ")");
}

std::vector<std::string> experiment_names(const std::string& text, const std::string& source) {
  std::vector<std::string> names;
  for (const auto& e : parse(text, source).experiments) names.push_back(e.name);
  return names;
}

// "pools[1].manning_n" → toml++'s "pools[0].manning_n": every [N] one less.
std::string toml_path(const std::string& key) {
  std::string path;
  std::size_t at = 0;
  while (at < key.size()) {
    const std::size_t open = key.find('[', at);
    const std::size_t close = open == std::string::npos ? open : key.find(']', open);
    if (close == std::string::npos) return path + key.substr(at);
    const std::string digits = key.substr(open + 1, close - open - 1);
    if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9) {
      throw InputError("scenario key " + key + ": expected an array index [1], [2], ... after " + key.substr(0, open));
    }
    const long index = std::stol(digits);
    if (index < 1) throw InputError("scenario key " + key + ": array indices start at 1");
    path += key.substr(at, open - at) + "[" + std::to_string(index - 1) + "]";
    at = close + 1;
  }
  return path;
}

py::object scenario_value(const std::string& text, const std::string& source, const std::string& key) {
  toml::table table;
  try {
    table = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw InputError(source + ": " + std::string(e.description()));
  }
  const toml::node_view<toml::node> node = table.at_path(toml_path(key));
  if (!node) throw py::key_error(key + ": not in " + source + " (the scenario's default applies; docs/scenarios.md)");
  if (const auto v = node.value<bool>(); v && node.is_boolean()) return py::bool_(*v);
  if (node.is_integer()) return py::int_(*node.value<std::int64_t>());
  if (node.is_floating_point()) return py::float_(*node.value<double>());
  if (node.is_string()) return py::str(*node.value<std::string>());
  throw py::key_error(key + ": a table or array in " + source + "; name one of its keys");
}

// The text with `key` set to `value` (a bool, int, float or str) and parsed again, so an edit
// the scenario reader refuses is refused here, naming the key.
std::string scenario_with(const std::string& text, const std::string& source, const std::string& key,
                          const py::object& value) {
  toml_path(key);  // refuses an index below 1
  calibration::KeyEdit edit{key, 0.0, "", ""};
  if (py::isinstance<py::bool_>(value)) {
    edit.text = value.cast<bool>() ? "true" : "false";
  } else if (py::isinstance<py::int_>(value)) {
    edit.text = std::to_string(value.cast<long long>());
  } else if (py::isinstance<py::float_>(value)) {
    edit.value = value.cast<double>();
    if (!std::isfinite(edit.value)) throw InputError("scenario key " + key + ": expected a finite number");
  } else if (py::isinstance<py::str>(value)) {
    const std::string s = value.cast<std::string>();
    if (s.find_first_of("\"\\\n") != std::string::npos) throw InputError("scenario key " + key + ": a text without quotes, backslashes or line breaks");
    edit.text = "\"" + s + "\"";
  } else {
    throw InputError("scenario key " + key + ": expected a bool, int, float or str, got " +
                     py::str(py::type::of(value).attr("__name__")).cast<std::string>());
  }
  const std::string edited = calibration::edit_scenario_toml(text, {edit});
  parse(edited, source);
  return edited;
}

// ---------------------------------------------------------------------------------------------
// Simulation and the linearised pool

py::dict simulate(const std::string& text, const std::string& source, const std::string& experiment, bool allow_long,
                  const std::string& scheme, const py::object& progress) {
  const scenarios::Scenario s = parse(text, source);
  const scenarios::ExperimentSpec& e = experiment_of(s, experiment);
  if (scheme != "finite-volume" && scheme != "staggered") {
    throw InputError("scheme: expected \"finite-volume\" or \"staggered\", got \"" + scheme + "\"");
  }
  if (scheme == "staggered") {
    py::dict d = recording_dict(scenarios::simulate_staggered(s, e));
    d["warnings"] = std::vector<std::string>{};
    return d;
  }
  LongCall call(progress);
  scenarios::SimulateOptions options;
  options.allow_long_run = allow_long;
  options.progress = call.callback();
  std::vector<std::string> warnings;
  options.warning = [&warnings](const std::string& w) { warnings.push_back(w); };
  const Recording r = call.run([&] { return scenarios::simulate(s, e, options); });
  py::dict d = recording_dict(r);
  d["warnings"] = warnings;
  return d;
}

py::dict linearize_pool(const std::string& text, const std::string& source, const std::string& experiment,
                        const std::string& input, const std::string& output, const std::string& freq, int poles) {
  linearize::LinearizeOptions options;
  options.input = linearize::parse_input(input, "input");
  options.output = linearize::parse_output(output, "output");
  if (!freq.empty()) options.grid = linearize::parse_grid(freq, "freq");
  options.poles = poles;
  const scenarios::Scenario s = parse(text, source);
  const scenarios::ExperimentSpec& e = experiment_of(s, experiment);
  LongCall call{py::none()};
  const linearize::FrequencyResponse r = call.run([&] { return linearize::linearize(s, e, options); });
  std::vector<double> real, imag;
  for (const auto& g : r.response) {
    real.push_back(g.real());
    imag.push_back(g.imag());
  }
  py::dict d;
  d["omega_rad_s"] = to_array(r.omega);
  d["real"] = to_array(real);
  d["imag"] = to_array(imag);
  d["phase_deg"] = to_array(linearize::unwrapped_phase_degrees(r.response));
  d["input"] = r.input_name;
  d["input_unit"] = r.input_unit;
  d["output"] = r.output_name;
  d["output_unit"] = r.output_unit;
  d["static_gain"] = r.static_gain;
  d["delay_s"] = r.delay_s;
  d["sensor_delay_s"] = r.system.output_delay_s;
  d["nyquist_rad_s"] = r.system.nyquist;
  d["states"] = r.system.A.rows();
  d["operating_point"] = r.steady_state;
  d["poles"] = r.poles;
  if (r.band_fit) {
    const auto& f = *r.band_fit;
    d["prbs_band"] = py::dict(py::arg("low_rad_s") = r.band->low, py::arg("high_rad_s") = r.band->high,
                              py::arg("K") = f.gain, py::arg("T") = f.time, py::arg("lambda") = f.order,
                              py::arg("L_s") = f.delay, py::arg("rms_relative_error") = f.rms_relative_error,
                              py::arg("liom_rms_relative_error") = f.integer_rms_relative_error);
  }
  return d;
}

// ---------------------------------------------------------------------------------------------
// Reduced models

reduced::FitOptions fit_options(const std::string& criterion, double quantum_mm, double gate_speed_mm_s,
                                const std::string& memory, std::size_t memory_terms, unsigned threads) {
  reduced::FitOptions options;
  if (criterion != "ls" && criterion != "iae") throw InputError("criterion " + criterion + ": expected ls or iae");
  if (memory != "short" && memory != "full") throw InputError("memory " + memory + ": expected short or full");
  options.criterion = criterion == "iae" ? reduced::Criterion::iae : reduced::Criterion::least_squares;
  options.actuation.quantum_mm = quantum_mm;
  options.actuation.gate_speed_mm_s = gate_speed_mm_s;
  options.simulation.gl.memory = memory == "full" ? reduced::GlMemory::full : reduced::GlMemory::short_memory;
  options.simulation.gl.memory_terms = memory_terms;
  options.threads = threads;
  if (const Status status = options.validate(); !status) throw InputError(status.message());
  return options;
}

double mean_of(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v;
  return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
}

// G(iω) of a reduced model about an operating point, mm/mm (reduced_models/frequency.hpp).
py::array_t<std::complex<double>> model_frequency_response(const std::string& model,
                                                           const std::map<std::string, double>& parameters,
                                                           const std::vector<double>& omega, double u0_mm,
                                                           double y0_mm, double y_up_mm, double head_ref_mm,
                                                           double head_ref_sub_mm) {
  reduced::Model m;
  m.kind = reduced::require_model_kind(model, "model");
  for (const auto& [name, value] : parameters) reduced::set_parameter(m.p, name, value);
  m.p.head_ref_mm = head_ref_mm;
  m.p.head_ref_sub_mm = head_ref_sub_mm;
  if (const Status status = reduced::validate(m); !status) throw InputError(status.message());
  std::vector<std::complex<double>> g;
  for (double w : omega) g.push_back(reduced::frequency_response(m, {u0_mm, y0_mm, y_up_mm}, w));
  return py::array_t<std::complex<double>>(static_cast<py::ssize_t>(g.size()), g.data());
}

py::dict fit_dict(const reduced::FitResult& r, const std::vector<reduced::ExperimentData>& data,
                  const std::vector<std::size_t>& which) {
  py::dict parameters;
  for (const auto& name : reduced::parameter_names(r.model.kind)) {
    parameters[py::str(name)] = reduced::get_parameter(r.model.p, name);
  }
  py::list responses;
  for (std::size_t i = 0; i < r.sources.size(); ++i) {
    const auto& d = data[which[i]];
    responses.append(py::dict(py::arg("recording") = r.sources[i], py::arg("t_s") = to_array(d.t_s),
                              py::arg("y_dwe_mm") = to_array(d.y_dwe_mm),
                              py::arg("model_y_dwe_mm") = to_array(r.response[i]), py::arg("u0_mm") = d.u0_mm,
                              py::arg("y0_mm") = r.y0_mm.empty() ? d.y0_mm : r.y0_mm[i],
                              py::arg("y_up_mm") = mean_of(d.y_up_mm)));
  }
  // The std, its numerical part and the correlations of the parameters the fit moved.
  py::dict std, numerical_std;
  std::vector<std::string> names;
  std::vector<std::size_t> rows;
  for (std::size_t a = 0; a < r.parameter_names.size() && a < r.std.size(); ++a) {
    std[py::str(r.parameter_names[a])] = r.std[a];
    if (a < r.numerical_std.size()) numerical_std[py::str(r.parameter_names[a])] = r.numerical_std[a];
    if (r.std[a] != 0.0) {  // 0: held fixed, not fitted
      names.push_back(r.parameter_names[a]);
      rows.push_back(a);
    }
  }
  std::vector<std::vector<double>> correlation;
  for (std::size_t a : rows) {
    correlation.emplace_back();
    for (std::size_t b : rows) correlation.back().push_back(r.correlation[a][b]);
  }
  py::dict out;
  out["model"] = reduced::model_name(r.model.kind);
  out["parameters"] = parameters;
  out["std"] = std;
  out["numerical_std"] = numerical_std;
  out["std_names"] = names;
  out["correlation"] = correlation;
  out["inflation"] = r.inflation;
  out["head_ref_mm"] = r.model.p.head_ref_mm;  // H of the nonlinear models' head terms
  out["head_ref_sub_mm"] = r.model.p.head_ref_sub_mm;
  out["nrmse"] = r.nrmse;
  out["iae"] = r.iae;
  out["iae_total"] = r.iae_total;
  out["cost_total"] = r.cost_total;
  out["responses"] = responses;
  out["converged"] = r.converged;
  out["message"] = r.message;
  return out;
}

py::list fit(const std::string& model, const py::list& recordings, bool nominal, const std::string& criterion,
             double quantum_mm, double gate_speed_mm_s, const std::string& memory, std::size_t memory_terms,
             std::optional<double> upstream_level_mm, unsigned threads, const py::object& progress) {
  const reduced::ModelKind kind = reduced::require_model_kind(model, "model");
  reduced::DataOptions data_options;
  data_options.upstream_level_mm = upstream_level_mm;
  std::vector<reduced::ExperimentData> data;
  for (const Recording& r : recordings_from(recordings, false)) {
    data.push_back(reduced::prepare_data(r, data_options));
    if (reduced::uses_upstream_level(kind)) reduced::require_upstream_level(data.back(), reduced::model_name(kind));
  }
  if (data.empty()) throw InputError("fit: no recordings given");
  LongCall call(progress);
  reduced::FitOptions options = fit_options(criterion, quantum_mm, gate_speed_mm_s, memory, memory_terms, threads);
  options.progress = call.callback();
  py::list fits;
  if (nominal) {
    const reduced::FitResult r = call.run([&] { return reduced::fit_nominal(kind, data, options); });
    std::vector<std::size_t> all(data.size());
    for (std::size_t j = 0; j < all.size(); ++j) all[j] = j;
    fits.append(fit_dict(r, data, all));
    return fits;
  }
  const auto each = call.run([&] { return reduced::fit_each(kind, data, options); });
  for (std::size_t j = 0; j < each.size(); ++j) fits.append(fit_dict(each[j], data, {j}));
  return fits;
}

// ---------------------------------------------------------------------------------------------
// Calibration and diagnosis: the JSON the command line writes, its text summary, and for a
// calibration the calibrated scenario's text.

py::dict calibrate(const std::string& text, const std::string& source, const py::list& recordings,
                   const py::list& validation, const std::vector<std::string>& parameters,
                   const std::vector<std::string>& channels, const std::vector<std::string>& gate_laws, int threads,
                   int starts, int grid_refinements, bool keep_grid, bool model_forms, const std::string& replay,
                   const py::object& progress) {
  const scenarios::Scenario s = parse(text, source);
  const std::vector<Recording> fitted = recordings_from(recordings, true);
  const std::vector<Recording> held_out = recordings_from(validation, true);
  calibration::CalibrateOptions options;
  options.parameters = parameters;
  if (replay == "diagnosis") {
    options.replay = diagnosis::calibration_replay_for_diagnosis();
  } else if (replay != "recorded-upstream") {
    throw InputError("replay " + replay + ": expected diagnosis or recorded-upstream");
  }
  if (!channels.empty()) options.replay.channels = channels;
  options.threads = threads;
  options.starts = starts;
  options.grid_refinements = grid_refinements;
  options.write_grid_converged = !keep_grid;
  options.try_model_forms = model_forms;
  for (const auto& law : gate_laws) {
    if (law != "swamee" && law != "simple") throw InputError("gate_laws " + law + ": expected swamee or simple");
    options.gate_laws.push_back(law == "swamee" ? scenarios::GateLaw::swamee : scenarios::GateLaw::simple);
  }
  std::vector<std::string> warnings;
  options.replay.warning = [&warnings](const std::string& w) {
    if (warnings.size() < 3) warnings.push_back(w);
  };
  LongCall call(progress);
  options.progress = call.callback();
  const calibration::Calibration c = call.run([&] { return calibration::calibrate(s, fitted, held_out, options); });
  py::dict out;
  out["ok"] = c.ok;
  out["message"] = c.message;
  out["summary"] = calibration::text_summary(c);
  out["json"] = calibration::to_json(c).dump();
  out["warnings"] = warnings;
  if (c.ok) {
    std::vector<std::string> names;
    for (const auto& r : fitted) names.push_back(std::filesystem::path(r.source).filename().string());
    out["scenario_text"] = diagnosis::calibrated_scenario_toml(text, c, {source, names, source + " (calibrated)"});
  }
  return out;
}

py::dict diagnose(const std::string& text, const std::string& source, const py::list& recordings,
                  const py::list& baseline, const std::vector<std::string>& candidates, double fit_fraction,
                  int threads, bool recorded_upstream, bool reconstruct_clock, int search_cells,
                  const py::object& progress) {
  const scenarios::Scenario s = parse(text, source);
  const std::vector<Recording> diagnosed = recordings_from(recordings, true);
  const std::vector<Recording> reference = recordings_from(baseline, true);
  if (diagnosed.empty()) throw InputError("diagnose: no recordings given");
  for (const auto* set : {&diagnosed, &reference}) {
    for (const Recording& r : *set) {
      if (recorded_upstream && !r.has(columns::upstream_level)) {
        throw InputError(r.source + ": missing column y_up_mm: recorded_upstream drives the head gate with it");
      }
    }
  }
  if (const auto problems = diagnosis::check_recordings(s, diagnosed); !problems.empty()) {
    throw InputError(problems.front() + " (scenario " + s.name + ")");
  }
  diagnosis::DiagnoseOptions options;
  options.candidates = candidates;
  options.fit_fraction = fit_fraction;
  options.threads = threads;
  options.use_recorded_upstream = recorded_upstream;
  options.reconstruct_clock = reconstruct_clock;
  options.search_max_cells = search_cells;
  LongCall call(progress);
  py::dict out;
  if (reference.empty()) {
    options.progress = call.callback();
    const diagnosis::Diagnosis d = call.run([&] { return diagnosis::diagnose(s, diagnosed, options); });
    out["ok"] = d.ok;
    out["message"] = d.message;
    out["summary"] = diagnosis::text_summary(d);
    out["json"] = diagnosis::to_json(d).dump();
    return out;
  }
  if (const auto problems = diagnosis::check_baseline(reference, diagnosed); !problems.empty()) {
    throw InputError(problems.front());
  }
  if (const auto problems = diagnosis::check_recordings(s, reference); !problems.empty()) {
    throw InputError(problems.front() + " (baseline; scenario " + s.name + ")");
  }
  diagnosis::BaselineOptions with_baseline;
  with_baseline.diagnosis = options;
  with_baseline.progress = call.callback();
  const diagnosis::BaselineDiagnosis r =
      call.run([&] { return diagnosis::diagnose_with_baseline(s, reference, diagnosed, with_baseline); });
  nlohmann::json json = diagnosis::to_json(r.diagnosis);
  json["baseline"] = diagnosis::baseline_json(r);
  out["ok"] = r.calibration.ok && r.diagnosis.ok;
  out["message"] = r.calibration.ok ? r.diagnosis.message : "calibration on the baseline failed: " + r.calibration.message;
  out["summary"] = diagnosis::baseline_summary(r) + diagnosis::text_summary(r.diagnosis);
  out["json"] = json.dump();
  return out;
}

}  // namespace
}  // namespace canalsim::python

PYBIND11_MODULE(_canalsim, m) {
  using namespace canalsim::python;
  m.doc() = "canalsim's compiled core; use the functions of the canalsim package (help(canalsim)).";
  // A ValueError too, so code catching ValueError for bad input catches it.
  py::register_exception<canalsim::InputError>(m, "InputError", PyExc_ValueError);

  m.def("builtin_scenarios", [] {
    std::vector<std::string> names;
    for (const auto& b : canalsim::scenarios::builtin_scenarios()) names.push_back(b.name);
    return names;
  });
  m.def("scenario_text", &canalsim::scenarios::scenario_toml_text);
  m.def("experiment_names", &experiment_names);
  m.def("scenario_value", &scenario_value);
  m.def("scenario_with", &scenario_with);
  m.def("read_recording", &read_recording_file);
  m.def("write_recording", &write_recording_file);
  m.def("check_recording", [](const py::dict& d) { return recording_dict(recording_from_dict(d)); });
  m.def("simulate", &simulate);
  m.def("linearize", &linearize_pool);
  m.def("fit", &fit);
  m.def("model_frequency_response", &model_frequency_response);
  m.def("calibrate", &calibrate);
  m.def("diagnose", &diagnose);
}
