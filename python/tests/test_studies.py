"""The nonlinear studies (poincare, bifurcation, lyapunov) against independent restatements:
the equation of motion of docs/model.md §4 written again in tests/model.py and solved by
SciPy's DOP853 at 1e-12, and the linearisation of §5 at rest."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import de_resonator as dr
from conftest import random_devices
from model import Model


def devices():
    return [dr.Device.reference(), *random_devices(4, 62)]


def strobe(model, bias, ac, hz, y0, times):
    """SciPy's states at `times` from `y0` at t = 0 (model.md §4 as tests/model.py has it)."""
    volts = lambda s: bias + ac * np.sin(2 * np.pi * hz * s)
    out = solve_ivp(model.rhs, (0.0, times[-1]), list(y0), method="DOP853", t_eval=times,
                    args=(volts,), rtol=1e-12, atol=1e-12)
    assert out.success
    return out.y


def drive_of(device):
    """A drive on the way to parametric resonance: 0.6 of the safe bias, 10% AC at 1.9·f0."""
    bias = 0.6 * device.safe(margin=0.3).max_bias_volts
    f0 = device.frequency(bias)
    return bias, 0.1 * bias, 1.9 * f0


def test_poincare_points_are_scipys_at_whole_drive_periods_on_random_devices():
    for device in devices():
        model = Model(device.to_dict())
        bias, ac, hz = drive_of(device)
        rest = model.stretch_for_bias(bias, device.safe(margin=0.0).limit["stretch"])
        starts = np.array([[rest, 0.0], [rest * 1.01, 0.0], [rest, -2.0]])
        ours = dr.poincare(device, bias, ac, hz, periods=30, transient_periods=5, y0=starts)
        assert ours.stretch.shape == ours.velocity.shape == (3, 30)
        assert ours.t == pytest.approx(np.arange(5, 35) / hz, rel=1e-15)
        for row, y0 in enumerate(starts):
            theirs = strobe(model, bias, ac, hz, y0, ours.t)
            assert np.max(np.abs(ours.stretch[row] - theirs[0])) < 1e-6, device
            scale = max(1.0, np.max(np.abs(theirs[1])))
            assert np.max(np.abs(ours.velocity[row] - theirs[1])) < 1e-6 * scale
        # The default start: the rest state at the bias, one row.
        alone = dr.poincare(device, bias, ac, hz, periods=3)
        assert alone.stretch.shape == (3,) and alone.stretch[0] == pytest.approx(rest, rel=1e-9)
        assert alone.velocity[0] == 0.0


def test_a_bifurcation_continues_each_value_from_the_last_ones_end():
    device = dr.Device.reference()
    model = Model(device.to_dict())
    bias, ac, hz = drive_of(device)
    values = np.linspace(0.5 * ac, ac, 4)
    y0 = (model.stretch_for_bias(bias, device.safe(margin=0.0).limit["stretch"]), 0.0)
    diagram = dr.bifurcation(device, bias, hz, values, periods=8, transient_periods=2,
                             direction="up", y0=y0)
    assert diagram.varied == "ac_volts" and diagram.stretch.shape == (4, 8)
    assert list(diagram.parameter) == list(values) and diagram.direction == ["up"] * 4
    first = dr.poincare(device, bias, values[0], hz, periods=8, transient_periods=2, y0=y0)
    assert np.array_equal(diagram.stretch[0], first.stretch)
    assert np.array_equal(diagram.velocity[0], first.velocity)
    # The second value starts from the first one's last section point (phase 0 again).
    times = np.arange(2, 10) / hz
    theirs = strobe(model, bias, values[1], hz,
                    (diagram.stretch[0, -1], diagram.velocity[0, -1]), times)
    assert np.max(np.abs(diagram.stretch[1] - theirs[0])) < 1e-6
    # Both ways: the walk down starts at the top value, from the rest state there.
    both = dr.bifurcation(device, bias, hz, values, periods=8, transient_periods=2)
    assert both.direction == ["up"] * 4 + ["down"] * 4
    assert list(both.parameter) == list(values) + list(values[::-1])
    top = dr.poincare(device, bias, values[-1], hz, periods=8, transient_periods=2)
    assert np.array_equal(both.stretch[4], top.stretch)


