"""Long calls release the GIL (a Python thread runs while one works: checked by what it does,
not by a speed-up a loaded machine would not show), and the Dask example maps a study over
worker processes with the same numbers as a plain loop."""

import pathlib
import sys
import threading
import time

import numpy as np

import de_resonator as dr

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import monte_carlo  # noqa: E402


def test_python_runs_while_a_call_works():
    """The GIL released: a Python thread counts while tune_many works (it would stand still
    for the whole call if the lock were held), whatever the machine's load."""
    device = dr.Device.reference()
    low, high = device.safe().tunable_range_hz
    targets = np.linspace(low, high, 60000)
    counts = []
    done = threading.Event()

    def count():
        n = 0
        while not done.is_set():
            n += 1
        counts.append(n)

    counter = threading.Thread(target=count)
    started = time.perf_counter()
    call = threading.Thread(target=lambda: (device.tune_many(targets), done.set()))
    call.start()
    counter.start()
    call.join()
    counter.join()
    seconds = time.perf_counter() - started
    # A Python loop counts millions a second; held out for the call it would count ~0.
    assert counts[0] > 1000 * seconds, (counts, seconds)


def test_the_dask_example_gives_the_plain_loops_numbers_on_two_worker_processes():
    from dask.distributed import Client, LocalCluster

    devices = monte_carlo.draw_devices(400, seed=3)
    plain = monte_carlo.run(devices)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        spread = monte_carlo.run(devices, client)
        assert len(client.scheduler_info()["workers"]) == 2
        seeded = monte_carlo.study(1000, seed=5, client=client, chunks=6)
    assert spread.shape == (400, 4)
    assert np.array_equal(spread, plain)
    assert np.array_equal(seeded, monte_carlo.study(1000, seed=5, chunks=6))
    # The draw's spread shows in the result: not one device 400 times.
    assert np.ptp(plain[:, 2]) > 0.1 * np.mean(plain[:, 2])


def test_the_batch_study_finds_no_device_below_the_guaranteed_limit():
    """docs/model.md §10: the sampled limits never below the guaranteed one, every frequency
    at the commanded bias inside the band; the same numbers on two worker processes as in
    the plain loop."""
    from dask.distributed import Client, LocalCluster

    guaranteed, tuned, rows = monte_carlo.batch_study(400, 45.5, seed=2, chunks=4)
    g = guaranteed["limit"]["volts"]
    assert rows[:, 0].min() >= g
    low, high = tuned.band_hz
    assert low <= rows[:, 1].min() and rows[:, 1].max() <= high
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        _, _, spread = monte_carlo.batch_study(400, 45.5, seed=2, client=client, chunks=4)
    assert np.array_equal(spread, rows)


def test_the_dask_example_runs_as_a_script(tmp_path, capsys):
    monte_carlo.main(["--devices", "300", "--workers", "0", "--plot", str(tmp_path / "mc.svg")])
    out = capsys.readouterr().out
    assert "300 devices" in out and (tmp_path / "mc.svg").stat().st_size > 1000
