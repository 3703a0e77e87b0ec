"""The package's promises (issue 62, 7), a test each: what docs/python.md and the stubs say
holds: frequencies only on the loading branch, numbers that are numbers, missing files said
as Python says them, and stubs that take what the docs pass."""

import ast
import pathlib

import numpy as np
import pytest

import de_resonator as dr
from conftest import ROOT, random_devices
from model import Model

STUBS = pathlib.Path(dr.__file__).with_name("_native.pyi")


def test_no_frequency_past_the_limit():
    # The reference device's limit is EMI at 9,854.73 V (docs/model.md §9): at 9,900 V no
    # equilibrium holds, so NaN, as docs/python.md says (it was 42.71 Hz).
    device = dr.Device.reference()
    assert np.isnan(device.frequency(9900.0))
    below = 9800.0
    m = Model(device.to_dict())
    lam = m.stretch_for_bias(below, device.safe(margin=0.0).limit["stretch"])
    assert device.frequency(below) == pytest.approx(m.frequency_hz(lam), rel=1e-8)
    for device in [device, *random_devices(6, 7)]:
        limit = device.safe(margin=0.0).limit["volts"]
        out = device.frequency(np.array([limit * (1 - 1e-6), limit * (1 + 1e-6), 2 * limit]))
        assert np.isfinite(out[0]) and np.isnan(out[1:]).all(), (limit, out)


def test_a_value_that_is_no_number_raises_type_error():
    # A bool is an int to Python, but `shear_modulus=True` is a slip, not 1 Pa.
    for value in (True, False, "thin", [45e3]):
        with pytest.raises(TypeError, match="`shear_modulus` must be a number"):
            dr.Device(shear_modulus=value, jlim=120)
    # A string is refused alike by the call for one target and by the call for many.
    device = dr.Device.reference()
    with pytest.raises(TypeError):
        device.tune("43")
    for call, arg in ((device.tune_many, ["43"]), (device.tune_many, [True]),
                      (device.frequency, "100"), (device.frequency, [np.bool_(True)])):
        with pytest.raises(TypeError, match="must be numbers"):
            call(arg)
    with pytest.raises(TypeError, match="prestretch_1 must be numbers"):
        device.family(prestretch_1=["2.0"])
    # Numbers of any int or float dtype still are.
    assert device.tune_many(np.array([44], dtype=np.int16)).ok.all()


def test_a_missing_file_raises_file_not_found_error(tmp_path):
    missing = tmp_path / "no-such-file.toml"
    for call in (lambda: dr.Device.from_file(missing),
                 lambda: dr.run_scene(missing),
                 lambda: dr.run_scene(str(missing)),
                 lambda: dr.check_image(missing),
                 lambda: dr.image(settings=missing, target_hz=44.0)):
        with pytest.raises(FileNotFoundError, match="no-such-file.toml"):
            call()


def test_the_stubs_take_what_the_docs_pass(tmp_path):
    tree = ast.parse(STUBS.read_text())
    annotations = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef):
            for arg in node.args.args + node.args.kwonlyargs:
                if arg.annotation is not None:
                    annotations[(node.name, arg.arg)] = ast.unparse(arg.annotation)
    # `jlim=None` (neo-Hookean), a Path for a scene, numpy arrays for a family.
    assert annotations[("__init__", "jlim")] == "Optional[float]"
    assert "PathLike" in annotations[("run_scene", "scene")]
    assert annotations[("family", "prestretch_1")] == "Optional[ArrayLike]"
    assert annotations[("family", "prestretch_2")] == "Optional[ArrayLike]"
    # And the calls themselves.
    assert dr.Device(shear_modulus=60e3, jlim=None).material == "neo_hookean"
    assert len(dr.Device().family(prestretch_1=np.linspace(2.0, 2.5, 3))) == 3
    text = (ROOT / "scenes" / "reference.toml").read_text()
    scene = tmp_path / "short.toml"
    scene.write_text(text.replace("duration_seconds = 10.0", "duration_seconds = 0.2"))
    assert dr.run_scene(scene).simulated_seconds == 0.2


