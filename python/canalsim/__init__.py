"""canalsim from Python: Saint-Venant simulations of irrigation canals, reduced models fitted to
recordings, calibration and diagnosis — the library the ``canalsim`` command runs, with numpy and
pandas (docs/python.md).

    >>> import canalsim
    >>> df = canalsim.simulate("lab", "op1")            # the recording as a DataFrame
    >>> fit = canalsim.fit("lfom", df)                 # parameters, std, nrmse, response
    >>> fit.parameters["lambda"], fit.std["lambda"]

Recordings are DataFrames with canalsim's columns (t_s, u_mm, y_dwe_mm, ...; docs/recording-format.md)
and their metadata in ``df.attrs``; wherever a recording is taken, a path to a CSV file is taken
too. Bad input raises :class:`InputError` with the command line's one-line message. Long calls
(simulate, fit, calibrate, diagnose) release the GIL, report to an optional
``progress(fraction, message)`` callable and stop on Ctrl-C with KeyboardInterrupt.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence, Union

import numpy as np
import pandas as pd

from . import _canalsim, _frames
from ._canalsim import InputError

__all__ = [
    "InputError", "Scenario", "scenarios", "simulate", "read_recording", "write_recording", "fit", "FitResult",
    "calibrate", "Calibration", "diagnose", "Diagnosis", "linearize",
]

Progress = Optional[Callable[[float, str], None]]
Recordings = Union[_frames.Recording, Sequence[_frames.Recording]]


def scenarios() -> List[str]:
    """The built-in scenarios' names (``canalsim scenarios``)."""
    return list(_canalsim.builtin_scenarios())


class Scenario:
    """A canal and its experiments, as a TOML scenario file describes them (docs/scenarios.md).

    ``Scenario("lab")`` is a built-in, ``Scenario("my.toml")`` a file. Keys are read and set by
    their TOML names, arrays 1-based as in the files: ``s["pools[1].manning_n"] = 0.011``.
    Every edit is checked by the scenario reader at once (an invalid value raises InputError);
    ``text`` is the TOML text, with its comments, that ``save`` writes.
    """

    def __init__(self, name_or_path: Union[str, os.PathLike], *, text: Optional[str] = None):
        self.source = os.fspath(name_or_path)
        self.text = _canalsim.scenario_text(self.source) if text is None else text
        self.experiments: List[str] = list(_canalsim.experiment_names(self.text, self.source))

    @classmethod
    def from_text(cls, text: str, source: str = "scenario text") -> "Scenario":
        """A scenario from TOML text; `source` names it in messages."""
        return cls(source, text=text)

    def __getitem__(self, key: str):
        return _canalsim.scenario_value(self.text, self.source, key)

    def __setitem__(self, key: str, value) -> None:
        if isinstance(value, np.generic):
            value = value.item()
        self.text = _canalsim.scenario_with(self.text, self.source, key, value)
        self.experiments = list(_canalsim.experiment_names(self.text, self.source))

    def copy(self) -> "Scenario":
        return Scenario(self.source, text=self.text)

    def save(self, path: Union[str, os.PathLike]) -> None:
        """Writes the TOML text (atomically: an existing file is replaced only when complete)."""
        path = os.fspath(path)
        tmp = path + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(self.text)
        os.replace(tmp, path)

    def __repr__(self) -> str:
        return f"Scenario({self.source!r}, experiments={self.experiments})"


ScenarioLike = Union[str, os.PathLike, Scenario]


def _scenario_text(s: ScenarioLike):
    """(text, source) of a scenario; a name or path is read, not parsed twice."""
    if isinstance(s, Scenario):
        return s.text, s.source
    if isinstance(s, (str, os.PathLike)):
        return _canalsim.scenario_text(os.fspath(s)), os.fspath(s)
    raise TypeError(f"scenario: expected a built-in name, a path or a Scenario, got {type(s).__name__}")


