"""A Monte Carlo of fabrication tolerances over many machines with Dask.

Devices are drawn around the reference device with the spreads a lab sees (shear modulus
±10%, thickness ±5%, each pre-stretch ±2%, one standard deviation), and each is asked for its
safe region: the tunable range and the limit's voltage. `study` sends each worker a seed and
a count, and the worker draws and summarises its chunk (only seeds and results travel);
`run` sends devices already drawn, pickled by their keys. The work is `Device.safe`, the same
code the CLI runs.

    python python/examples/monte_carlo.py --devices 20000 --workers 2
    python python/examples/monte_carlo.py --devices 100000 --scheduler tcp://host:8786

With `--scheduler` it joins any Dask cluster (the workers need this package installed);
without, it starts a `LocalCluster` of `--workers` processes (`--workers 0`: a plain loop
here, no Dask). Prints the distribution and, with `--plot`, writes a figure.

`--batch` studies the batch instead (docs/model.md §10): the same tolerances as a box (each
±its spread), the guaranteed limit certified over it, devices drawn uniformly from the box,
every sampled limit against the guaranteed one, and the yield of `--target-hz`: the share of
devices within `--yield-tolerance` of it at the bias the board commands (the batch's nominal
device's).

    python python/examples/monte_carlo.py --batch --devices 5000 --target-hz 45.5
"""

import argparse
import math
import sys
import time

import numpy as np

import de_resonator as dr

#: Each tolerance as a relative standard deviation, by the device file's key.
TOLERANCES = {"shear_modulus": 0.10, "thickness": 0.05, "prestretch_1": 0.02, "prestretch_2": 0.02}

#: The columns `summarise` gives, per device.
COLUMNS = ["low_hz", "high_hz", "limit_volts", "max_bias_volts"]


def draw_devices(count, seed=0):
    """`count` devices around the reference, the tolerances normal; a draw the model refuses
    (a pre-stretch below 1, say) is drawn again."""
    rng = np.random.default_rng(seed)
    nominal = dr.Device.reference().to_dict()
    devices = []
    while len(devices) < count:
        keys = dict(nominal)
        for key, spread in TOLERANCES.items():
            keys[key] = nominal[key] * (1.0 + spread * rng.standard_normal())
        try:
            devices.append(dr.Device(**keys))
        except ValueError:
            continue
    return devices


def summarise(devices, margin=0.05):
    """Each device's tunable range (Hz), limit (V) and highest bias (V): an array n × 4."""
    out = np.empty((len(devices), len(COLUMNS)))
    for row, device in zip(out, devices):
        safe = device.safe(margin=margin)
        row[:] = [*safe.tunable_range_hz, safe.limit["volts"], safe.max_bias_volts]
    return out


def run(devices, client=None, chunks=None):
    """`summarise` over `devices`: on the Dask `client`'s workers in `chunks` pieces (default:
    4 a worker), or here in one loop without a client. The rows keep the devices' order."""
    if client is None:
        return summarise(devices)
    if chunks is None:
        chunks = 4 * max(1, len(client.scheduler_info()["workers"]))
    size = math.ceil(len(devices) / chunks)
    pieces = [devices[k : k + size] for k in range(0, len(devices), size)]
    futures = client.map(summarise, pieces, pure=False)
    return np.vstack(client.gather(futures))


def draw_and_summarise(seed, count):
    """One chunk of a study drawn where it runs: `count` devices from `seed`, summarised."""
    return summarise(draw_devices(count, seed))


