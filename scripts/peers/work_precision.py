#!/usr/bin/env python3
"""Error against run time, host-sim beside its peers (SciMLBenchmarks' way), on two scenes of
the reference device: our DOP853 and Radau (rtol = atol = each tolerance) and the core's
fixed-step methods (the output step divided by 1 … 16), beside SciPy's DOP853, Radau and LSODA,
numbalsoda's DOP853 (Hairer's, compiled) and CVODE's BDF (C), all with the output at the same
times and the same tolerances on the same dimensionless state.

The reference of each scene: a solve at 1e-14 checked against a second solver's at 1e-14, of
another code (REFERENCES: numbalsoda's DOP853 and host-sim's on the reference drive, both
Hairer's method written twice; SciPy's Radau and DOP853 on the stiff scene). Errors, of the
stretch against the reference: at the final time, and the L2 error over the series (the root
mean square over every output time). Times: the median of RUNS launches of the whole process
(start, solve, its summary out; the series kept in memory), and the median of the solve's own
time in those processes: host-sim's `run_seconds` (the scene's setup, the solve with the §6
monitor at every step, the outcome), the peers' timers round their solve (numbalsoda's JIT
excluded; CVODE's context made and freed). The series for the errors: host-sim writes it as
CSV in one more, untimed launch; a peer writes it (raw floats) in its first timed one.

Writes work-precision-peers.csv (a row per point), work-precision-peers.svg (in-process
time) and work-precision-peers-whole.svg (whole process) into --out. With --check (CI):
the committed figures drawn again from the committed CSV, byte for byte; then fewer points
measured (host-sim and CVODE with 5 launches each, the Python peers with --runs), each
figure's words (titles, axes, legend, the peers' versions; not tick numbers) compared with
the committed ones, each point's errors within 20% (and 10 times the references' distance)
of the committed CSV's, and its times within --slack either way (--ours-slack for host-sim's,
which CI runs in its test profile). Run by scripts/bench-peers.sh, which installs the peers.
"""
import argparse
import csv
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
KEPT = os.path.join(ROOT, "docs", "plots")

# name, title, bias V, AC V, drive Hz, damping N·s, duration s, start
SCENES = [
    ("reference", "reference drive: 7000 V + 200 V at 30 Hz, undamped, 1 s from equilibrium",
     7000.0, 200.0, 30.0, 0.0, 1.0, "equilibrium"),
    ("stiff", "stiff: c = 10 N·s, 7000 V + 200 V at 30 Hz, 1 s from the pre-stretch",
     7000.0, 200.0, 30.0, 10.0, 1.0, "prestretch"),
]
TOLERANCES = [10.0 ** -k for k in range(4, 13)]
CHECK_TOLERANCES = [1e-4, 1e-12]
DIVISIONS = [1, 2, 4, 8, 16]
CHECK_DIVISIONS = [1, 16]
# The core's fixed-step methods on each scene (explicit ones are refused on the stiff scene:
# the damping's eigenvalue, about −c/M = −2e5 1/s, bounds their stable step near 1e-5 s).
FIXED = {"reference": ["rk4-f64", "verlet-f64", "implicit-midpoint-f64", "rk4-f32"],
         "stiff": ["implicit-midpoint-f64"]}
# Each scene's reference: the first solver's solve at 1e-14, the second's at most 1e-12 from it
# (host-sim's Radau is not one: its tolerance stops at RADAU5's floor, about 1e-11 asked;
# numbalsoda's DOP853 stops at its 10,000 steps on the stiff scene).
REFERENCES = {"reference": ("numbalsoda-dop853", "host-sim reference"),
              "stiff": ("scipy-Radau", "scipy-DOP853")}
# The peers on each scene (explicit ones left out of the stiff scene, for the same reason).
PEERS = {"reference": ["scipy-DOP853", "scipy-Radau", "scipy-LSODA", "numbalsoda-dop853",
                       "cvode-bdf"],
         "stiff": ["scipy-Radau", "scipy-LSODA", "cvode-bdf"]}