def _scenario(s: ScenarioLike) -> Scenario:
    if isinstance(s, Scenario):
        return s
    if isinstance(s, (str, os.PathLike)):
        return Scenario(s)
    raise TypeError(f"scenario: expected a built-in name, a path or a Scenario, got {type(s).__name__}")


def simulate(scenario: ScenarioLike, experiment: str, *, allow_long: bool = False,
             scheme: str = "finite-volume", progress: Progress = None) -> pd.DataFrame:
    """Runs one experiment of a scenario and returns its recording (``canalsim simulate``).

    Columns t_s, u_mm, x_up_mm, y_up_mm, y_dw_mm, y_dwe_mm, q_lps, regime; the metadata
    (scenario, experiment, sensors, operating point, ...) in ``df.attrs``. A run past the cost
    ceilings (docs/scenarios.md, "Run cost") is refused unless ``allow_long``. ``scheme="staggered"``
    runs it on the second simulator, written apart from the model (``--scheme staggered``,
    docs/numerics.md §9): a truth of another scheme to test fits, calibrations and diagnoses against.
    """
    text, source = _scenario_text(scenario)
    result = _canalsim.simulate(text, source, experiment, allow_long, scheme, progress)
    for warning in result["warnings"]:
        import warnings
        warnings.warn(warning, RuntimeWarning, stacklevel=2)
    return _frames.frame(result)


def read_recording(path: Union[str, os.PathLike], *, columns: Optional[Dict[str, str]] = None) -> pd.DataFrame:
    """Reads a recording CSV file (docs/recording-format.md) into a DataFrame. ``columns`` maps
    canalsim's names to the file's, e.g. ``{"y_dwe_mm": "level", "u_mm": "gate"}``."""
    return _frames.frame(_canalsim.read_recording(os.fspath(path), dict(columns or {})))


def write_recording(df: pd.DataFrame, path: Union[str, os.PathLike]) -> None:
    """Writes a DataFrame as a recording CSV file, checked as the reader checks it; an existing
    file is replaced only when the new one is complete."""
    _canalsim.write_recording(_frames.recording(df, "DataFrame"), os.fspath(path))


@dataclass
class FitResult:
    """A reduced model fitted to one recording (or, nominal, to several; paper eq. 21).

    ``parameters`` and ``std`` by name (K, T, lambda, L, ...; the units of docs/reduced-models.md;
    std 0 for a parameter held fixed): the noise's part, widened for the residuals'
    autocorrelation (``inflation``), and the model's time step's part (``numerical_std``),
    combined; ``correlation`` a DataFrame over the fitted parameters; ``nrmse`` (%, eq. 19) and ``iae``
    (mm s, eq. 20) per recording; ``response`` a DataFrame with t_s, the recorded and the model's
    y_dwe_mm per recording.
    """
    model: str
    parameters: Dict[str, float]
    std: Dict[str, float]
    correlation: pd.DataFrame
    nrmse: List[float]
    iae: List[float]
    response: pd.DataFrame
    converged: bool
    message: str
    recordings: List[str] = field(default_factory=list)
    numerical_std: Dict[str, float] = field(default_factory=dict)
    inflation: float = float("nan")
    operating_point: Dict[str, float] = field(default_factory=dict)

    def frequency_response(self, omega) -> np.ndarray:
        """G(iω) of the fitted model about its (first) recording's operating point, in mm of
        y_dwe per mm of command, at the angular frequencies `omega` [rad/s]; the nonlinear
        models linearised there (reduced_models/frequency.hpp). Hold it against
        :func:`linearize` (in m/m, the same ratio)."""
        p = self.operating_point
        return _canalsim.model_frequency_response(self.model, self.parameters, np.asarray(omega, dtype=float).tolist(),
                                                  p["u0_mm"], p["y0_mm"], p["y_up_mm"], p["head_ref_mm"],
                                                  p["head_ref_sub_mm"])


