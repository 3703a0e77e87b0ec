"""Shared by the tests: random valid devices, and the host-sim binary for the CLI's JSON."""

import os
import pathlib
import shutil

import numpy as np
import pytest

import de_resonator as dr

ROOT = pathlib.Path(__file__).resolve().parents[2]


def random_devices(count, seed):
    """`count` devices the model accepts, drawn around the reference device (SI units)."""
    rng = np.random.default_rng(seed)
    devices = []
    while len(devices) < count:
        keys = dict(
            shear_modulus=rng.uniform(20e3, 200e3),
            jlim=rng.uniform(40, 200),
            relative_permittivity=rng.uniform(2.5, 6),
            density=rng.uniform(900, 1200),
            breakdown_field=rng.uniform(50e6, 300e6),
            thickness=rng.uniform(0.2e-3, 2e-3),
            length_active=rng.uniform(10e-3, 40e-3),
            length_passive=rng.uniform(10e-3, 40e-3),
            width=rng.uniform(20e-3, 60e-3),
            bar_mass=rng.uniform(0.5e-3, 5e-3),
            prestretch_1=rng.uniform(1.5, 3.5),
            prestretch_2=rng.uniform(1.5, 3.5),
        )
        try:
            devices.append(dr.Device(**keys))
        except ValueError:
            continue
    return devices


@pytest.fixture(scope="session")
def host_sim():
    """The host-sim binary (`HOST_SIM`, else the workspace's build): the CLI whose JSON the
    package must match."""
    for candidate in [
        os.environ.get("HOST_SIM"),
        ROOT / "target" / "debug" / "host-sim",
        ROOT / "target" / "release" / "host-sim",
        shutil.which("host-sim"),
    ]:
        if candidate and pathlib.Path(candidate).is_file():
            return str(candidate)
    pytest.fail("no host-sim binary: build it (`cargo build -p host-sim`) or set HOST_SIM")
