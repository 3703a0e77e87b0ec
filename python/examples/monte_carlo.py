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
            rows = study(args.devices, args.seed, client, chunks=args.chunks)
    else:
        rows = study(args.devices, args.seed, chunks=args.chunks)
    seconds = time.perf_counter() - started
    print(report(rows))
    print(f"  {seconds:.2f} s ({args.workers if not args.scheduler else 'cluster'} workers)")
    if args.plot:
        plot(rows, args.plot)
        print(f"wrote {args.plot}")


if __name__ == "__main__":
    sys.exit(main())
