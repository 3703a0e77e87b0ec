"""simulate: against SciPy's solve_ivp on the equation of motion of docs/model.md §4 written
again in tests/model.py, and its result shaped like SciPy's OdeResult."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import de_resonator as dr
from conftest import random_devices
from model import Model


def scipy_run(device, bias, ac, hz, t, start_stretch):
    m = Model(device.to_dict())
    volts = lambda s: bias + ac * np.sin(2 * np.pi * hz * s)
    return solve_ivp(
        m.rhs, (t[0], t[-1]), [start_stretch, 0.0], method="DOP853", t_eval=t,
        args=(volts,), rtol=1e-12, atol=1e-12,
    )


@pytest.mark.parametrize("method", ["reference", "reference-radau"])
def test_the_motion_agrees_with_solve_ivp_on_random_devices(method):
    for device in [dr.Device.reference(), *random_devices(4, 5)]:
        safe = device.safe(margin=0.3)
        bias = 0.6 * safe.max_bias_volts
        f0 = device.frequency(bias)
        ours = dr.simulate(
            device, bias, ac_volts=0.05 * bias, ac_hz=0.9 * f0, duration_seconds=10 / f0,
            method=method,
        )
        assert ours.status == 0 and ours.success and ours.limit is None
        assert ours.t.shape == ours.volts.shape == (ours.y.shape[1],) and ours.y.shape[0] == 2
        theirs = scipy_run(device, bias, 0.05 * bias, 0.9 * f0, ours.t, ours.y[0, 0])
        assert theirs.success
        swing = np.ptp(theirs.y[0])
        assert np.max(np.abs(ours.y[0] - theirs.y[0])) < 1e-8 * swing
        assert np.max(np.abs(ours.y[1] - theirs.y[1])) < 1e-8 * np.ptp(theirs.y[1])
        assert ours.volts == pytest.approx(0.6 * safe.max_bias_volts + 0.05 * bias * np.sin(2 * np.pi * 0.9 * f0 * ours.t))
        assert ours.nfev > 0 and ours.method == method


@pytest.mark.parametrize("method,order", [("rk4", 4), ("verlet", 2), ("implicit-midpoint", 2)])
def test_the_core_methods_converge_at_their_order_and_f32_follows_f64(method, order):
    device = dr.Device.reference()
    bias = 5000.0
    f0 = device.frequency(bias)
    drive = dict(ac_volts=100, ac_hz=0.8 * f0, duration_seconds=0.2)
    reference = dr.simulate(device, bias, **drive, step_seconds=1 / (256 * f0))
    errors = []
    for step in [1 / (64 * f0), 1 / (128 * f0)]:
        run = dr.simulate(device, bias, **drive, method=f"{method}-f64", step_seconds=step)
        assert run.nfev is None and run.method == f"{method}-f64"
        on_reference = np.interp(run.t, reference.t, reference.y[0])
        # The reference's samples are its dense output, exact to 1e-12: compare where both
        # have a sample.
        shared = np.isin(np.round(run.t / reference.step_seconds, 6) % 1, [0.0])
        errors.append(np.max(np.abs(run.y[0] - on_reference)[shared]))
    ratio = errors[0] / errors[1]
    assert 0.6 * 2**order < ratio < 1.6 * 2**order, (errors, ratio)
    single = dr.simulate(device, bias, **drive, method=f"{method}-f32", step_seconds=1 / (64 * f0))
    double = dr.simulate(device, bias, **drive, method=f"{method}-f64", step_seconds=1 / (64 * f0))
    assert np.max(np.abs(single.y[0] - double.y[0])) < 1e-3 * np.ptp(double.y[0])


def test_a_crossing_is_status_1_with_the_event_and_its_mode():
    device = dr.Device.reference()
    limit = device.safe().limit
    ours = dr.simulate(device, 0.99 * limit["volts"], ac_volts=0.05 * limit["volts"],
                       ac_hz=40.0, duration_seconds=0.5)
    assert ours.status == 1 and ours.success
    assert ours.limit == "emi" and "emi" in ours.message
    [t_cross] = ours.t_events[0]
    [[stretch, rate]] = ours.y_events[0]
    assert 0 < t_cross < 0.5
    # Stopped there, as SciPy's terminal event: the last sample is the crossing.
    assert ours.t[-1] == t_cross and ours.y[0, -1] == stretch and ours.t[-2] < t_cross
    whole = dr.simulate(device, 0.99 * limit["volts"], ac_volts=0.05 * limit["volts"],
                        ac_hz=40.0, duration_seconds=0.5, stop_at_limit=False)
    assert whole.t[-1] == pytest.approx(0.5) and whole.t_events[0][0] == t_cross
    # The equation written in the test reaches the model's EMI stretch at that time too.
    m = Model(device.to_dict())
    theirs = scipy_run(device, 0.99 * limit["volts"], 0.05 * limit["volts"], 40.0,
                       np.array([0.0, t_cross]), ours.y[0, 0])
    assert theirs.y[0, -1] == pytest.approx(stretch, rel=1e-8)
    # There, under the voltage of that instant, the Hessian of §6.2 stops being positive.
    volts = 0.99 * limit["volts"] + 0.05 * limit["volts"] * np.sin(2 * np.pi * 40.0 * t_cross)
    assert m.emi_hessian_positive(stretch * (1 - 1e-4), volts=volts)
    assert not m.emi_hessian_positive(stretch * (1 + 1e-4), volts=volts)


def test_a_core_method_stops_at_its_crossing_too():
    device = dr.Device.reference()
    limit = device.safe().limit
    for method in ["rk4-f32", "verlet-f64"]:
        run = dr.simulate(device, 0.95 * limit["volts"], ac_volts=0.2 * limit["volts"],
                          ac_hz=40.0, duration_seconds=0.5, start="prestretch", method=method)
        assert run.status == 1, method
        [t_cross] = run.t_events[0]
        [[stretch, rate]] = run.y_events[0]
        assert np.isfinite([stretch, rate]).all(), method
        assert run.t[-1] == t_cross and run.y[0, -1] == stretch and run.t[-2] < t_cross
        whole = dr.simulate(device, 0.95 * limit["volts"], ac_volts=0.2 * limit["volts"],
                            ac_hz=40.0, duration_seconds=0.5, start="prestretch",
                            method=method, stop_at_limit=False)
        assert whole.t[-1] == pytest.approx(0.5)


def test_a_drive_that_is_not_a_number_is_refused_not_run():
    device = dr.Device.reference()
    for bad in [dict(ac_volts=float("nan"), ac_hz=40.0), dict(ac_volts=float("inf"), ac_hz=40.0)]:
        with pytest.raises(ValueError, match="must be a finite number"):
            dr.simulate(device, 5000.0, duration_seconds=0.05, **bad)
    with pytest.raises(ValueError, match="must be a finite number"):
        dr.simulate(device, float("nan"), duration_seconds=0.05, start="prestretch")


def test_bad_inputs_raise_value_error_with_a_clear_message():
    device = dr.Device.reference()
    with pytest.raises(ValueError, match="method `rk5`: one of reference"):
        dr.simulate(device, 1000.0, duration_seconds=0.1, method="rk5")
    with pytest.raises(ValueError, match="needs ac_hz"):
        dr.simulate(device, 1000.0, ac_volts=10, duration_seconds=0.1)
    with pytest.raises(ValueError, match="duration -1 s must be positive"):
        dr.simulate(device, 1000.0, duration_seconds=-1)
    with pytest.raises(ValueError, match="start `rest`"):
        dr.simulate(device, 1000.0, duration_seconds=0.1, start="rest")
    with pytest.raises(TypeError):
        dr.simulate(device, 1000.0)


def test_ctrl_c_stops_a_long_simulation_cleanly():
    """SIGINT during a long call raises KeyboardInterrupt within a fraction of a second, and
    the interpreter goes on (the work was stopped, not left running)."""
    script = textwrap.dedent("""
        import os, signal, threading, time
        import de_resonator as dr
        # Python's own Ctrl-C handler, whatever this process inherited (a job started in the
        # background by a shell inherits SIGINT ignored, and Python then installs none).
        signal.signal(signal.SIGINT, signal.default_int_handler)
        threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        started = time.monotonic()
        try:
            dr.simulate(dr.Device(), 5000.0, ac_volts=100, ac_hz=40, duration_seconds=3000)
            print("finished")
        except KeyboardInterrupt:
            print(f"interrupted after {time.monotonic() - started:.2f} s")
        print(dr.Device().tune(44.0).bias_volts > 0)
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.split("\n")
    assert lines[0].startswith("interrupted after"), out.stdout
    assert float(lines[0].split()[2]) < 2.0
    assert lines[1] == "True"