LABELS = {"reference": "host-sim DOP853 (Radau once stiff)", "reference-radau": "host-sim Radau IIA 5",
          "rk4-f64": "core rk4 (f64)", "verlet-f64": "core verlet (f64)",
          "implicit-midpoint-f64": "core implicit midpoint (f64)", "rk4-f32": "core rk4 (f32)",
          "scipy-DOP853": "SciPy DOP853", "scipy-Radau": "SciPy Radau",
          "scipy-LSODA": "SciPy LSODA", "numbalsoda-dop853": "numbalsoda DOP853 (Hairer)",
          "cvode-bdf": "CVODE BDF (SUNDIALS)"}
STYLE = {"reference": ("#c0392b", "o"), "reference-radau": ("#e67e22", "s"),
         "rk4-f64": ("#8e44ad", "^"), "verlet-f64": ("#a0522d", "v"),
         "implicit-midpoint-f64": ("#d4a017", "D"), "rk4-f32": ("#ff69b4", "^"),
         "scipy-DOP853": ("#1f77b4", "o"), "scipy-Radau": ("#17becf", "s"),
         "scipy-LSODA": ("#2ca02c", "P"), "numbalsoda-dop853": ("#000080", "X"),
         "cvode-bdf": ("#555555", "*")}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--host-sim", required=True, help="the host-sim binary")
    p.add_argument("--cvode", required=True, help="scripts/peers/cvode_scene.c, compiled")
    p.add_argument("--runs", type=int, default=10, help="launches timed per point (median)")
    p.add_argument("--out", required=True, help="folder for the CSV and the figures")
    p.add_argument("--check", action="store_true",
                   help="fewer points, compared with docs/plots/ (CI)")
    p.add_argument("--scene", choices=[s[0] for s in SCENES], action="append",
                   help="only this scene (repeatable; default: all; not with --check)")
    p.add_argument("--slack", type=float, default=4.0,
                   help="--check: a peer's time may be this factor off the committed one, "
                   "after the machine's (the peers' median ratio)")
    p.add_argument("--ours-slack", type=float, default=6.0,
                   help="--check: host-sim's (the test profile's is 2–2.4× the peak build's)")
    p.add_argument("--versions", default="", help="the peers' versions, named in the figures")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.check:
        failed = redrawn(args.out, args.versions)
    tolerances = CHECK_TOLERANCES if args.check else TOLERANCES
    divisions = CHECK_DIVISIONS if args.check else DIVISIONS
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for scene in SCENES:
            if args.scene and not args.check and scene[0] not in args.scene:
                continue
            rows += study(args, scene, tolerances, divisions, tmp)
    path = os.path.join(args.out, "work-precision-peers.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    figures = figures_of(rows, args.out, args.versions)
    print(f"wrote {path}, {figures[0]}, {figures[1]}")
    if args.check:
        sys.exit(check(rows, figures, args.slack, args.ours_slack) or failed)


def figures_of(rows, out, versions):
    """Both figures of `rows` into `out`: against the solve's time and the whole process's."""
    return [plot(rows, "solve_seconds", "in process (the solve alone)", versions,
                 os.path.join(out, "work-precision-peers.svg")),
            plot(rows, "whole_seconds", "whole process (start, solve, a summary out)",
                 versions, os.path.join(out, "work-precision-peers-whole.svg"))]


def committed_rows():
    with open(os.path.join(KEPT, "work-precision-peers.csv")) as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for key in ["error_final", "error_l2", "whole_seconds", "solve_seconds",
                    "reference_apart"]:
            r[key] = float(r[key])
        r["runs"] = int(r["runs"])
    return rows


def redrawn(out, versions):
    """1 where a committed figure is not what its committed CSV draws (byte for byte)."""
    folder = os.path.join(out, "committed")
    os.makedirs(folder, exist_ok=True)
    failed = 0
    for made in figures_of(committed_rows(), folder, versions):
        kept = os.path.join(KEPT, os.path.basename(made))
        with open(made, "rb") as a, open(kept, "rb") as b:
            if a.read() != b.read():
                print(f"work_precision.py: {kept} is not what work-precision-peers.csv draws "
                      f"(with {versions or 'no versions named'})", file=sys.stderr)
                failed = 1
    return failed


def study(args, scene, tolerances, divisions, tmp):
    name, title, bias, ac, hz, damping, duration, start = scene
    print(f"== {name}: {title}", flush=True)
    common = ["--bias-volts", repr(bias), "--ac-volts", repr(ac), "--ac-hz", repr(hz),
              "--damping", repr(damping), "--duration-seconds", repr(duration),
              "--start", start]

    # The output step (host-sim's default), then the reference from a peer, checked by a
    # second independent solver.
    step = json.loads(run([args.host_sim, "--json", "simulate", *common]))["step_seconds"]

    def peer(solver, tol, series):
        """The command of a peer's solve, writing its series to `series` (None: not)."""
        out = [series] if series else []
        if solver == "cvode-bdf":
            return [args.cvode, repr(bias), repr(ac), repr(hz), repr(damping), repr(duration),
                    repr(step), repr(tol), "1", start, *out]
        if solver.startswith("host-sim "):
            return host_sim(solver.split()[1], ["--rtol", repr(tol)])(series)
        return [sys.executable, "-W", "ignore", os.path.join(HERE, "solve.py"), solver,
                repr(bias), repr(ac), repr(hz), repr(damping), repr(duration), repr(step),
                start, repr(tol), *out]

    def host_sim(method, extra):
        """host-sim's command for `method`, writing its series as CSV to `series` (None: not)."""
        return lambda series: [args.host_sim, "--json", "simulate", *common, "--method", method,
                               *extra, *(["--csv", series] if series else [])]

    pair = REFERENCES[name]
    refs = []
    for solver in pair:
        series = os.path.join(tmp, f"reference-{len(refs)}")
        run(peer(solver, 1e-14, series))
        refs.append(series_of(series))
    reference = refs[0]
    apart = float(np.max(np.abs(refs[1] - refs[0])))
    print(f"  reference: {pair[0]} at 1e-14 ({len(reference)} output times), {pair[1]} at "
          f"1e-14 at most {apart:.1e} from it", flush=True)
    if not apart < 1e-12:
        raise SystemExit(f"the two references of {name} disagree by {apart:.1e}")

    def errors(stretch):
        if len(stretch) != len(reference):
            raise SystemExit(f"{len(stretch)} output times against the reference's "
                             f"{len(reference)}")
        diff = stretch - reference
        return float(abs(diff[-1])), float(np.sqrt(np.mean(diff * diff)))

    rows = []

    def point(solver, setting, launch, read, every=1, raw=False):
        """Times `launch` (a command writing its series to the file given, or none; and how
        to read its solve time) args.runs times; the series for the errors (every `every`-th
        output time: a finer step's) from a first launch, untimed where it writes CSV
        (host-sim), else (`raw`: 2,942 floats as bytes) the first timed one. The references
        ran before: the peers' caches (bytecode, numba's) are warm."""
        series = os.path.join(tmp, "series")
        whole, inner = [], []

        def timed(cmd):
            started = time.perf_counter()
            out = run(cmd)
            whole.append(time.perf_counter() - started)
            inner.append(read(out))

        if raw:
            timed(launch(series))
        else:
            read(run(launch(series)))
        final, l2 = errors(series_of(series)[::every])
        cmd = launch(None)
        # --check's single launches: the compiled ones' (milliseconds) five times over.
        compiled = solver == "cvode-bdf" or not peer_of(solver)
        runs = max(args.runs, 5) if args.check and compiled else args.runs
        while len(whole) < runs:
            timed(cmd)
        row = {"scene": name, "solver": solver, "setting": setting, "error_final": final,
               "error_l2": l2, "whole_seconds": statistics.median(whole),
               "solve_seconds": statistics.median(inner), "runs": len(whole),
               "reference_apart": apart}
        rows.append(row)
        print(f"  {LABELS[solver]:30} {setting:>10}  final {final:8.1e}  L2 {l2:8.1e}  "
              f"whole {row['whole_seconds'] * 1e3:9.2f} ms  solve "
              f"{row['solve_seconds'] * 1e3:9.3f} ms", flush=True)

    run_seconds = lambda out: json.loads(out)["run_seconds"]  # noqa: E731
    for method in ["reference", "reference-radau"]:
        for tol in tolerances:
            point(method, f"{tol:.0e}", host_sim(method, ["--rtol", repr(tol)]), run_seconds)
    for method in FIXED[name]:
        for k in divisions:
            point(method, f"step/{k}", host_sim(method, ["--step-seconds", repr(step / k)]),
                  run_seconds, every=k)
    for solver in PEERS[name]:
        read = (lambda out: json.loads(out)["best_seconds"]) if solver == "cvode-bdf" else (
            lambda out: json.loads(out)["solve_seconds"])
        for tol in tolerances:
            point(solver, f"{tol:.0e}", lambda series, s=solver, t=tol: peer(s, t, series),
                  read, raw=True)
    return rows


def peer_of(solver):
    """Whether `solver` is a peer's (else host-sim's)."""
    return solver.startswith(("scipy", "numbalsoda", "cvode"))


def series_of(path):
    """The stretch series a launch wrote: host-sim's CSV (a finer step's every k-th row) or
    the peers' raw float64."""
    with open(path, "rb") as f:
        head = f.read(4)
    if head == b"time":
        return np.loadtxt(path, delimiter=",", skiprows=1)[:, 1]
    return np.fromfile(path)


def run(cmd):
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({done.returncode}): {done.stderr.strip()}")
    return done.stdout


def plot(rows, time_key, what, versions, path):
    import matplotlib

    matplotlib.use("svg")
    import matplotlib.pyplot as plt

    plt.rcParams["svg.hashsalt"] = "de-resonator"
    plt.rcParams["svg.fonttype"] = "none"
    fig, axes = plt.subplots(2, len(SCENES), figsize=(13, 9.5), squeeze=False)
    for col, scene in enumerate(SCENES):
        for row, (key, measure) in enumerate([("error_final", "error at the final time"),
                                              ("error_l2", "L2 error over the series")]):
            ax = axes[row][col]
            scene_rows = [r for r in rows if r["scene"] == scene[0]]
            if not scene_rows:
                continue
            for solver in LABELS:
                pts = [r for r in scene_rows if r["solver"] == solver]
                if not pts:
                    continue
                colour, marker = STYLE[solver]
                ours = not peer_of(solver)
                ax.loglog([r[time_key] for r in pts], [max(r[key], 1e-17) for r in pts],
                          color=colour, marker=marker, markersize=5,
                          linestyle="-" if ours else "--", label=LABELS[solver])
            apart = scene_rows[0]["reference_apart"]
            ax.axhline(apart, color="#999999", linestyle=":", linewidth=1,
                       label="the two references' distance (the error floor)")
            ax.set_title(f"{scene[1]}", fontsize=9)
            ax.set_xlabel(f"time, s: {what}")
            ax.set_ylabel(f"stretch: {measure}")
            ax.grid(True, which="major", alpha=0.3)
    handles, labels = [], []
    for ax in axes.flat:
        for h, l in zip(*ax.get_legend_handles_labels()):
            if l not in labels:
                handles.append(h)
                labels.append(l)
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=9)
    fig.suptitle(f"Work-precision against the peers, {what}; median of each point's runs "
                 "(solid: ours, dashed: the peers)", fontsize=11)
    if versions:
        fig.text(0.5, 0.005, f"peers: {versions}", ha="center", fontsize=8)
    fig.tight_layout(rect=(0, 0.09, 1, 0.97))
    fig.savefig(path, metadata={"Date": None})
    plt.close(fig)
    return path


