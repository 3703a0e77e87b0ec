"""Device, safe, tune, frequency, tune_many and curves: against the CLI's JSON for the same
inputs and against the statics of docs/model.md §5 written again in tests/model.py."""

import json
import pickle
import subprocess

import numpy as np
import pytest
from scipy.optimize import brentq

import de_resonator as dr
from conftest import ROOT, random_devices
from model import Model


def cli(host_sim, *args):
    out = subprocess.run([host_sim, *args, "--json"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def model(device):
    return Model(device.to_dict())


def test_reference_device_is_the_built_in_one():
    device = dr.Device.reference()
    assert device.material == "gent"
    assert device["shear_modulus"] == 45e3 and device["jlim"] == 120.0
    assert dr.Device() == device
    assert "Gent" in repr(device) and "shear_modulus=45000.0" in repr(device)


def test_keywords_take_the_reference_values_and_an_absent_jlim_is_neo_hookean():
    with pytest.warns(UserWarning, match="no `jlim`: the material is neo-Hookean"):
        device = dr.Device(shear_modulus=60e3)
    assert device.material == "neo_hookean" and device.to_dict()["jlim"] is None
    assert device["thickness"] == dr.Device.reference()["thickness"]
    assert "neo-Hookean" in repr(device) and "jlim=None" in repr(device)
    with pytest.raises(KeyError):
        device["jlim"]
    # Said outright, no warning; the same device.
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert dr.Device(shear_modulus=60e3, jlim=None) == device
        assert dr.Device(**device.to_dict()) == device


def test_a_wrong_value_raises_value_error_with_the_models_reason():
    with pytest.raises(ValueError, match="`thickness` must be greater than zero"):
        dr.Device(thickness=-1e-3)
    with pytest.raises(ValueError, match="unknown field `thicknes`.*`thickness`"):
        dr.Device(thicknes=1e-3)
    with pytest.raises(TypeError, match="must be a number"):
        dr.Device(thickness="thin")
    with pytest.raises(ValueError, match="margin 1.5"):
        dr.Device().safe(margin=1.5)


def test_a_value_no_membrane_has_is_warned_of():
    with pytest.warns(UserWarning, match="`thickness` = 0.5 m is outside"):
        dr.Device(thickness=0.5, jlim=120)


def test_a_device_file_reads_as_the_cli_reads_it(tmp_path, host_sim):
    path = tmp_path / "thin.toml"
    path.write_text("shear_modulus = 60e3\njlim = 90\nthickness = 0.5e-3\nprestretch_1 = 3.0\n")
    device = dr.Device.from_file(path)
    assert device == dr.Device.from_toml(path.read_text())
    assert device == dr.Device(shear_modulus=60e3, jlim=90, thickness=0.5e-3, prestretch_1=3.0)
    ours = device.safe(margin=0.1)
    theirs = cli(host_sim, "safe", "--device", str(path), "--margin", "0.1")
    assert ours == theirs
    ours = device.tune(ours.tunable_range_hz[0] * 1.001, margin=0.1)
    theirs = cli(
        host_sim, "tune", "--device", str(path), "--margin", "0.1",
        "--target-hz", repr(ours.target_hz),
    )
    assert ours == theirs
    with pytest.raises(ValueError, match="line 1: unknown field `mu`"):
        dr.Device.from_toml("mu = 1\n")


def test_pickle_round_trip_keeps_the_device():
    import warnings

    neo = dr.Device(shear_modulus=60e3, jlim=None)
    with pytest.warns(UserWarning, match="thickness"):
        odd = dr.Device(jlim=90, thickness=0.5)
    for device in [dr.Device.reference(), neo, odd, *random_devices(5, 1)]:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # nothing said again on the way back
            again = pickle.loads(pickle.dumps(device))
        assert again == device and again.to_dict() == device.to_dict()
    result = dr.Device().safe()
    assert pickle.loads(pickle.dumps(result)) == result


def test_the_limit_is_where_the_hessian_of_model_md_6_2_stops_being_positive():
    device = dr.Device.reference()
    safe = device.safe()
    assert safe.limit["mode"] == "emi"
    m = model(device)
    lam = safe.limit["stretch"]
    assert m.emi_hessian_positive(lam * (1 - 1e-4))
    assert not m.emi_hessian_positive(lam * (1 + 1e-4))
    assert safe.limit["volts"] == pytest.approx(m.bias_volts(lam), rel=1e-9)
    assert safe.max_bias_volts == pytest.approx(0.95 * safe.limit["volts"], rel=1e-12)


def test_frequency_agrees_with_the_statics_for_any_dtype_and_shape():
    for device in [dr.Device.reference(), *random_devices(6, 2)]:
        m = model(device)
        safe = device.safe(margin=0.0)
        lam = np.linspace(device["prestretch_1"], safe.limit["stretch"], 7)[1:-1]
        volts = m.bias_volts(lam)
        assert device.frequency(volts) == pytest.approx(m.frequency_hz(lam), rel=1e-8)
        grid = volts.reshape(5, 1)
        assert device.frequency(grid).shape == (5, 1)
    device = dr.Device.reference()
    f0 = model(device).frequency_hz(2.0)
    for given in [0, np.int8(0), np.array([0, 0], dtype=np.uint16), [0.0], np.float32(0)]:
        got = device.frequency(given)
        assert np.all(np.asarray(got) == pytest.approx(f0, rel=1e-11))
    assert isinstance(device.frequency(0), float)
    out = device.frequency(np.array([-1.0, np.nan, 1e9]))
    assert out.dtype == np.float64 and np.isnan(out).all()


def independent_bias(m, target_hz, limit_stretch):
    """The smallest bias tuning m to target_hz: the first sign change of f − target along
    the loading branch from λ1p, then brentq (SciPy) in it."""
    lam = np.linspace(m.l1p, limit_stretch, 4001)
    gap = m.frequency_hz(lam) - target_hz
    first = np.nonzero(np.sign(gap[:-1]) != np.sign(gap[1:]))[0]
    if len(first) == 0:
        return np.nan
    k = first[0]
    root = brentq(lambda x: m.frequency_hz(x) - target_hz, lam[k], lam[k + 1], xtol=1e-15)
    return m.bias_volts(root)


def test_tune_many_agrees_with_brentq_on_the_statics_on_random_devices():
    for device in [dr.Device.reference(), *random_devices(8, 3)]:
        m = model(device)
        safe = device.safe(margin=0.05)
        low, high = safe.tunable_range_hz
        targets = np.linspace(low, high, 9)[1:-1]
        many = device.tune_many(targets)
        assert many.ok.all() and many.bias_volts.shape == targets.shape
        for target, bias in zip(targets, many.bias_volts):
            expected = independent_bias(m, target, safe.limit["stretch"])
            assert bias == pytest.approx(expected, rel=1e-8, abs=1e-9 * safe.limit["volts"])
        assert many.natural_frequency_hz == pytest.approx(targets, rel=1e-9)


def test_tune_many_gives_nan_and_the_reason_where_a_target_is_out_of_reach():
    device = dr.Device.reference()
    low, high = device.safe().tunable_range_hz
    targets = np.array([[low - 1, (low + high) / 2], [high + 1, np.nan]])
    many = device.tune_many(targets)
    assert many.ok.tolist() == [[False, True], [False, False]]
    assert np.isnan(many.bias_volts[0, 0]) and not np.isnan(many.bias_volts[0, 1])
    assert many.reason[0] is not None and "outside the tunable range" in many.reason[0]
    assert many.reason[1] is None
    with pytest.raises(ValueError, match="outside the tunable range"):
        device.tune(high + 1)


def test_the_curve_is_the_clis_and_lies_on_the_statics(tmp_path, host_sim):
    device = dr.Device.reference()
    curve = device.curve(points=50, target_hz=44.0)
    theirs = cli(host_sim, "curve", "--points", "50", "--target-hz", "44", "--out", str(tmp_path))
    [one] = theirs["curves"]
    assert curve.bias_volts.tolist() == [p["bias_volts"] for p in one["points"]]
    assert curve.natural_frequency_hz.tolist() == [p["natural_frequency_hz"] for p in one["points"]]
    assert curve.limit == one["limit"] and curve.target == one["target"]
    m = model(device)
    inner = curve.stretch[1:-1]
    assert curve.bias_volts[1:-1] == pytest.approx(m.bias_volts(inner), rel=1e-9)
    assert curve.natural_frequency_hz[1:-1] == pytest.approx(m.frequency_hz(inner), rel=1e-8)
    assert curve.beyond_margin.dtype == np.bool_


def test_a_family_has_a_curve_for_each_pair_and_says_which_make_no_device():
    family = dr.Device().family(prestretch_1=[1.5, 2.0, 2.5], prestretch_2=[0.5, 2.0])
    assert len(dr.Device().family(prestretch_1=2.5)) == 1
    assert len(family) == 6
    assert [(c.prestretch_1, c.prestretch_2) for c in family][:2] == [(1.5, 0.5), (1.5, 2.0)]
    bad = [c for c in family if c.prestretch_2 == 0.5]
    assert all(c.problem and len(c.bias_volts) == 0 for c in bad)
    good = [c for c in family if c.prestretch_2 == 2.0]
    assert all(c.problem is None and len(c.bias_volts) == 200 for c in good)
