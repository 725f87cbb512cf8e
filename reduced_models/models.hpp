// The reduced models of the main pool (paper Section 3), in deviations from the operating point
// (u0, y0): Δu(t) = u(t) − u0, Δy_dwe(t) = y_dwe(t) − y0.
//
//   LIOM    (eq. 3–4)   T D Δy + Δy = K Δu(t − L)
//   SOPD    (eq. 5)     Δy = K e^{−Ls} / ((T s + 1)(T2 s + 1)) Δu
//   LFOM    (eq. 6–7)   T D^λ Δy + Δy = K Δu(t − L)
//   NLIOM-F (eq. 12)    T D Δy + Δy = K (y_up(t)/H)^γ Δu(t − L)
//   NLFOM-F (eq. 13)    T D^λ Δy + Δy = K (y_up(t)/H)^γ Δu(t − L)
//   NLIOM-S (eq. 14)    T D Δy + Δy = K ((y_up(t) − y_dwe(t))/H)^γ Δu(t − L)
//   NLFOM-S (eq. 15)    T D^λ Δy + Δy = K ((y_up(t) − y_dwe(t))/H)^γ Δu(t − L)
//   ID                  dΔy/dt = K Δu(t − L)            integrator plus delay (Schuurmans et
//                                                        al. 1999); K in mm/(mm·s)
//   IDZ                 Δy = K (1/s + Tz) e^{−Ls} Δu     integrator-delay-zero (Litrico &
//                                                        Fromion 2004): the integrator plus the
//                                                        direct (high-frequency) gain K·Tz
//   hybrid              T D^λ Δy + Δy = g(t) Δu(t − L), where g is the free-flow term
//                       K (y_up/H)^γ while condition (8) holds and the submerged term
//                       K_sub ((y_up − y_dwe)/H_sub)^γ_sub under condition (10).
//
// Head reference H (mm). The paper writes K · y_up^γ with levels in mm; with γ up to 10 that
// makes K span twenty orders of magnitude across γ. Here the head is divided by a reference
// head H (by default the mean head of the fitted data), so K stays the incremental gain at the
// operating point; the paper's gain is K_paper = K / H^γ (see paper_gain()). y_up(t) is the
// absolute upstream level (recorded, or a constant option); y_dwe(t) inside the submerged head is
// the model's own absolute output y0 + Δy (one sample behind, which keeps the GL step explicit).
// A negative submerged head is clamped to zero (no flow law applies there).
//
// Every model can include the gate rate limit (eq. 16, gate speed v, applied to the absolute
// command before the deviations are taken) and the output quantisation (eq. 17, resolution r,
// applied to the absolute output).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "reduced_models/data.hpp"
#include "reduced_models/gl.hpp"