def test_errors_name_the_keywords_not_the_command_line():
    # Each bad call's message names the keyword it was given by, never a host-sim flag
    # (`--points`) or a cargo command.
    device = dr.Device.reference()
    calls = [
        (lambda: device.sweep(points=10**6, bias_volts=4000, ac_volts=40), "points"),
        (lambda: device.sweep(points=41, bias_volts=4000, ac_volts=40, quality_factor=-1),
         "quality_factor"),
        (lambda: device.curve(margin=2.0), "margin"),
        (lambda: device.curve(points=1), "points"),
        (lambda: dr.simulate(device, 4000.0, duration_seconds=0.1, ac_volts=10.0), "ac_hz"),
        (lambda: dr.simulate(device, 4000.0, duration_seconds=0.1, ac_volts=10.0, ac_hz=-1.0),
         "ac_hz"),
        (lambda: dr.simulate(device, 4000.0, duration_seconds=0.1, method="reference-bdf"),
         "reference-radau"),
    ]
    for call, keyword in calls:
        with pytest.raises(ValueError) as raised:
            call()
        message = str(raised.value)
        assert "--" not in message and "cargo" not in message, message
        assert keyword in message, (keyword, message)


def test_ctrl_c_stops_a_sweep_within_a_point():
    """docs/python.md: Ctrl-C stops a long call within a point. Measured against the same
    sweep's own run time on this machine (no fixed seconds): interrupted at a tenth of it,
    the KeyboardInterrupt comes before half of it (issue 62 saw it only near the end)."""
    import _thread
    import threading
    import time

    device = dr.Device.reference()
    sweep = dict(points=160, periods=4000)
    t0 = time.perf_counter()
    device.sweep(**sweep)
    whole = time.perf_counter() - t0
    timer = threading.Timer(0.1 * whole, _thread.interrupt_main)
    t0 = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        device.sweep(**sweep)
    stopped = time.perf_counter() - t0
    timer.join()
    assert stopped < 0.5 * whole, (stopped, whole)


def test_a_fixed_step_method_that_leaves_its_range_returns_the_trajectory(host_sim, tmp_path):
    """A core method whose step leaves the range it was checked for (a large AC at the
    resonance, 16 steps a period, on a device of conftest's draw where the monitor sees no
    crossing first) returns the samples to there with status −1, as SciPy's solvers return a
    failed step, stop_at_limit or not; the CLI reports it with exit 1, not 2 (bad input). The
    samples are those of the same run asked to end just there."""
    import json
    import subprocess

    device = random_devices(1, 3)[0]
    limit = device.safe(margin=0.0).limit["volts"]
    bias, ac = 0.5 * limit, 0.45 * limit
    f0 = float(device.frequency(bias))
    asked = dict(ac_volts=ac, ac_hz=f0, method="rk4-f32", step_seconds=1 / (16 * f0))
    for stop_at_limit in (True, False):
        run = dr.simulate(device, bias, duration_seconds=30 / f0, stop_at_limit=stop_at_limit,
                          **asked)
        assert run.status == -1 and run.success is False and run.limit is None, run.message
        assert "left the range the step was checked for" in run.stopped
        assert run.message == "the method stopped: " + run.stopped
        assert 1 < len(run.t) and run.t[-1] < 30 / f0
    shorter = dr.simulate(device, bias, duration_seconds=run.t[-1], **asked)
    assert shorter.status == 0 and len(shorter.t) == len(run.t)
    assert np.array_equal(shorter.y, run.y)
    keys = tmp_path / "device.toml"
    keys.write_text("".join(f"{k} = {v!r}\n" for k, v in device.to_dict().items()))
    out = subprocess.run(
        [host_sim, "--json", "simulate", "--device", str(keys),
         "--bias-volts", repr(bias), "--ac-volts", repr(ac),
         "--ac-hz", repr(f0), "--duration-seconds", repr(30 / f0), "--method", "rk4-f32",
         "--step-seconds", repr(1 / (16 * f0))], capture_output=True, text=True)
    assert out.returncode == 1, out.stderr
    report = json.loads(out.stdout)
    assert report["stopped"] == run.stopped and report["steps"] == len(run.t) - 1


def test_a_scene_keeps_its_caveat_and_measures_no_error_after_a_fault():
    """run_scene (and run --json) carry the report's caveat: a branch faster than 10 periods
    of the target (read here from the scene's own TOML) makes the frozen-network frequency
    not hold; and a faulted run has no frequency error (the output is at 0 V after it)."""
    import tomllib

    path = ROOT / "scenes" / "stiff-relaxation.toml"
    scene = tomllib.loads(path.read_text())
    target = scene["controller"]["target_hz"]
    fast = [b for b in scene["plant"]["branches"] if b["relaxation_seconds"] * target < 10]
    report = dr.run_scene(path)
    assert len(report.caveats) == len(fast) == 1
    assert "does not hold" in report.caveats[0]
    faulted = dr.run_scene(ROOT / "scenes" / "fault-sensor-stuck.toml")
    assert faulted.fault is not None
    assert faulted.natural_frequency_hz is None and faulted.relative_error is None
