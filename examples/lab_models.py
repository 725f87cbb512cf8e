#!/usr/bin/env python3
"""The laboratory canal's four operating points from Python: simulate each PRBS experiment, fit
the integer- and fractional-order models (LIOM, LFOM) to its recording, and hold both against the
linearised Saint-Venant pool in frequency. Writes two PNGs and prints a table.

    python3 examples/lab_models.py [OUT_DIR]          (default: ./lab_models)

About 20 s here. Needs the package (`scripts/demo` installs it) and matplotlib (Debian's
python3-matplotlib).
"""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt
import numpy as np

import canalsim

EXPERIMENTS = ["op1", "op2", "op3", "op4"]


def fit_both(recording):
    return {model: canalsim.fit(model, recording) for model in ("liom", "lfom")}


def plot_time(ax, name, recording, fits):
    ax.plot(recording["t_s"], recording["y_dwe_mm"], color="0.6", lw=2.5, label="simulated recording")
    for model, fit in fits.items():
        ax.plot(fit.response["t_s"], fit.response["model_y_dwe_mm"], lw=1.0,
                label=f"{model.upper()} (Nrmse {fit.nrmse[0]:.1f} %)")
    ax.set_title(f"{name}: downstream-end level, the first 60 s", loc="left", fontsize=10)
    ax.set_xlim(0, 60)
    ax.set_ylabel("y_dwe [mm]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")


def plot_frequency(gain_ax, phase_ax, name, pool, fits):
    band = pool.attrs.get("prbs_band")
    omega = pool["omega_rad_s"].to_numpy()
    gain_ax.semilogx(omega, 20 * np.log10(pool["gain"]), color="black", lw=2, label="linearised pool")
    phase_ax.semilogx(omega, pool["phase_deg"], color="black", lw=2)
    for model, fit in fits.items():
        g = fit.frequency_response(omega)
        gain_ax.semilogx(omega, 20 * np.log10(np.abs(g)), lw=1, label=model.upper())
        phase_ax.semilogx(omega, np.degrees(np.unwrap(np.angle(g))), lw=1)
    for ax in (gain_ax, phase_ax):
        if band:
            ax.axvspan(band["low_rad_s"], band["high_rad_s"], color="tab:blue", alpha=0.07)
        ax.grid(which="both", alpha=0.3)
    gain_ax.set_title(name, fontsize=10)
    gain_ax.set_ylim(-60, 10)
    phase_ax.set_ylim(-1440, 30)
    phase_ax.set_xlabel("ω [rad/s]")


def main(out: pathlib.Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    time_fig, time_axes = plt.subplots(len(EXPERIMENTS), 1, figsize=(10, 11), constrained_layout=True)
    freq_fig, freq_axes = plt.subplots(2, len(EXPERIMENTS), figsize=(15, 6.5), constrained_layout=True)
    print(f"{'':5} {'LIOM K':>8} {'T':>7} {'L':>6} {'Nrmse':>7}   {'LFOM K':>8} {'T':>7} {'λ':>6} {'L':>6} {'Nrmse':>7}"
          f"   {'pool λ (PRBS band)':>18}")
    for i, name in enumerate(EXPERIMENTS):
        recording = canalsim.simulate("lab", name)
        fits = fit_both(recording)
        pool = canalsim.linearize("lab", name)
        plot_time(time_axes[i], name, recording, fits)
        plot_frequency(freq_axes[0, i], freq_axes[1, i], name, pool, fits)
        liom, lfom = fits["liom"].parameters, fits["lfom"].parameters
        band = pool.attrs.get("prbs_band") or {"lambda": float("nan")}
        print(f"{name:5} {liom['K']:8.3f} {liom['T']:7.2f} {liom['L']:6.2f} {fits['liom'].nrmse[0]:6.1f}%"
              f"   {lfom['K']:8.3f} {lfom['T']:7.2f} {lfom['lambda']:6.3f} {lfom['L']:6.2f} {fits['lfom'].nrmse[0]:6.1f}%"
              f"   {band['lambda']:18.3f}")
    time_axes[-1].set_xlabel("t [s]")
    freq_axes[0, 0].set_ylabel("gain [dB, mm/mm]")
    freq_axes[1, 0].set_ylabel("phase [deg]")
    freq_axes[0, 0].legend(fontsize=8)
    freq_fig.suptitle("Fitted models against the linearised Saint-Venant pool (shaded: the PRBS band)")
    time_fig.savefig(out / "lab_models_time.png", dpi=110)
    freq_fig.savefig(out / "lab_models_bode.png", dpi=110)
    print(f"wrote {out / 'lab_models_time.png'} and {out / 'lab_models_bode.png'}")


if __name__ == "__main__":
    main(pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "lab_models"))
