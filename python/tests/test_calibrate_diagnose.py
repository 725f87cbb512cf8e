"""calibrate and diagnose: the command line's results from the same inputs, on recordings of a
canal that differs from the scenario (a head gate passing 6 % more than its law says)."""

import json

import numpy as np
import pytest

import canalsim


@pytest.fixture(scope="module")
def recording_of_a_freer_gate(tmp_path_factory):
    truth = canalsim.Scenario("lab")
    truth["head_gate.discharge_coefficient"] = 1.06
    df = canalsim.simulate(truth, "op3")
    path = tmp_path_factory.mktemp("freer") / "op3.csv"
    canalsim.write_recording(df, path)
    return path


def test_calibrate_equals_the_command_line_and_finds_the_coefficient(cli, tmp_path, recording_of_a_freer_gate):
    flags = ["--params", "cd_free,cd_submerged", "--grid-refinements", "0", "--starts", "1"]
    cli("calibrate", "--scenario", "lab", recording_of_a_freer_gate, *flags, "-o", tmp_path / "cal.toml",
        "--json", tmp_path / "cal.json")
    expected = json.loads((tmp_path / "cal.json").read_text())
    result = canalsim.calibrate("lab", recording_of_a_freer_gate, params=["cd_free", "cd_submerged"],
                                grid_refinements=0, starts=1)
    assert result.ok, result.message
    for row in expected["parameters"]:
        assert result.estimates.loc[row["name"], "value"] == pytest.approx(row["value"], rel=1e-9)
        assert result.estimates.loc[row["name"], "std"] == pytest.approx(row["std"], rel=1e-6)
        assert row["value"] == pytest.approx(1.06, abs=0.01)  # the truth, up to the sensors' 0.05 mm steps
    value = result.estimates.loc["cd_free", "value"]
    # The calibrated scenario is the file the command line wrote, and it carries the estimate.
    assert result.scenario.text == (tmp_path / "cal.toml").read_text()
    assert result.scenario["head_gate.discharge_coefficient"] == pytest.approx(value, rel=1e-8)
    # The whole JSON is the command line's, but for the time it took.
    ours, theirs = dict(result.json), dict(expected)
    for j in (ours, theirs):
        j.pop("seconds", None)
    assert json.dumps(ours, sort_keys=True) == json.dumps(theirs, sort_keys=True)
    assert "cd_free" in result.summary


def test_diagnose_equals_the_command_line(cli, tmp_path, recording_of_a_freer_gate):
    candidates = "discharge_coefficient,friction"
    cli("diagnose", "--scenario", "lab", recording_of_a_freer_gate, "--candidates", candidates,
        "--json", tmp_path / "d.json")
    expected = json.loads((tmp_path / "d.json").read_text())
    result = canalsim.diagnose("lab", recording_of_a_freer_gate, candidates=candidates.split(","))
    assert result.ok
    assert result.verdict == expected["verdict"]
    # The whole JSON is the command line's, but for the time it took.
    ours, theirs = dict(result.json), dict(expected)
    for j in (ours, theirs):
        j.pop("seconds", None)
    assert json.dumps(ours, sort_keys=True) == json.dumps(theirs, sort_keys=True)
    assert result.explanation == expected["explanation"]


def test_diagnose_searches_on_the_grid_the_command_line_would(cli, tmp_path, recording_of_a_freer_gate):
    # The lab's 100 cells, searched on 50 as --search-cells 50 does; the JSON names both grids.
    candidates = "discharge_coefficient,friction"
    cli("diagnose", "--scenario", "lab", recording_of_a_freer_gate, "--candidates", candidates,
        "--search-cells", "50", "--json", tmp_path / "d.json")
    expected = json.loads((tmp_path / "d.json").read_text())
    result = canalsim.diagnose("lab", recording_of_a_freer_gate, candidates=candidates.split(","), search_cells=50)
    assert result.json["grid"] == {"model_cells": 100, "search_cells": 50} == expected["grid"]
    assert result.verdict == expected["verdict"] == "discharge_coefficient"
    assert result.explanation == expected["explanation"]
    with pytest.raises(canalsim.InputError, match="search_max_cells"):
        canalsim.diagnose("lab", recording_of_a_freer_gate, candidates=["friction"], search_cells=-1)


def test_progress_reaches_the_callable_and_its_exception_stops_the_work():
    reports = []
    canalsim.simulate("lab", "op1", progress=lambda fraction, message: reports.append(fraction))
    assert len(reports) > 10
    assert all(0.0 <= f <= 1.0 for f in reports) and reports == sorted(reports)

    class Enough(Exception):
        pass

    def stop_at_half(fraction, message):
        if fraction > 0.5:
            raise Enough(message)

    with pytest.raises(Enough):
        canalsim.simulate("lab", "op1", progress=stop_at_half)


def test_ctrl_c_stops_a_long_call_with_keyboard_interrupt():
    import os
    import signal

    def press_ctrl_c(fraction, message):
        if fraction > 0.2:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        canalsim.simulate("lab", "op1", progress=press_ctrl_c)
    # Python's own handler is back: a later call runs to the end.
    assert len(canalsim.simulate("lab", "op1")) > 1000
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_long_call_releases_the_gil():
    # While a simulation runs in another thread, this thread keeps running Python: the longest
    # pause between its steps stays far below the simulation's duration (holding the GIL, the
    # pause would be the whole run).
    import threading
    import time

    stamps = []
    done = threading.Event()

    def run():
        start = time.perf_counter()
        canalsim.simulate("lab", "op1")
        stamps.append(("duration", time.perf_counter() - start))
        done.set()

    worker = threading.Thread(target=run)
    worker.start()
    ticks = [time.perf_counter()]
    while not done.is_set():
        ticks.append(time.perf_counter())
    worker.join()
    duration = stamps[0][1]
    longest_pause = max(b - a for a, b in zip(ticks, ticks[1:]))
    assert longest_pause < 0.5 * duration, (longest_pause, duration)
