"""A batch of membranes (docs/model.md §10): Device(tolerance=...), safe().guaranteed,
tune().band_hz and tune_many's bands, against the batch's corner devices each on its own,
and the same batch read from a device file and through the CLI."""

import itertools
import json
import pickle
import subprocess

import numpy as np
import pytest

import de_resonator as dr

TOLERANCE = {
    "shear_modulus": 0.1,
    "thickness": 0.05,
    "prestretch_1": 0.02,
    "breakdown_field": (35e6, 200e6),
}


def corners(device):
    """Every corner of the batch, each a device without tolerances."""
    ranges = device.tolerance
    keys = {k: v for k, v in device.to_dict().items() if k != "tolerance"}
    for ends in itertools.product(*ranges.values()):
        yield dr.Device(**{**keys, **dict(zip(ranges, ends))})


def test_no_corner_lies_below_the_guaranteed_limit():
    batch = dr.Device(jlim=120, tolerance=TOLERANCE)
    g = batch.safe().guaranteed
    limits = [c.safe().limit["volts"] for c in corners(batch)]
    assert min(limits) >= g["limit"]["volts"] >= 0.97 * min(limits)
    assert g["max_bias_volts"] == pytest.approx(0.95 * g["limit"]["volts"], rel=1e-12)
    assert g["limit"]["mode"] == "breakdown"
    assert batch.tolerance["shear_modulus"] == pytest.approx((40.5e3, 49.5e3))


def test_the_band_holds_every_corner_at_the_bias():
    batch = dr.Device(jlim=120, tolerance=TOLERANCE)
    tuned = batch.tune(45.0)
    low, high = tuned.band_hz
    volts = tuned.bias_volts
    fs = [c.frequency(volts) for c in corners(batch)]
    assert low <= min(fs) and max(fs) <= high
    assert high - low <= 1.1 * (max(fs) - min(fs))
    assert tuned.every_device_reaches is False


def test_tune_many_gives_bands_as_arrays():
    batch = dr.Device(jlim=120, tolerance=TOLERANCE)
    many = batch.tune_many(np.array([44.0, 45.0, 43.1]))
    one = batch.tune(45.0)
    assert many.band_low_hz[1] == one.band_hz[0] and many.band_high_hz[1] == one.band_hz[1]
    # 43.1 Hz needs more than the guaranteed cap on the nominal device: refused, said why.
    assert not many.ok[2] and "guaranteed cap" in many.reason[2]
    assert np.isnan(many.band_low_hz[2])
    with pytest.raises(ValueError, match="guaranteed cap"):
        batch.tune(43.1)


def test_a_batch_pickles_and_reads_from_a_file(tmp_path, host_sim):
    batch = dr.Device(jlim=120, tolerance=TOLERANCE)
    again = pickle.loads(pickle.dumps(batch))
    assert again == batch and again.tolerance == batch.tolerance
    assert batch != dr.Device(jlim=120)
    text = "jlim = 120\n[tolerance]\nshear_modulus = 0.1\nthickness = 0.05\n" \
        "prestretch_1 = 0.02\nbreakdown_field = [35e6, 200e6]\n"
    path = tmp_path / "batch.toml"
    path.write_text(text)
    from_file = dr.Device.from_file(path)
    assert from_file.tolerance == batch.tolerance
    cli = json.loads(subprocess.run([host_sim, "safe", "--device", str(path), "--json"],
                                    capture_output=True, text=True, check=True).stdout)
    assert cli["guaranteed"] == from_file.safe().guaranteed


def test_bad_tolerances_are_refused():
    with pytest.raises(TypeError, match="tolerance"):
        dr.Device(tolerance=0.1)
    with pytest.raises(TypeError, match="fraction or"):
        dr.Device(tolerance={"thickness": "5%"})
    with pytest.raises(TypeError):
        dr.Device(tolerance={"thickness": True})
    with pytest.raises(ValueError, match="unknown field"):
        dr.Device(tolerance={"thicknes": 0.1})
    with pytest.raises(ValueError, match="does not hold"):
        dr.Device(tolerance={"breakdown_field": (1e6, 2e6)})
    with pytest.raises(ValueError, match="fraction in"):
        dr.Device(tolerance={"thickness": 2.0})


def test_an_image_of_a_batch_keeps_it_and_its_cap():
    """`image(batch)`: the board's cap by the batch's guaranteed limit, as host-sim's."""
    batch = dr.Device(jlim=120, tolerance=TOLERANCE)
    made = dr.image(batch, target_hz=45.5)
    verdict = made.verdict
    g = batch.safe().guaranteed["limit"]["volts"]
    assert verdict["cap_by"] == "batch"
    assert verdict["batch_limit_volts"] == pytest.approx(g, rel=1e-6)
    assert verdict["max_volts"] <= 0.95 * g
    assert dr.check_image(made.data).verdict == verdict
