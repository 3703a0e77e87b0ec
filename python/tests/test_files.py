"""lut, sweep, image and check_image: the CLI's files and JSON for the same inputs, and what
the model says of the response's peak."""

import inspect
import json
import subprocess

import numpy as np
import pytest

import de_resonator as dr
from conftest import ROOT
from model import Model


def cli(host_sim, *args):
    out = subprocess.run([host_sim, *args, "--json"], capture_output=True, text=True)
    assert out.returncode in (0, 1), out.stderr
    return json.loads(out.stdout)


def test_the_table_is_the_clis_byte_for_byte(host_sim, tmp_path):
    device = dr.Device.reference()
    table = device.lut()
    theirs = cli(host_sim, "lut", "--out", str(tmp_path / "t.bin"))
    assert table.data == (tmp_path / "t.bin").read_bytes() and table.bytes == len(table.data)
    assert table.crc32 == theirs["crc32"] and table.points == theirs["points"]
    assert table.natural_frequency_hz.dtype == np.float32 and len(table.bias_volts) == table.points
    # The table's points lie on the statics' curve (model.md §5 in tests/model.py; f32).
    m = Model(device.to_dict())
    top = device.safe(margin=0.0).limit["stretch"]
    for hz, volts in zip(table.natural_frequency_hz, table.bias_volts):
        lam = m.stretch_for_bias(float(volts), top) if volts > 0 else m.l1p
        assert m.frequency_hz(lam) == pytest.approx(float(hz), rel=2e-6)
    written = device.lut(points=64, out=tmp_path / "t.csv")
    assert (tmp_path / "t.csv").read_text().startswith("natural_frequency_hz,bias_volts")
    assert written.files == [str(tmp_path / "t.csv")] and written.format == "csv"
    with pytest.raises(ValueError, match="points"):
        device.lut(points=1)


def test_the_sweep_is_the_clis_and_peaks_at_the_natural_frequency(host_sim, tmp_path):
    device = dr.Device.reference()
    ours = device.sweep(points=41, periods=120, from_ratio=0.8, to_ratio=1.2,
                        bias_volts=4000.0, ac_volts=40.0, quality_factor=50)
    theirs = cli(host_sim, "sweep", "--points", "41", "--periods", "120", "--from-ratio", "0.8",
                 "--to-ratio", "1.2", "--bias-volts", "4000", "--ac-volts", "40",
                 "--quality-factor", "50", "--out", str(tmp_path))
    assert ours.amplitude.tolist() == [p["amplitude"] for p in theirs["points"]]
    assert ours.peaks == theirs["peaks"]
    m = Model(device.to_dict())
    f0 = m.frequency_hz(m.stretch_for_bias(4000.0, device.safe(margin=0.0).limit["stretch"]))
    assert ours.natural_frequency_hz == pytest.approx(f0, rel=1e-9)
    # A Q of 50: the peak within a half-width (f0/2Q) of f0.
    top = ours.drive_hz[np.nanargmax(ours.amplitude)]
    assert abs(top - f0) < f0 / 100 + (ours.drive_hz[1] - ours.drive_hz[0])
    with pytest.raises(ValueError, match="quality_factor -1"):
        device.sweep(quality_factor=-1)


def test_the_image_is_the_clis_and_its_check_accepts_it(host_sim, tmp_path):
    device = dr.Device(shear_modulus=60e3, jlim=None)
    ours = device.safe()
    target = sum(ours.tunable_range_hz) / 2
    made = dr.image(device, target_hz=target, power_up="drive", out=tmp_path / "py.img")
    toml = tmp_path / "d.toml"
    toml.write_text("shear_modulus = 60e3\n")
    subprocess.run([host_sim, "image", "--device", str(toml), "--target-hz", repr(target),
                    "--power-up", "drive", "--out", str(tmp_path / "cli.img")], check=True,
                   capture_output=True)
    assert made.data == (tmp_path / "py.img").read_bytes() == (tmp_path / "cli.img").read_bytes()
    assert made.verdict == dr.check_image(made.data).verdict
    assert dr.check_image(tmp_path / "cli.img") == {**dr.check_image(made.data),
                                                     "file": str(tmp_path / "cli.img")}
    assert dr.image().data == dr.image(dr.Device.reference(), target_hz=44.0).data
    with pytest.raises(ValueError, match="give the target"):
        dr.image(device)
    with pytest.warns(UserWarning, match="`dac_reference_volts` = 2500 V is outside"):
        dr.image(dac_reference_volts=2500.0, gain=4.0)
    with pytest.raises(ValueError, match="power_up `later`"):
        dr.image(power_up="later")
    scene = dr.image(scene=ROOT / "scenes" / "reference.toml")
    assert scene.verdict == dr.check_image(scene.data).verdict
    # A scene's image drives at power-up, as run and serve boot it, unless asked to wait; a
    # device's waits unless asked to drive.
    assert (scene.power_up, made.power_up, dr.image().power_up) == ("drive", "drive", "wait")
    waits = dr.image(scene=ROOT / "scenes" / "reference.toml", power_up="wait")
    assert waits.power_up == "wait" and waits.data != scene.data


def cli_defaults(host_sim, command):
    """`host-sim COMMAND --help`'s defaults, by flag (`--gain` → 4000.0; a path's as text)."""
    text = subprocess.run([host_sim, command, "--help"], capture_output=True, text=True,
                          check=True).stdout
    defaults, flag = {}, None
    for line in text.splitlines():
        words = line.split()
        if words and words[0].startswith("--"):
            flag = words[0].rstrip(",")
        elif flag and "[default: " in line:
            value = line.split("[default: ")[1].split("]")[0]
            try:
                defaults[flag] = float(value)
            except ValueError:
                defaults[flag] = value
    return defaults


def test_the_keywords_defaults_are_the_clis(host_sim):
    # One default a value, whichever way it is asked: each keyword's default in the
    # package's signatures is the flag's in host-sim's --help.
    for function, command in [(dr.image, "image"), (dr.drive_map, "drive-map"),
                              (dr.Device.sweep, "sweep")]:
        flags = cli_defaults(host_sim, command)
        compared = 0
        for name, parameter in inspect.signature(function).parameters.items():
            flag = "--" + name.replace("_", "-")
            if isinstance(parameter.default, (int, float)) and flag in flags:
                assert parameter.default == flags[flag], (command, name)
                compared += 1
        assert compared >= 2, (command, flags)