def study(count, seed=0, client=None, chunks=8):
    """A Monte Carlo of `count` devices in `chunks` pieces, each drawn from its own seed on the
    worker that summarises it (only the seeds travel, not the devices); without a client,
    the same pieces in one loop here, so the numbers are the same either way."""
    sizes = [count // chunks + (k < count % chunks) for k in range(chunks)]
    seeds = [seed * 100_003 + k for k in range(chunks)]
    if client is None:
        return np.vstack([draw_and_summarise(s, n) for s, n in zip(seeds, sizes) if n])
    futures = client.map(draw_and_summarise, seeds, sizes, pure=False)
    return np.vstack([f for f in client.gather(futures) if len(f)])


def report(rows):
    """The distribution as text: the quantiles of each column."""
    lines = [f"{len(rows)} devices; quantiles 5%, 50%, 95%"]
    for name, column in zip(COLUMNS, rows.T):
        q = np.quantile(column, [0.05, 0.5, 0.95])
        lines.append(f"  {name:<15} {q[0]:10.4g} {q[1]:10.4g} {q[2]:10.4g}")
    width = rows[:, 1] - rows[:, 0]
    q = np.quantile(width, [0.05, 0.5, 0.95])
    lines.append(f"  {'range width_hz':<15} {q[0]:10.4g} {q[1]:10.4g} {q[2]:10.4g}")
    return "\n".join(lines)


def plot(rows, path):
    """The tunable range's ends and the limit's voltage as histograms."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(9, 3.5), constrained_layout=True)
    left.hist(rows[:, 0], bins=60, alpha=0.7, label="lowest frequency (at the highest bias)")
    left.hist(rows[:, 1], bins=60, alpha=0.7, label="frequency at 0 V")
    left.set_xlabel("natural frequency, Hz")
    left.set_ylabel("devices")
    left.legend(fontsize=8)
    right.hist(rows[:, 2] / 1e3, bins=60, color="0.4")
    right.set_xlabel("limit's voltage, kV")
    right.set_ylabel("devices")
    fig.suptitle(f"Reference device, fabrication tolerances: {len(rows)} draws")
    fig.savefig(path)
    plt.close(fig)


def batch_device():
    """The reference device as a batch: each tolerance a ± range (docs/model.md §10)."""
    return dr.Device(**dr.Device.reference().to_dict(), tolerance=dict(TOLERANCES))


def draw_from_batch(batch, count, seed=0):
    """`count` devices drawn uniformly from the batch's box (keys as `Device`'s)."""
    rng = np.random.default_rng(seed)
    keys = {k: v for k, v in batch.to_dict().items() if k != "tolerance"}
    ranges = batch.tolerance
    return [dr.Device(**{**keys, **{k: rng.uniform(lo, hi) for k, (lo, hi) in ranges.items()}})
            for _ in range(count)]


def batch_chunk(seed, count, bias_volts):
    """One chunk of a batch study: each drawn device's limit (V) and its frequency at
    `bias_volts` (Hz), an array count × 2."""
    out = np.empty((count, 2))
    for row, device in zip(out, draw_from_batch(batch_device(), count, seed)):
        row[:] = [device.safe().limit["volts"], device.frequency(bias_volts)]
    return out


def batch_study(count, target_hz, seed=0, client=None, chunks=8):
    """The batch's guaranteed limit and the tuned bias for `target_hz`, and `batch_chunk`'s
    rows for `count` devices (on the client's workers, else here; the same numbers)."""
    batch = batch_device()
    guaranteed = batch.safe().guaranteed
    tuned = batch.tune(target_hz)
    sizes = [count // chunks + (k < count % chunks) for k in range(chunks)]
    seeds = [seed * 100_003 + k for k in range(chunks)]
    bias = [tuned.bias_volts] * chunks
    if client is None:
        parts = [batch_chunk(s, n, b) for s, n, b in zip(seeds, sizes, bias) if n]
    else:
        parts = client.gather(client.map(batch_chunk, seeds, sizes, bias, pure=False))
    return guaranteed, tuned, np.vstack([p for p in parts if len(p)])


def batch_report(guaranteed, tuned, rows, target_hz, tolerance):
    """Every sampled limit against the guaranteed one, the band, and the target's yield."""
    g = guaranteed["limit"]["volts"]
    limits, freqs = rows[:, 0], rows[:, 1]
    within = np.abs(freqs / target_hz - 1.0) <= tolerance
    low, high = tuned.band_hz
    return "\n".join([
        f"{len(rows)} devices drawn from the batch",
        f"  guaranteed limit {g:.1f} V ({guaranteed['limit']['mode']}); sampled limits "
        f"{limits.min():.1f} .. {limits.max():.1f} V, none below: {bool(limits.min() >= g)}",
        f"  at {tuned.bias_volts:.1f} V (the nominal device's bias for {target_hz} Hz): "
        f"sampled {freqs.min():.3f} .. {freqs.max():.3f} Hz, band {low:.3f} .. {high:.3f} Hz",
        f"  yield within {100 * tolerance:g}% of {target_hz} Hz: {100 * within.mean():.1f}%",
    ])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--devices", type=int, default=20000, help="devices to draw")
    parser.add_argument("--seed", type=int, default=0, help="the draw's seed")
    parser.add_argument("--workers", type=int, default=2,
                        help="a LocalCluster of this many processes (0: a plain loop)")
    parser.add_argument("--scheduler", help="a Dask scheduler's address, in place of a LocalCluster")
    parser.add_argument("--chunks", type=int, default=8,
                        help="pieces of the study, each drawn from its own seed (the numbers "
                             "depend on it, not on the workers)")
    parser.add_argument("--plot", help="write the histograms to this file (SVG, PNG)")
    parser.add_argument("--batch", action="store_true",
                        help="the tolerances as a batch: its guaranteed limit and a target's yield")
    parser.add_argument("--target-hz", type=float, default=45.5,
                        help="with --batch: the target whose yield is counted, Hz")
    parser.add_argument("--yield-tolerance", type=float, default=0.01,
                        help="with --batch: a device counts within this fraction of the target")
    args = parser.parse_args(argv)
    if args.devices < 1 or args.chunks < 1:
        parser.error("--devices and --chunks must be at least 1")
    started = time.perf_counter()
    if args.scheduler or args.workers > 0:
        from dask.distributed import Client, LocalCluster

        if args.scheduler:
            client = Client(args.scheduler)
        else:
            cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
        with client:
            workers = len(client.scheduler_info()["workers"])
            print(f"  on {workers} workers")
            if args.batch:
                found = batch_study(args.devices, args.target_hz, args.seed, client, args.chunks)
            else:
                rows = study(args.devices, args.seed, client, chunks=args.chunks)
    elif args.batch:
        found = batch_study(args.devices, args.target_hz, args.seed, chunks=args.chunks)
    else:
        rows = study(args.devices, args.seed, chunks=args.chunks)
    seconds = time.perf_counter() - started
    if args.batch:
        print(batch_report(*found, args.target_hz, args.yield_tolerance))
        print(f"  {seconds:.2f} s")
        return 0
    print(report(rows))
    print(f"  {seconds:.2f} s ({args.workers if not args.scheduler else 'cluster'} workers)")
    if args.plot:
        plot(rows, args.plot)
        print(f"wrote {args.plot}")


if __name__ == "__main__":
    sys.exit(main())
