#!/usr/bin/env python3
"""The README's picture: the laboratory canal's op1 experiment simulated by canalsim, the
fractional-order model (LFOM) fitted to it, and the gate command that drove both.

    python3 examples/overview.py [OUT.png]          (default: docs/img/overview.png)

A few seconds. Needs the package (`scripts/demo` installs it; or PYTHONPATH=BUILD/python) and
matplotlib (Debian's python3-matplotlib). Writes a 900 x 450 px PNG.
"""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt

import canalsim

WINDOW_S = 60.0  # the first 60 s of the 255.5 s PRBS: the steps stay readable


def main():
    out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path("docs/img/overview.png")
    recording = canalsim.simulate("lab", "op1")  # Saint-Venant flume, Swamee gates, PRBS command
    fit = canalsim.fit("lfom", recording)  # T D^λ Δy + Δy = K Δu(t − L), least-squares polish
    p, s = fit.parameters, fit.std
    summary = (f"LFOM: K {p['K']:.3f} ± {s['K']:.3f} mm/mm, T {p['T']:.2f} ± {s['T']:.2f} s, "
               f"λ {p['lambda']:.3f} ± {s['lambda']:.3f}, L {p['L']:.3f} ± {s['L']:.3f} s; "
               f"Nrmse {fit.nrmse[0]:.1f} %")

    shown = recording[recording["t_s"] <= WINDOW_S]
    response = fit.response[fit.response["t_s"] <= WINDOW_S]
    fig, (level_ax, gate_ax) = plt.subplots(
        2, 1, figsize=(9, 4.5), dpi=100, sharex=True, gridspec_kw={"height_ratios": [2.2, 1]})
    level_ax.plot(shown["t_s"], shown["y_dwe_mm"], color="0.55", lw=2.2,
                  label="recorded level y_dwe (simulated lab canal, op1)")
    level_ax.plot(response["t_s"], response["model_y_dwe_mm"], color="tab:red", lw=1.1,
                  label="fitted LFOM")
    level_ax.set_ylabel("level [mm]")
    level_ax.set_title(summary, loc="left", fontsize=9)
    low, high = shown["y_dwe_mm"].min(), shown["y_dwe_mm"].max()
    level_ax.set_ylim(low - 0.3, high + 0.45 * (high - low))  # room for the legend above the data
    level_ax.legend(fontsize=8, loc="upper left", ncol=2)
    level_ax.grid(alpha=0.3)
    gate_ax.step(shown["t_s"], shown["u_mm"], where="post", color="tab:blue", lw=1.0)
    gate_ax.set_ylabel("gate [mm]")
    gate_ax.set_xlabel("time [s]")
    gate_ax.set_xlim(0, WINDOW_S)
    gate_ax.grid(alpha=0.3)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    print(summary)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