@pytest.mark.parametrize("method,within", [("reference", 1e-9), ("reference-radau", 1e-6),
                                           ("rk4-f64", 1e-5)])
def test_y0_and_t_eval_as_scipy_means_them(method, within):
    rng = np.random.default_rng(621)
    for device in [dr.Device.reference(), *random_devices(3, 621)]:
        bias = 0.5 * device.safe(margin=0.3).max_bias_volts
        f0 = device.frequency(bias)
        model = Model(device.to_dict())
        rest = model.stretch_for_bias(bias, device.safe(margin=0.0).limit["stretch"])
        y0 = (rest * 1.002, 0.3 * rng.uniform(-1, 1))
        duration = 8 / f0
        t_eval = np.sort(rng.uniform(0, duration, 37))
        ours = dr.simulate(device, bias, ac_volts=0.05 * bias, ac_hz=1.3 * f0,
                           duration_seconds=duration, method=method, y0=y0, t_eval=t_eval,
                           step_seconds=1 / (200 * f0))
        assert ours.status == 0 and np.array_equal(ours.t, t_eval)
        volts = lambda s: bias + 0.05 * bias * np.sin(2 * np.pi * 1.3 * f0 * s)
        theirs = solve_ivp(model.rhs, (0.0, duration), list(y0), method="DOP853",
                           t_eval=t_eval, args=(volts,), rtol=1e-12, atol=1e-12)
        swing = np.ptp(theirs.y[0])
        assert np.max(np.abs(ours.y[0] - theirs.y[0])) < within * swing, method
        assert np.max(np.abs(ours.y[1] - theirs.y[1])) < within * np.ptp(theirs.y[1]), method


def test_t_eval_outside_the_run_or_unsorted_is_refused():
    device = dr.Device.reference()
    with pytest.raises(ValueError, match="outside the run"):
        dr.simulate(device, 5000.0, duration_seconds=0.1, t_eval=[0.05, 0.2])
    with pytest.raises(ValueError, match="increasing"):
        dr.simulate(device, 5000.0, duration_seconds=0.1, t_eval=[0.05, 0.01])
    with pytest.raises(ValueError, match="y0 of shape"):
        dr.simulate(device, 5000.0, duration_seconds=0.1, y0=[2.0])