def test_a_bifurcation_over_the_frequency_or_the_bias():
    device = dr.Device.reference()
    bias, ac, hz = drive_of(device)
    over_hz = dr.bifurcation(device, bias, np.array([0.9 * hz, hz]), ac, periods=4,
                             transient_periods=0, direction="down")
    assert over_hz.varied == "ac_hz" and list(over_hz.parameter) == [hz, 0.9 * hz]
    one = dr.poincare(device, bias, ac, hz, periods=4)
    assert np.array_equal(over_hz.stretch[0], one.stretch)
    over_bias = dr.bifurcation(device, [0.9 * bias, bias], hz, ac, periods=4,
                               transient_periods=0, direction="up")
    assert over_bias.varied == "bias_volts"
    assert over_bias.stretch[0][0] == pytest.approx(
        dr.poincare(device, 0.9 * bias, ac, hz, periods=1).stretch[0])
    with pytest.raises(TypeError, match="must be an array"):
        dr.bifurcation(device, bias, hz, ac, periods=4)
    with pytest.raises(ValueError, match="only one"):
        dr.bifurcation(device, [bias, bias + 1], hz, [ac, 2 * ac], periods=4)
    with pytest.raises(ValueError, match="must increase"):
        dr.bifurcation(device, bias, hz, [2 * ac, ac], periods=4)


def test_a_drive_that_crosses_a_limit_says_which_and_when():
    device = dr.Device.reference()
    limit = device.safe(margin=0.0)
    bias = 0.97 * limit.max_bias_volts
    f0 = device.frequency(bias)
    out = dr.poincare(device, bias, 0.2 * bias, 2 * f0, periods=50)
    assert out.limit is not None and out.limit_time_seconds > 0
    quiet = dr.poincare(device, 0.5 * bias, 0.01 * bias, 2 * f0, periods=5)
    assert quiet.limit is None and np.isnan(quiet.limit_time_seconds) and quiet.stopped is None


@pytest.mark.parametrize("zeta", [0.02, 0.05])
def test_the_exponent_of_a_damped_membrane_at_rest_is_the_linearisations(zeta):
    for device in devices():
        model = Model(device.to_dict())
        bias = 0.5 * device.safe(margin=0.3).max_bias_volts
        lam = model.stretch_for_bias(bias, device.safe(margin=0.0).limit["stretch"])
        w2 = model.omega_squared(lam)
        c = 2 * zeta * model.mass * np.sqrt(w2)
        jacobian = np.array([[0.0, 1.0], [-w2, -c / model.mass]])
        largest = np.max(np.linalg.eigvals(jacobian).real)
        out = dr.lyapunov(device, bias, damping=c, periods=400, transient_periods=0)
        assert out.exponent == pytest.approx(largest, rel=0.02), device
        assert out.t.shape == out.estimate.shape and out.t[-1] == pytest.approx(
            400 * out.interval_seconds, rel=1e-12)


def test_the_exponent_of_an_undamped_membrane_at_rest_is_zero():
    for device in devices():
        bias = 0.5 * device.safe(margin=0.3).max_bias_volts
        out = dr.lyapunov(device, bias, damping=0.0, periods=200)
        assert abs(out.exponent) < 1e-3, device


def test_the_studies_refuse_bad_input_with_clear_errors():
    device = dr.Device.reference()
    with pytest.raises(ValueError, match="a drive"):
        dr.poincare(device, 5000.0, 100.0, 0.0, periods=3)
    with pytest.raises(ValueError, match="periods 0"):
        dr.poincare(device, 5000.0, 100.0, 40.0, periods=0)
    with pytest.raises(ValueError, match="y0 of shape"):
        dr.poincare(device, 5000.0, 100.0, 40.0, periods=3, y0=[1.0, 2.0, 3.0])
    with pytest.raises(TypeError, match="y0 must be numbers"):
        dr.poincare(device, 5000.0, 100.0, 40.0, periods=3, y0=["a", "b"])
    with pytest.raises(ValueError, match="direction"):
        dr.bifurcation(device, 5000.0, 40.0, [1.0, 2.0], periods=3, direction="sideways")


