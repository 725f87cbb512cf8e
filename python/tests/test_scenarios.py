"""Scenario: keys by their TOML names, checked by the scenario reader; an edited scenario runs as
the same file would through the command line; linearize against the command line's JSON and the
pool's closed-form static gain."""

import json

import numpy as np
import pytest

import canalsim


def test_builtins_are_listed_and_a_key_reads_as_the_file_holds_it():
    assert "lab" in canalsim.scenarios()
    lab = canalsim.Scenario("lab")
    assert "op1" in lab.experiments
    assert isinstance(lab["pools[1].manning_n"], float)
    with pytest.raises(KeyError, match="no_such_key"):
        lab["pools[1].no_such_key"]


def test_an_edit_the_reader_refuses_raises_input_error_and_leaves_the_scenario_as_it_was():
    lab = canalsim.Scenario("lab")
    before = lab.text
    with pytest.raises(canalsim.InputError, match="manning_n"):
        lab["pools[1].manning_n"] = -1.0
    assert lab.text == before
    with pytest.raises(canalsim.InputError, match="indices start at 1"):
        lab["pools[0].manning_n"] = 0.01


def test_an_edited_scenario_runs_as_the_saved_file_does_through_the_command_line(cli, tmp_path):
    rough = canalsim.Scenario("lab")
    rough["pools[1].manning_n"] = 2.0 * rough["pools[1].manning_n"]
    rough.save(tmp_path / "rough.toml")
    cli("simulate", tmp_path / "rough.toml", "-e", "op3", "-o", tmp_path / "op3.csv")
    from_cli = canalsim.read_recording(tmp_path / "op3.csv")
    from_python = canalsim.simulate(rough, "op3")
    assert np.max(np.abs(from_python["y_dwe_mm"] - from_cli["y_dwe_mm"])) < 0.006  # printed to 0.01 mm
    # Twice the roughness raises the level the gate feeds into: the edit took effect.
    smooth = canalsim.simulate("lab", "op3")
    assert from_python["y_dw_mm"].iloc[0] > smooth["y_dw_mm"].iloc[0] + 0.05


def test_linearize_equals_the_command_lines_json(cli, tmp_path):
    cli("linearize", "lab", "-e", "op2", "--json", tmp_path / "op2.json")
    expected = json.loads((tmp_path / "op2.json").read_text())
    df = canalsim.linearize("lab", "op2")
    assert len(df) == len(expected["response"])
    gain = np.array([r["gain"] for r in expected["response"]])
    phase = np.array([r["phase_deg"] for r in expected["response"]])
    np.testing.assert_allclose(df["gain"], gain, rtol=1e-9)
    np.testing.assert_allclose(df["phase_deg"], phase, atol=1e-9)
    assert df.attrs["static_gain"] == pytest.approx(expected["static_gain"], rel=1e-12)
    assert df.attrs["prbs_band"]["lambda"] == pytest.approx(expected["prbs_band"]["lfom"]["lambda"], rel=1e-12)


def test_the_linearised_pools_static_gain_is_the_slope_of_the_simulated_steady_states():
    # An independent computation of G(0): the steady level at the downstream end for the operating
    # opening moved by ±1 mm (central difference), read by sensors without quantisation.
    lab = canalsim.Scenario("lab")
    lab["sensors.resolution_mm"] = 0.0
    df = canalsim.linearize(lab, "op3")
    opening = lab["experiments[3].operating_opening_mm"]
    level = {}
    for step in (-1.0, 1.0):
        moved = lab.copy()
        moved["experiments[3].operating_opening_mm"] = float(opening + step)
        level[step] = canalsim.simulate(moved, "op3")["y_dwe_mm"].iloc[:5].mean()
    slope = (level[1.0] - level[-1.0]) / 2.0  # mm per mm = m per m
    assert df.attrs["output_unit"] == "m" and df.attrs["input_unit"] == "m"
    assert df.attrs["static_gain"] == pytest.approx(slope, rel=0.02)