def _fit_result(d: dict) -> FitResult:
    frames = []
    for r in d["responses"]:
        frames.append(pd.DataFrame({"recording": r["recording"], "t_s": r["t_s"], "y_dwe_mm": r["y_dwe_mm"],
                                    "model_y_dwe_mm": r["model_y_dwe_mm"]}))
    names = list(d.get("std_names", []))
    correlation = pd.DataFrame(d.get("correlation", []), index=names, columns=names)
    return FitResult(model=d["model"], parameters=dict(d["parameters"]), std=dict(d.get("std", {})),
                     correlation=correlation, nrmse=list(d["nrmse"]), iae=list(d["iae"]),
                     response=pd.concat(frames, ignore_index=True), converged=d["converged"],
                     message=d["message"], recordings=[r["recording"] for r in d["responses"]],
                     numerical_std=dict(d["numerical_std"]), inflation=d["inflation"],
                     operating_point={"u0_mm": d["responses"][0]["u0_mm"], "y0_mm": d["responses"][0]["y0_mm"],
                                      "y_up_mm": d["responses"][0]["y_up_mm"], "head_ref_mm": d["head_ref_mm"],
                                      "head_ref_sub_mm": d["head_ref_sub_mm"]})


def fit(model: str, recordings: Recordings, *, nominal: bool = False, criterion: str = "ls",
        quantum_mm: float = 0.0, gate_speed_mm_s: float = 0.0, memory: str = "short", memory_terms: int = 500,
        upstream_level_mm: Optional[float] = None, threads: int = 2,
        progress: Progress = None) -> Union[FitResult, List[FitResult]]:
    """Fits a reduced model (liom, sopd, lfom, nliom-f, nlfom-f, nliom-s, nlfom-s, hybrid, id, idz)
    to recordings, as ``canalsim fit`` does: the paper's IAE fit polished by least squares with each
    recording's operating point estimated (``criterion="iae"``: the IAE fit alone).

    One recording gives a FitResult, several a list of them (one per recording), or with
    ``nominal=True`` one model over all of them (IAE_c, eq. 21). ``quantum_mm`` and
    ``gate_speed_mm_s`` put the sensor resolution (eq. 17) and the gate's rate limit (eq. 16) into
    the model; ``memory``/``memory_terms`` choose the Grünwald–Letnikov memory of the fractional
    models (paper: short, 500 terms).
    """
    single = isinstance(recordings, (str, os.PathLike, pd.DataFrame))
    data = _frames.recordings(recordings)
    fits = [_fit_result(d) for d in _canalsim.fit(model, data, nominal, criterion, quantum_mm, gate_speed_mm_s,
                                                   memory, memory_terms, upstream_level_mm, threads, progress)]
    return fits[0] if single or nominal else fits


@dataclass
class Calibration:
    """A scenario calibrated on recordings (``canalsim calibrate``; docs/calibration.md).

    ``estimates``: a DataFrame with a row per parameter (value, std, bounds, start, ...);
    ``correlation`` between them; ``scenario`` the calibrated Scenario (what ``-o`` writes);
    ``json`` the dict ``--json`` writes; ``summary`` the printed table.
    """
    ok: bool
    message: str
    estimates: pd.DataFrame
    correlation: pd.DataFrame
    scenario: Optional[Scenario]
    json: dict
    summary: str


