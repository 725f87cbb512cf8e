#!/usr/bin/python3
"""The LFOM fit as a SciPy user writes it, for canalsim's fit to be timed against (bench/README.md).

    scipy_lfom_fit.py RECORDING.csv

The model (Gharab et al. 2019, eq. 12): T D^λ x + x = u(t − L) − u0, y = y0 + K x, D^λ by the
Grünwald–Letnikov sum with the short memory of N = 500 terms (the paper's). The recursion
x_k (c + 1) = u_k − c Σ_{j=1..N} w_j x_{k−j}, c = T / h^λ, is an all-pole filter, run by
scipy.signal.lfilter in C. The delay: a grid of delays two samples apart, each fitted over (K, T, λ, y0)
by scipy.optimize.least_squares (trust-region reflective), then the best refined with L free
(the input delayed by linear interpolation). Prints the estimates and the cost evaluations.
"""
import sys

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import lfilter

MEMORY_TERMS = 500


def read_recording(path):
    names = None
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                continue
            if names is None:
                names = line.strip().split(",")
                continue
            rows.append(line.strip().split(","))
    columns = {name: np.array([float(r[i]) for r in rows]) for i, name in enumerate(names) if name in ("t_s", "u_mm", "y_dwe_mm")}
    return columns["t_s"], columns["u_mm"], columns["y_dwe_mm"]


def gl_weights(order, n):
    w = np.empty(n + 1)
    w[0] = 1.0
    for j in range(1, n + 1):
        w[j] = w[j - 1] * (1.0 - (order + 1.0) / j)
    return w


def lfom_response(T, order, forcing, h):
    """x at the sample times: step k of the recursion integrates over [t_k, t_k+1], so its x_k is
    the level at t_k+1 (canalsim's convention, reduced_models/models.cpp)."""
    c = T / h ** order
    a = c * gl_weights(order, MEMORY_TERMS)
    a[0] += 1.0
    x = lfilter([1.0], a, forcing)
    return np.concatenate(([0.0], x[:-1]))


def delayed(u, delay_samples):
    k = np.arange(len(u)) - delay_samples
    return np.interp(k, np.arange(len(u)), u, left=u[0])


def main():
    t, u, y = read_recording(sys.argv[1])
    h = t[1] - t[0]
    u0 = u[0]
    evaluations = 0

    def residuals(p, delay_samples):
        nonlocal evaluations
        evaluations += 1
        K, T, order, y0 = p[:4]
        L = p[4] if len(p) > 4 else delay_samples * h
        x = lfom_response(T, order, delayed(u, L / h) - u0, h)
        return y0 + K * x - y

    start = [1.0, 5.0 * h, 0.8, y[0]]
    lower = [-100.0, 0.01, 0.1, -np.inf]
    upper = [100.0, 10.0 * (t[-1] - t[0]), 1.5, np.inf]
    best = None
    for delay_samples in range(0, 81, 2):  # 0 to 10.4 s, every 0.26 s at h = 0.13 s
        fit = least_squares(residuals, start, bounds=(lower, upper), args=(delay_samples,), method="trf")
        if best is None or fit.cost < best[0].cost:
            best = (fit, delay_samples)
    fit, delay_samples = best
    final = least_squares(residuals, list(fit.x) + [delay_samples * h], args=(0,),
                          bounds=(lower + [0.0], upper + [0.5 * (t[-1] - t[0])]), method="trf")
    K, T, order, y0, L = final.x
    print(f"K {K:.6g} T {T:.6g} lambda {order:.6g} L {L:.6g} y0 {y0:.6g} cost {2 * final.cost:.6g} evaluations {evaluations}")


if __name__ == "__main__":
    main()