namespace canalsim::reduced {

enum class ModelKind { liom, sopd, lfom, nliom_f, nlfom_f, nliom_s, nlfom_s, hybrid, id, idz };

// "liom", "sopd", "lfom", "nliom-f", "nlfom-f", "nliom-s", "nlfom-s", "hybrid", "id", "idz".
std::string model_name(ModelKind kind);
// Parses a model name (case-insensitive, '_' accepted for '-'); nullopt when unknown.
std::optional<ModelKind> parse_model_kind(const std::string& name);
std::vector<ModelKind> all_model_kinds();
// parse_model_kind, or InputError "<option> NAME: unknown model (expected liom, sopd, ...)".
ModelKind require_model_kind(const std::string& name, const std::string& option = "--model");

bool is_fractional(ModelKind kind);     // λ is a parameter (lfom, nlfom-*, hybrid)
bool uses_upstream_level(ModelKind kind);  // nonlinear models need y_up
bool uses_gamma(ModelKind kind);        // γ is a parameter
bool is_linear_time_invariant(ModelKind kind);  // liom, sopd, lfom, id, idz
bool is_integrating(ModelKind kind);    // id, idz: no time constant, K in mm/(mm·s)

// Model parameters; fields a model does not use keep their defaults and are ignored.
struct ModelParameters {
  double K = 1.0;          // static gain, mm/mm (nonlinear models: at head H)
  double T = 1.0;          // time constant, s (SOPD: T1)
  double T2 = 0.5;         // SOPD second time constant, s
  double lambda = 1.0;     // fractional order λ (integer models: 1)
  double gamma = 0.5;      // flow-law exponent γ (free-flow term for hybrid)
  double L = 0.0;          // delay, s (any real value ≥ 0: fractional samples interpolated)
  double K_sub = 1.0;      // hybrid: submerged-flow gain
  double gamma_sub = 0.5;  // hybrid: submerged-flow exponent
  double Tz = 0.0;         // IDZ: zero time constant, s (direct gain K·Tz, mm/mm)
  double head_ref_mm = 0.0;      // H of the free-flow (or only) head term; 0 = from the data
  double head_ref_sub_mm = 0.0;  // H of the hybrid's submerged head term; 0 = from the data
};

// Actuator and sensor effects (eqs. 16–17); zero disables each.
struct Actuation {
  double gate_speed_mm_s = 0.0;  // v in eq. 16; 0 = the gate follows u instantly
  double quantum_mm = 0.0;       // r in eq. 17 (paper: 0.05 mm); 0 = no quantisation
  [[nodiscard]] Status validate() const;
};

struct Model {
  ModelKind kind = ModelKind::lfom;
  ModelParameters p;
  Actuation actuation;
};

// Names of the parameters of a model in a fixed order, e.g. {"K","T","lambda","L"} for LFOM.
std::vector<std::string> parameter_names(ModelKind kind);
// Access by name ("K", "T", "T2", "lambda", "gamma", "L", "K_sub", "gamma_sub", "Tz").
double get_parameter(const ModelParameters& p, const std::string& name);
void set_parameter(ModelParameters& p, const std::string& name, double value);

// Ok when the parameters are usable for `kind`, else one line naming the field ("p.L = -1: ...").
[[nodiscard]] Status validate(const Model& model);

// Flow regime test of the paper: free when y_up > 0.81 y_dwe (y_dwe / x_up)^0.72 (eq. 8),
// submerged otherwise (eq. 10; y_up ≤ y_dwe is reported as submerged too).
bool is_free_flow(double y_up_mm, double y_dwe_mm, double x_up_mm);
// y_lc of eq. 23.
double free_flow_limit_mm(double y_dwe_mm, double x_up_mm);

// Gate position under the rate limit (eq. 16) for command u, starting at u[0].
std::vector<double> rate_limit(const std::vector<double>& u_mm, double h, double speed_mm_s);
// r · nint(y / r) (eq. 17).
double quantise(double y, double r);

// Fills head_ref_mm (and head_ref_sub_mm) where they are 0 with the mean head over `data`.
void set_head_references(Model& model, const std::vector<const ExperimentData*>& data);
// The paper's gain for the nonlinear models, K / H^γ (levels in mm).
double paper_gain(const Model& model);

struct SimulationOptions {
  GlOptions gl;  // short memory with N = 500 by default, as in the paper
  [[nodiscard]] Status validate() const { return Validator().nested("gl", gl.validate()).status(); }
};

struct SimulationResult {
  std::vector<double> y_dwe_mm;  // absolute model output, y0 + Δy (quantised if r > 0)
  std::vector<int> regime;       // hybrid only: 1 = free flow, 0 = submerged, per sample
};

// Simulates `model` driven by the input of `data` (its u, y_up, operating point and h).
// Throws InputError when the model needs y_up and data has none; std::invalid_argument on
// invalid parameters.
SimulationResult simulate(const Model& model, const ExperimentData& data,
                          const SimulationOptions& options = {});

// The input deviation Δu = x_up − u0 after the rate limit of `actuation` (undelayed).
std::vector<double> input_deviation(const ExperimentData& data, const Actuation& actuation);

// The integer-order models (LIOM, SOPD, NLIOM-*, and the fractional ones at λ = 1 exactly) are
// simulated by the exact zero-order-hold discretisation (zoh.hpp); the others by GL (gl.hpp),
// whose output is stamped at the end of each step (the level at t_k is GL's x_{k−1}).
bool is_integer_order(const Model& model);

// For a linear time-invariant model: the response to a delay of (d + frac) samples is (1 − w)
// y^{(d)} + w y^{(d+1)} (responses delayed by whole samples) with the returned w — frac for GL
// and the integrators, zoh_delay_weight for the ZOH lag; nullopt when no such blend is exact
// (SOPD's two modes, the nonlinear models).
std::optional<double> delay_interpolation_weight(const Model& model, double h, double frac);

// The input Δu delayed by L seconds (linear interpolation between samples; zero before t = 0),
// after the rate limit of `actuation`.
std::vector<double> delayed_input(const ExperimentData& data, const Actuation& actuation, double L);

// Delays a sequence by L/h samples with linear interpolation (zero before the start).
void fractional_delay(const std::vector<double>& x, double delay_samples, std::vector<double>& out);
// Delays by floor(delay_samples) whole samples and blends with the next one with weight `frac`:
// out_k = (1 − frac) x_{k−d} + frac x_{k−d−1}.
void blended_delay(const std::vector<double>& x, double delay_samples, double frac,
                   std::vector<double>& out);

}  // namespace canalsim::reduced
