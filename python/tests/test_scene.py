"""run_scene: a scene as `host-sim run` runs it, the report and the history as arrays."""

import json
import subprocess

import numpy as np
import pytest

import de_resonator as dr
from conftest import ROOT


def test_the_reference_scene_reports_as_the_cli_and_gives_its_history(host_sim, tmp_path):
    ours = dr.run_scene(str(ROOT / "scenes" / "reference.toml"))
    out = subprocess.run(
        [host_sim, "run", str(ROOT / "scenes" / "reference.toml"), "--out", str(tmp_path),
         "--json"], capture_output=True, text=True,
    )
    assert out.returncode == 0, out.stderr
    theirs = json.loads(out.stdout)
    for key in ["ticks", "bias_volts", "natural_frequency_hz", "relative_error", "fault",
                "plant_crossing", "events", "commands", "final_membrane_volts"]:
        assert ours[key] == theirs[key], key
    history = ours.history
    assert history.time_seconds.shape == (ours.ticks,)
    assert history.dac_code.dtype == np.uint16 and history.enable.dtype == np.bool_
    assert len(history.phase) == ours.ticks and history.phase[-1] == "driving"
    # The stretch the plant holds on average over the last second is the statics' stretch
    # for the bias the board holds (model.md §5, written again in tests/model.py).
    from model import Model

    m = Model(dr.Device.reference().to_dict())
    static = m.stretch_for_bias(ours.bias_volts, top=2.36)
    last = history.time_seconds > history.time_seconds[-1] - 1.0
    assert np.mean(history.stretch[last]) == pytest.approx(static, rel=2e-4)


def test_a_scene_from_its_text_and_its_errors():
    text = (ROOT / "scenes" / "reference.toml").read_text()
    short = text.replace("duration_seconds = 10.0", "duration_seconds = 0.5")
    assert short != text
    ours = dr.run_scene(short)
    assert ours.simulated_seconds == 0.5
    with pytest.raises(FileNotFoundError, match="no-such-scene.toml"):
        dr.run_scene("no-such-scene.toml")
    with pytest.raises(ValueError, match="unknown field"):
        dr.run_scene("name = 'x'\nnonsense = 1\n")