def test_every_drive_the_board_accepts_stays_inside_the_full_simulation():
    for device in devices()[:3]:
        low, high = device.safe(margin=0.05).tunable_range_hz
        target = 0.5 * (low + high)
        f0 = target
        amplitudes = np.linspace(0.0, 0.3, 7) * device.safe(margin=0.05).max_bias_volts
        freqs = np.array([0.5, 0.8, 1.0, 1.3, 2.0]) * f0
        out = dr.drive_map(device, ac_volts=amplitudes, ac_hz=freqs, target_hz=target,
                           periods=60, quality_factor=80,
                           gain=device.safe(margin=0.0).limit["volts"] / 2.0)
        assert out.safe.shape == out.accepted.shape == out.max_swing.shape == (7, 5)
        assert out.disagreements == 0 and not np.any(out.accepted & ~out.safe), device
        assert out.natural_frequency_hz == pytest.approx(target, rel=1e-3)
        assert np.all(out.accepted[0]), "no AC is always accepted"
        # The boundary against direct simulations: SciPy's run of model.md §4 (sampled 400
        # times a period of f0) at the last safe and the first unsafe amplitude of each
        # frequency, and a simulate() of the same drive crossing where the map says.
        model = Model({**device.to_dict(), "damping": out.damping})
        duration = out.duration_seconds
        for j, hz in enumerate(freqs):
            unsafe = np.flatnonzero(~out.safe[:, j])
            for i in {max(unsafe[0] - 1, 0), unsafe[0]} if unsafe.size else {6}:
                ac = amplitudes[i]
                volts = lambda s: out.bias_volts + ac * np.sin(2 * np.pi * hz * s)
                t = np.linspace(0, duration, int(400 * duration * f0))
                theirs = solve_ivp(model.rhs, (0, duration), [out.stretch, 0.0],
                                   method="DOP853", t_eval=t, args=(volts,), rtol=1e-11,
                                   atol=1e-11)
                if not theirs.success:
                    assert not out.safe[i, j]
                    continue
                swing = np.max(np.abs(theirs.y[0] - out.stretch))
                assert swing <= out.max_swing[i, j] <= swing * 1.001 + 1e-9, (i, j)
                run = dr.simulate(device, out.bias_volts, ac_volts=ac, ac_hz=hz,
                                  duration_seconds=duration, damping=out.damping)
                assert (run.status == 0) == bool(out.safe[i, j]), (i, j, run.message)


@pytest.mark.parametrize("study", ["bifurcation", "drive_map", "poincare"])
def test_ctrl_c_stops_a_study_within_a_run(study):
    """Ctrl-C at a tenth of a study's own run time raises KeyboardInterrupt before half of it
    (no fixed seconds: measured against the same call on this machine)."""
    import _thread
    import threading
    import time

    device = dr.Device.reference()
    calls = {
        "bifurcation": lambda: dr.bifurcation(device, 7450.0, 88.0, np.linspace(0, 1500, 800),
                                              periods=50, transient_periods=150),
        "drive_map": lambda: dr.drive_map(device, ac_volts=np.linspace(0, 2000, 20),
                                          ac_hz=np.linspace(20, 100, 20), target_hz=44.0,
                                          quality_factor=100, periods=300),
        "poincare": lambda: dr.poincare(device, 7450.0, 1000.0, 85.0, periods=3000,
                                        y0=np.tile([2.19, 0.0], (30, 1))),
    }
    t0 = time.perf_counter()
    calls[study]()
    whole = time.perf_counter() - t0
    timer = threading.Timer(0.1 * whole, _thread.interrupt_main)
    t0 = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        calls[study]()
    stopped = time.perf_counter() - t0
    timer.join()
    assert stopped < 0.5 * whole, (stopped, whole)