def calibrate(scenario: ScenarioLike, recordings: Recordings, *, validate: Recordings = (),
              params: Sequence[str] = (), channels: Sequence[str] = (), gate_laws: Sequence[str] = (),
              threads: int = 2, starts: int = 2, grid_refinements: int = 2, keep_grid: bool = False,
              model_forms: bool = False, replay: str = "diagnosis", progress: Progress = None) -> Calibration:
    """Fits a scenario's uncertain parameters to recordings, with ``canalsim calibrate``'s
    defaults; the keyword arguments are its flags (``params=["cd_free", "manning_n:0.008:0.02"]``,
    ``validate=[held-out recordings]``; ``model_forms=True`` is ``--model-forms``, its result in
    ``json["model_forms"]``). Raises InputError for bad input; a calibration that runs
    but fails returns ``ok=False`` with the reason in ``message``.
    """
    s = _scenario(scenario)
    held_out = _frames.recordings(list(validate), "validation recording") if len(validate) else []
    d = _canalsim.calibrate(s.text, s.source, _frames.recordings(recordings), held_out, list(params), list(channels),
                            list(gate_laws), threads, starts, grid_refinements, keep_grid, model_forms, replay,
                            progress)
    for warning in d["warnings"]:
        import warnings
        warnings.warn(warning, RuntimeWarning, stacklevel=2)
    j = json.loads(d["json"])
    rows = j.get("parameters", [])
    estimates = pd.DataFrame(rows).set_index("name") if rows else pd.DataFrame()
    names = list(estimates.index)
    correlation = pd.DataFrame(j.get("correlation", []), index=names, columns=names) if names else pd.DataFrame()
    calibrated = Scenario.from_text(d["scenario_text"], s.source + " (calibrated)") if d["ok"] else None
    return Calibration(ok=d["ok"], message=d["message"], estimates=estimates, correlation=correlation,
                       scenario=calibrated, json=j, summary=d["summary"])


@dataclass
class Diagnosis:
    """What a diagnosis found (``canalsim diagnose``; docs/diagnosis.md): ``verdict`` (an effect of
    the catalog, ``none`` or ``unexplained``), ``explanation`` (the effects that explain the
    mismatch, with their estimates), ``json`` the dict ``--json`` writes, ``summary`` the printed
    report."""
    ok: bool
    message: str
    verdict: str
    explanation: list
    json: dict
    summary: str


def diagnose(scenario: ScenarioLike, recordings: Recordings, baseline: Optional[Recordings] = None, *,
             candidates: Sequence[str] = (), fit_fraction: float = 0.5, threads: int = 2,
             recorded_upstream: bool = False, clock: bool = True, search_cells: int = 200,
             progress: Progress = None) -> Diagnosis:
    """Locates and explains the mismatch between a scenario and recordings, as ``canalsim
    diagnose`` does; with ``baseline`` (recordings of the canal as it was) the scenario is first
    calibrated on them (``--baseline``). ``clock=False`` is ``--no-clock``; ``search_cells`` is
    ``--search-cells`` (0: every replay on the scenario's grid)."""
    s = _scenario(scenario)
    reference = _frames.recordings(baseline, "baseline recording") if baseline is not None else []
    d = _canalsim.diagnose(s.text, s.source, _frames.recordings(recordings), reference, list(candidates),
                           fit_fraction, threads, recorded_upstream, clock, search_cells, progress)
    j = json.loads(d["json"])
    explanation = j.get("explanation", {})
    effects = explanation.get("effects", []) if isinstance(explanation, dict) else explanation
    return Diagnosis(ok=d["ok"], message=d["message"], verdict=j.get("verdict", ""), explanation=effects,
                     json=j, summary=d["summary"])


def linearize(scenario: ScenarioLike, experiment: str, *, input: str = "gate", output: str = "y_dwe",
              freq: str = "", poles: int = 6) -> pd.DataFrame:
    """The frequency response of the linearised canal at an experiment's steady state
    (``canalsim linearize``; docs/linearization.md): a DataFrame with omega_rad_s, gain, phase_deg
    (unwrapped), real, imag; ``df.attrs`` holds the static gain, the delay, the poles, the units
    and, for a PRBS experiment, the LFOM fitted over its band (``prbs_band``). ``freq`` is
    "LO:HI:N" in rad/s (default: 200 points up to half the grid's Nyquist frequency)."""
    s = _scenario(scenario)
    d = _canalsim.linearize(s.text, s.source, experiment, input, output, freq, poles)
    g = np.asarray(d["real"]) + 1j * np.asarray(d["imag"])
    df = pd.DataFrame({"omega_rad_s": d["omega_rad_s"], "gain": np.abs(g), "phase_deg": d["phase_deg"],
                       "real": d["real"], "imag": d["imag"]})
    df.attrs = {k: v for k, v in d.items() if k not in ("omega_rad_s", "real", "imag", "phase_deg")}
    return df
