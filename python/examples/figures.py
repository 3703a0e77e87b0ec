"""The paper's kind of figures from Python, with matplotlib: the tuning-curve family with the
safe region's edge, a trajectory crossing a limit, and a frequency response.

    python python/examples/figures.py --out out/python

Writes tuning-family.png, crossing.png and response.png (and .svg) into --out.
"""

import argparse
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
# The same figure is the same file (ids from a fixed salt), its words kept as text (read by
# scripts/plots.sh --check, and by a reader's search).
matplotlib.rcParams["svg.hashsalt"] = "de-resonator"
matplotlib.rcParams["svg.fonttype"] = "none"
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import de_resonator as dr  # noqa: E402

# A colour-blind safe cycle (Okabe and Ito).
COLOURS = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"]


def tuning_family(device, path):
    """f against the bias for five pre-stretches λ1p (λ2p the device's), each ending at its
    limit; the safe region's edge (the highest bias within the margin) marked on each."""
    ones = np.linspace(1.6, 2.4, 5)
    fig, ax = plt.subplots(figsize=(6, 4), constrained_layout=True)
    for colour, curve in zip(COLOURS, device.family(prestretch_1=list(ones), points=300)):
        if curve.problem:
            continue
        safe = ~curve.beyond_margin
        label = f"λ1p = {curve.prestretch_1:.1f}"
        ax.plot(curve.bias_volts[safe] / 1e3, curve.natural_frequency_hz[safe], color=colour,
                label=label)
        ax.plot(curve.bias_volts[~safe] / 1e3, curve.natural_frequency_hz[~safe], color=colour,
                linestyle=":")
        edge = curve.max_bias_volts
        ax.plot(edge / 1e3, device_frequency(device, curve, edge), "o", color=colour, ms=5)
        ax.plot(curve.limit["volts"] / 1e3, curve.limit["natural_frequency_hz"], "x",
                color=colour, ms=6)
    ax.set_xlabel("bias voltage, kV")
    ax.set_ylabel("natural frequency, Hz")
    ax.set_title("Tuning curves of the reference device (λ2p = 2)")
    ax.plot([], [], "ko", ms=5, label="safe edge (5% margin)")
    ax.plot([], [], "kx", ms=6, label="limit (model.md §6)")
    ax.legend(fontsize=8, loc="best")
    save(fig, path)


def device_frequency(device, curve, volts):
    """The frequency at `volts` on this curve's device."""
    keys = device.to_dict()
    keys.update(prestretch_1=curve.prestretch_1, prestretch_2=curve.prestretch_2)
    return dr.Device(**keys).frequency(volts)


def crossing(device, path):
    """A drive near the limit: the stretch against time until it crosses, the crossing
    marked with its mode."""
    limit = device.safe().limit
    bias = 0.97 * limit["volts"]
    run = dr.simulate(device, bias, ac_volts=0.06 * limit["volts"], ac_hz=20.0,
                      duration_seconds=0.3)
    fig, ax = plt.subplots(figsize=(6, 3.5), constrained_layout=True)
    ax.plot(run.t * 1e3, run.y[0], color=COLOURS[0], label="stretch λ")
    ax.axhline(limit["stretch"], color=COLOURS[1], linestyle="--",
               label=f"static {limit['mode']} stretch")
    if run.status == 1:
        [t] = run.t_events[0]
        [[stretch, _]] = run.y_events[0]
        ax.plot(t * 1e3, stretch, "o", color=COLOURS[1],
                label=f"{run.limit} crossed at {t * 1e3:.1f} ms")
    ax.set_xlabel("time, ms")
    ax.set_ylabel("stretch λ")
    ax.set_title(f"{bias / 1e3:.2f} kV bias with 6% AC at 20 Hz")
    ax.legend(fontsize=8, loc="lower right")
    save(fig, path)


def response(device, path, damping=5e-4):
    """The steady swing of the stretch against the drive's frequency at a bias, from the
    simulated motion (the last periods of each run), with the natural frequency marked."""
    bias = 5000.0
    f0 = device.frequency(bias)
    keys = device.to_dict()
    keys["damping"] = damping
    damped = dr.Device(**keys)
    drives = np.linspace(0.7 * f0, 1.3 * f0, 41)
    swings = []
    for hz in drives:
        run = dr.simulate(damped, bias, ac_volts=50.0, ac_hz=hz, duration_seconds=4.0,
                          step_seconds=1 / (32 * hz))
        tail = run.y[0][run.t > 3.0]
        swings.append(0.5 * np.ptp(tail))
    fig, ax = plt.subplots(figsize=(6, 3.5), constrained_layout=True)
    ax.plot(drives, swings, "o-", color=COLOURS[0], ms=3)
    ax.axvline(f0, color=COLOURS[1], linestyle="--", label=f"f0 = {f0:.2f} Hz at {bias:.0f} V")
    ax.set_xlabel("drive frequency, Hz")
    ax.set_ylabel("stretch amplitude")
    ax.set_title(f"Frequency response: 50 V AC on {bias:.0f} V, c = {damping} N·s")
    ax.legend(fontsize=8)
    save(fig, path)


def save(fig, path):
    fig.savefig(path.with_suffix(".png"), dpi=120)
    # No date in the SVG: the same figure is the same file.
    fig.savefig(path.with_suffix(".svg"), metadata={"Date": None})
    plt.close(fig)
    print(f"wrote {path.with_suffix('.png')} and .svg")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="out/python", help="folder for the figures")
    args = parser.parse_args(argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    device = dr.Device.reference()
    tuning_family(device, out / "tuning-family")
    crossing(device, out / "crossing")
    response(device, out / "response")


if __name__ == "__main__":
    sys.exit(main())
