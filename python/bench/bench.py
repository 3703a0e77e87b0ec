"""The Python package side by side with its peers, in one run (BENCHMARKS.md, "Python").

    python python/bench/bench.py [--host-sim target/release/host-sim] [--targets 100000]

1. `tune_many` over N targets, against the same targets through the CLI (`host-sim tune
   --json`, a process each: timed over --cli-calls of them and scaled to N) and against
   SciPy's `brentq` on the statics of docs/model.md §5 written in python/tests/model.py.
2. `simulate` of 10 s against SciPy's `solve_ivp` (DOP853) at the same tolerance.
3. The Dask Monte Carlo (python/examples/monte_carlo.py) over --devices devices: a plain
   loop, a LocalCluster of one worker process, and of two.

Prints a Markdown table; the machine's other load shows in the figures.
"""

import argparse
import os
import pathlib
import subprocess
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import de_resonator as dr

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
sys.path.insert(0, str(HERE.parent / "examples"))
from model import Model  # noqa: E402
import monte_carlo  # noqa: E402


def timed(job):
    started = time.perf_counter()
    out = job()
    return time.perf_counter() - started, out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    root = HERE.parents[1]
    parser.add_argument("--host-sim", default=str(root / "target" / "release" / "host-sim"))
    parser.add_argument("--targets", type=int, default=100_000)
    parser.add_argument("--cli-calls", type=int, default=300)
    parser.add_argument("--devices", type=int, default=100_000)
    args = parser.parse_args()
    rows = []
    device = dr.Device.reference()
    safe = device.safe()
    low, high = safe.tunable_range_hz
    targets = np.linspace(low, high, args.targets + 2)[1:-1]

    # 1. tune_many, the CLI, brentq.
    seconds, many = timed(lambda: device.tune_many(targets))
    assert many.ok.all()
    rows.append((f"tune_many, {args.targets:,} targets", seconds, "one call"))
    picked = targets[:: max(1, len(targets) // args.cli_calls)][: args.cli_calls]

    def cli():
        out = []
        for hz in picked:
            done = subprocess.run(
                [args.host_sim, "tune", "--target-hz", repr(float(hz)), "--json"],
                capture_output=True, text=True, check=True,
            )
            out.append(done.stdout)
        return out

    seconds, _ = timed(cli)
    rows.append((f"the CLI (`host-sim tune --json`), {args.targets:,} targets",
                 seconds * args.targets / len(picked),
                 f"scaled from {len(picked)} calls ({seconds / len(picked) * 1e3:.2f} ms each)"))
    m = Model(device.to_dict())
    top = safe.limit["stretch"]

    def scipy_tune():
        # f falls monotonically on the reference device's branch: one bracket, λ1p to the limit.
        return [m.bias_volts(brentq(lambda x: m.frequency_hz(x) - hz, m.l1p, top, xtol=1e-14))
                for hz in targets]

    seconds, biases = timed(scipy_tune)
    worst = np.max(np.abs(np.array(biases) - many.bias_volts) / many.bias_volts)
    rows.append((f"SciPy `brentq` on the statics in Python, {args.targets:,} targets", seconds,
                 f"biases agree within {worst:.1e} relative"))

    # 2. simulate 10 s against solve_ivp, both DOP853 at rtol = atol = 1e-10.
    bias, ac, hz = 5000.0, 100.0, 40.0
    seconds, ours = timed(lambda: dr.simulate(device, bias, ac_volts=ac, ac_hz=hz,
                                              duration_seconds=10.0, rtol=1e-10))
    rows.append(("simulate, 10 s, reference (DOP853, rtol = atol = 1e-10)", seconds,
                 f"{ours.nfev:,} right-hand sides, {len(ours.t):,} samples"))
    volts = lambda t: bias + ac * np.sin(2 * np.pi * hz * t)
    seconds, theirs = timed(lambda: solve_ivp(m.rhs, (0.0, 10.0), [ours.y[0, 0], 0.0],
                                              method="DOP853", t_eval=ours.t, args=(volts,),
                                              rtol=1e-10, atol=1e-10))
    gap = np.max(np.abs(theirs.y[0] - ours.y[0]))
    rows.append(("SciPy `solve_ivp` DOP853 on the equation in Python, the same", seconds,
                 f"{theirs.nfev:,} right-hand sides; stretches within {gap:.1e}"))

    # 3. The Dask Monte Carlo: drawn where it runs (seeds travel), and devices sent pickled.
    seconds, plain = timed(lambda: monte_carlo.study(args.devices, seed=0, chunks=8))
    rows.append((f"Monte Carlo, {args.devices:,} devices drawn and summarised, a plain loop",
                 seconds, "8 chunks, no Dask"))
    devices = monte_carlo.draw_devices(args.devices // 10, seed=0)
    seconds, plain_sent = timed(lambda: monte_carlo.run(devices))
    rows.append((f"{len(devices):,} devices drawn here, summarised in a plain loop", seconds, ""))
    from dask.distributed import Client, LocalCluster

    for workers in [1, 2]:
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            monte_carlo.study(2000, seed=1, client=client, chunks=8)  # the workers warmed
            seconds, spread = timed(lambda: monte_carlo.study(args.devices, seed=0,
                                                              client=client, chunks=8))
            assert np.array_equal(spread, plain)
            plural = "es" if workers > 1 else ""
            rows.append((f"the study on a LocalCluster of {workers} worker process{plural}",
                         seconds, "the plain loop's numbers; seeds travel"))
            seconds, sent = timed(lambda: monte_carlo.run(devices, client))
            assert np.array_equal(sent, plain_sent)
            rows.append((f"{len(devices):,} pickled devices sent to {workers} worker{plural[1:]}",
                         seconds, "the plain loop's numbers"))

    print(f"{os.cpu_count()} cores, Python {sys.version.split()[0]}, numpy {np.__version__}\n")
    print("| what | seconds | note |\n|---|---|---|")
    for what, seconds, note in rows:
        print(f"| {what} | {seconds:.3f} | {note} |")


if __name__ == "__main__":
    main()