def words(path):
    """The figure's words but numbers (tick labels), as scripts/plots.sh compares them."""
    svg = open(path, encoding="utf-8").read()
    texts = (t.strip() for t in re.findall(r"<(?:text|tspan)[^>]*>([^<]*)", svg))
    return [t for t in texts if not re.fullmatch(r"[-+0-9.,eE×·^ −⁰¹²³⁴⁵⁶⁷⁸⁹⁻]*", t)]


def machine_factor(pairs, key):
    """The median over the peers' points of the time now over the time committed."""
    ratios = [r[key] / kept[key] for r, kept in pairs if peer_of(r["solver"])]
    return statistics.median(ratios) if ratios else 1.0


def check(rows, figures, slack, ours_slack):
    failed = 0
    for made in figures:
        kept = os.path.join(KEPT, os.path.basename(made))
        if not os.path.exists(kept) or words(kept) != words(made):
            print(f"work_precision.py: {kept} differs in its words from what is made now",
                  file=sys.stderr)
            failed = 1
    committed = {(r["scene"], r["solver"], r["setting"]): r for r in committed_rows()}
    pairs = []
    for r in rows:
        kept = committed.get((r["scene"], r["solver"], r["setting"]))
        if kept is None:
            print(f"work_precision.py: no committed point {r['scene']} {r['solver']} "
                  f"{r['setting']}", file=sys.stderr)
            failed = 1
            continue
        pairs.append((r, kept))
    # This machine against the one the figures were taken on: the median over the peers'
    # points (which no change of ours moves) of time now / time committed, a key at a time.
    # Each point is then compared after that factor, so a machine uniformly slower or faster
    # passes, and a point that moved against its peers in this one run does not.
    machine = {key: machine_factor(pairs, key) for key in ["whole_seconds", "solve_seconds"]}
    print("work_precision.py: this machine against the committed figures' (the peers' "
          "median): " + ", ".join(f"{key} {f:.2f}×" for key, f in machine.items()))
    for r, kept in pairs:
        factor = slack if peer_of(r["solver"]) else ours_slack
        for key in ["whole_seconds", "solve_seconds"]:
            ratio = r[key] / kept[key] / machine[key]
            if not 1.0 / factor <= ratio <= factor:
                print(f"work_precision.py: {r['scene']} {r['solver']} {r['setting']}: {key} "
                      f"{r[key]:.3g} s against the committed {kept[key]:.3g} s, "
                      f"{ratio:.2f}× after this machine's {machine[key]:.2f}× "
                      f"(more than {factor}× apart)", file=sys.stderr)
                failed = 1
        for key in ["error_final", "error_l2"]:
            was = kept[key]
            # Rounding may move an error at the references' floor; a method's, not 20%.
            if not abs(r[key] - was) <= 0.2 * was + 10.0 * kept["reference_apart"]:
                print(f"work_precision.py: {r['scene']} {r['solver']} {r['setting']}: {key} "
                      f"{r[key]:.3g} against the committed {was:.3g}", file=sys.stderr)
                failed = 1
    if failed:
        print("work_precision.py: run scripts/bench-peers.sh and commit docs/plots/ "
              "(each figure read before)", file=sys.stderr)
    else:
        print(f"work_precision.py: the committed figures drawn from the committed CSV; "
              f"{len(rows)} points within {slack}× (ours {ours_slack}×) of the committed "
              "times after this machine's factor, their errors and the figures' words as committed")
    return failed


if __name__ == "__main__":
    main()
