"""fit against truths of another form: an LFOM recording made by numerical Laplace inversion of its
transfer function (not by canalsim's Grünwald–Letnikov simulation), with sensor noise and
quantisation; and the command line's fit of the same file."""

import json

import numpy as np
import pandas as pd
import pytest

import canalsim


def talbot_step_response(order, time_constant, t, terms=32):
    """y(t) of 1 / (T s^λ + 1) for a unit step: the inverse Laplace transform of
    1 / (s (T s^λ + 1)) by the fixed Talbot contour (Abate & Valkó 2004), t > 0."""
    t = np.asarray(t, dtype=float)
    r = 2.0 * terms / (5.0 * t)
    theta = np.arange(1, terms) * np.pi / terms
    cot = 1.0 / np.tan(theta)
    s = r[:, None] * theta * (cot + 1j)
    sigma = theta + (theta * cot - 1.0) * cot
    transform = 1.0 / (s * (time_constant * s**order + 1.0))
    total = 0.5 * np.exp(r * t) / (r * (time_constant * r**order + 1.0))
    total = total + np.sum(np.real(np.exp(t[:, None] * s) * transform * (1.0 + 1j * sigma)), axis=1)
    return r / terms * total


def lfom_recording(K, T, order, L, seed, samples=4000, h=0.13, clock_samples=20, noise_mm=0.05, quantum_mm=0.05):
    """A PRBS-like command switching every `clock_samples` samples (±5 mm about 20 mm) through
    K e^{-Ls} / (T s^λ + 1), the level read by a sensor with white noise and a resolution. The
    command switches on the sample grid, so the output is the command's steps convolved with the
    step response at the lags k h − L."""
    rng = np.random.default_rng(seed)
    t = np.arange(samples) * h
    u = np.full(samples, 20.0)
    for start in range(150, samples, clock_samples):
        u[start:] = 20.0 + 5.0 * rng.choice([-1.0, 1.0])
    steps = np.diff(u, prepend=20.0)
    lag = t - L
    response = np.zeros(samples)
    response[lag > 0] = K * talbot_step_response(order, T, lag[lag > 0])
    y = 40.0 + np.convolve(steps, response)[:samples]
    y = quantum_mm * np.round((y + rng.normal(0.0, noise_mm, samples)) / quantum_mm)
    return pd.DataFrame({"t_s": t, "u_mm": u, "y_dwe_mm": y})


def test_the_talbot_generator_meets_the_first_order_closed_form():
    t = np.linspace(0.05, 20.0, 50)
    np.testing.assert_allclose(talbot_step_response(1.0, 1.25, t), 1.0 - np.exp(-t / 1.25), atol=1e-8)


TRUTH = {"K": 0.9, "T": 1.25, "lambda": 0.41, "L": 4.9}


def test_an_lfom_of_another_form_is_recovered_within_three_standard_deviations():
    fit = canalsim.fit("lfom", lfom_recording(**{"order" if k == "lambda" else k: v for k, v in TRUTH.items()}, seed=3))
    assert fit.converged
    for name, true in TRUTH.items():
        std = fit.std[name]
        assert np.isfinite(std) and 0.0 < std < 0.2 * abs(true), (name, std)
        assert abs(fit.parameters[name] - true) < 3.0 * std, (name, fit.parameters[name], std)
    assert list(fit.correlation.index) == list(TRUTH)
    assert np.allclose(np.diag(fit.correlation), 1.0)


def test_the_standard_deviation_is_not_too_small_over_noise_seeds():
    # Were the std ten times too small, |error| < 2 std would hold in almost none of the seeds.
    inside = 0
    seeds = range(10, 16)
    for seed in seeds:
        fit = canalsim.fit("lfom", lfom_recording(0.9, 1.25, 0.41, 4.9, seed=seed))
        inside += abs(fit.parameters["K"] - 0.9) < 2.0 * fit.std["K"]
    assert inside >= 4, f"K within 2 std in {inside} of {len(seeds)} seeds"


def test_fit_equals_the_command_lines_fit_of_the_same_file(cli, tmp_path):
    recording = lfom_recording(0.9, 1.25, 0.41, 4.9, seed=5, samples=2000)
    canalsim.write_recording(recording, tmp_path / "lfom.csv")
    cli("fit", "-m", "lfom", tmp_path / "lfom.csv", "--json", tmp_path / "fit.json")
    expected = json.loads((tmp_path / "fit.json").read_text())["fits"][0]
    fit = canalsim.fit("lfom", tmp_path / "lfom.csv")
    for name, value in expected["parameters"].items():
        assert fit.parameters[name] == pytest.approx(value, rel=1e-12), name
    assert fit.nrmse[0] == pytest.approx(expected["recordings"][0]["nrmse"], rel=1e-12)
    assert np.allclose(fit.response["model_y_dwe_mm"], expected["recordings"][0]["model_y_dwe_mm"], rtol=1e-12)
    for name, value in expected["std"].items():
        assert fit.std[name] == pytest.approx(value, rel=1e-9), name
        assert fit.numerical_std[name] == pytest.approx(expected["numerical_std"][name], rel=1e-9, abs=1e-15), name
