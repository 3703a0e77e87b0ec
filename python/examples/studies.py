"""The driven membrane's nonlinear dynamics from Python, with matplotlib: a Poincaré section
from several starts, a bifurcation diagram over the drive frequency walked up and down (the
resonance's jump at different frequencies: hysteresis), one over the AC amplitude at twice
f0 (period doubling), and the safe drive map beside the board's own acceptance. The limits
of docs/model.md §6 are drawn on each: runs that crossed one in red.

    python python/examples/studies.py --out out/python

Writes poincare.png, bifurcation.png and drive-map.png (and .svg) into --out; prints what
each shows, and exits 1 if the board accepts a drive the full simulation sees cross a limit.
"""

import argparse
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
matplotlib.rcParams["svg.hashsalt"] = "de-resonator"
matplotlib.rcParams["svg.fonttype"] = "none"
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import de_resonator as dr  # noqa: E402

COLOURS = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"]
RED = "#d62728"
BIAS = 7450.0  # V: the reference job's 44 Hz


def save(fig, out, name):
    for ext in ("png", "svg"):
        fig.savefig(out / f"{name}.{ext}", dpi=120)
    plt.close(fig)


def poincare(device, out):
    starts = np.array([[2.19, 0.0], [2.3, 0.0], [2.05, -40.0]])
    s = dr.poincare(device, BIAS, 1200.0, 85.0, periods=150, y0=starts, quality_factor=100)
    fig, ax = plt.subplots(figsize=(6, 4), constrained_layout=True)
    for i, colour in enumerate(COLOURS[:len(starts)]):
        crossed = s.limit[i] is not None
        ax.plot(s.stretch[i], s.velocity[i], ".", color=RED if crossed else colour,
                label=f"from λ {starts[i, 0]}, {starts[i, 1]} 1/s" + (" (crossed)" if crossed else ""))
    limit = device.safe(margin=0.0).limit
    ax.axvline(limit["stretch"], color=RED, ls="--", lw=1, label=f"static limit ({limit['mode']})")
    ax.set(xlabel="stretch at t = k/f", ylabel="dλ/dt at t = k/f, 1/s",
           title=f"Poincaré section: {BIAS:.0f} V + 1200 V at 85 Hz, Q 100")
    ax.legend(fontsize=8)
    save(fig, out, "poincare")
    print(f"poincare: {len(starts)} starts, {s.stretch.shape[1]} points each, "
          f"crossings {sum(x is not None for x in s.limit)}")


def bifurcation(device, out):
    f0 = device.frequency(BIAS)
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4), constrained_layout=True)
    hz = np.linspace(0.91 * f0, 1.07 * f0, 71)
    over_hz = dr.bifurcation(device, BIAS, hz, 200.0, periods=10, transient_periods=300,
                             quality_factor=100)
    ac = np.linspace(0.0, 1500.0, 61)
    over_ac = dr.bifurcation(device, BIAS, 2 * f0, ac, periods=20, transient_periods=300,
                             quality_factor=100)
    for ax, d, xlabel, title in [
        (left, over_hz, "drive frequency, Hz", "200 V AC: the jump at f0"),
        (right, over_ac, "AC amplitude, V", f"at 2·f0 = {2 * f0:.1f} Hz: period doubling"),
    ]:
        walk = np.array(d.direction)
        for direction, colour, mark in [("up", COLOURS[0], "o"), ("down", COLOURS[1], "d")]:
            rows = np.flatnonzero(walk == direction)
            x = np.repeat(d.parameter[rows], d.stretch.shape[1])
            crossed = np.repeat([d.limit[r] is not None for r in rows], d.stretch.shape[1])
            y = d.stretch[rows].ravel()
            ax.plot(x[~crossed], y[~crossed], mark, ms=3, color=colour, label=f"walked {direction}")
            if crossed.any():
                ax.plot(x[crossed], y[crossed], mark, ms=3, color=RED, label="crossed a limit")
        ax.set(xlabel=xlabel, ylabel="stretch at t = k/f", title=title)
        ax.legend(fontsize=8)
    save(fig, out, "bifurcation")
    n = len(hz)
    up = over_hz.stretch[:n, -1]
    down = over_hz.stretch[n:, -1][::-1]
    apart = hz[np.abs(up - down) > 0.05]
    print(f"bifurcation: up and down differ between {apart.min():.2f} and {apart.max():.2f} Hz"
          if apart.size else "bifurcation: no hysteresis")


def drive_map(device, out):
    m = dr.drive_map(device, ac_volts=np.linspace(0, 3000, 13),
                     ac_hz=np.linspace(13, 106, 32), target_hz=44.0, quality_factor=100,
                     periods=80)
    fig, ax = plt.subplots(figsize=(6.5, 4), constrained_layout=True)
    hz, volts = np.meshgrid(m.ac_hz, m.ac_volts)
    ax.plot(hz[m.safe], volts[m.safe], ".", color="#999999", label="safe in the full simulation")
    ax.plot(hz[~m.safe], volts[~m.safe], "s", ms=3, color=RED, label="crossed a limit of §6")
    # Over each frequency, the top of the run of accepted amplitudes from 0 V.
    below = np.cumprod(m.accepted, axis=0).astype(bool)
    ax.plot(m.ac_hz, np.nanmax(np.where(below, volts, np.nan), axis=0), "--",
            color=COLOURS[2], label="largest the board accepts")
    f0 = m.natural_frequency_hz
    for ratio, name in [(0.5, "f0/2"), (1, "f0"), (2, "2 f0")]:
        ax.axvline(ratio * f0, color="#bbbbbb", lw=0.8)
        ax.text(ratio * f0, 0.98 * ax.get_ylim()[1], name, ha="left", va="top", fontsize=8)
    ax.set(xlabel="drive frequency, Hz", ylabel="AC amplitude, V",
           title=f"Safe drives at {m.bias_volts:.0f} V (f0 {f0:.1f} Hz, Q 100)")
    ax.legend(fontsize=8, loc="lower right")
    save(fig, out, "drive-map")
    print(f"drive map: {m.safe.sum()} of {m.safe.size} drives safe, the board accepts "
          f"{m.accepted.sum()}, {m.disagreements} accepted drives cross a limit")
    return m.disagreements


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="out/python", help="folder for the figures")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    device = dr.Device.reference()
    poincare(device, out)
    bifurcation(device, out)
    if drive_map(device, out):
        sys.exit("the board accepts drives that cross a limit")


if __name__ == "__main__":
    main()
