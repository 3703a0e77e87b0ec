"""de-resonator from Python: tunable dielectric elastomer resonators over numpy.

The same code the `host-sim` CLI and the firmware run (the Rust core and host-sim's
engines, built into ``de_resonator._native``): no second implementation.

- ``Device``: a resonator, from keyword arguments (SI units), a device file or
  ``Device.reference()``; ``safe``, ``tune``, ``frequency``, ``tune_many``, ``curve``,
  ``family``, ``sweep`` (the frequency response), ``lut`` (the table to flash).
- ``simulate``: the motion under a bias and an AC drive, shaped like SciPy's OdeResult.
- ``poincare``, ``bifurcation``, ``lyapunov``: the driven membrane's nonlinear dynamics
  (Poincaré sections, bifurcation diagrams by continuation, the largest Lyapunov exponent);
  ``drive_map``: the safe drive map beside the board's own acceptance.
- ``run_scene``: a scene file run as ``host-sim run`` runs it (the board against the plant).
- ``image``, ``check_image``: the configuration image to flash, and what one holds.

Units are SI throughout and carried in names: ``bias_volts``, ``natural_frequency_hz``,
``duration_seconds``. See docs/python.md.
"""

from ._native import (
    Device,
    bifurcation,
    check_image,
    drive_map,
    image,
    lyapunov,
    poincare,
    run_scene,
    simulate,
)

__all__ = [
    "Device",
    "Result",
    "bifurcation",
    "check_image",
    "drive_map",
    "image",
    "lyapunov",
    "poincare",
    "run_scene",
    "simulate",
]


class Result(dict):
    """What a call returns: a dict whose keys are attributes too (as SciPy's OdeResult)."""

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError as missing:
            raise AttributeError(name) from missing

    def __dir__(self):
        return list(self.keys())

    def __repr__(self):
        if not self:
            return "Result()"
        width = max(len(k) for k in self) + 1
        return "\n".join(f"{k.rjust(width)}: {_short(v)}" for k, v in self.items())

    def __reduce__(self):
        return (Result, (dict(self),))


def _short(value):
    """A value as one line: arrays by their shape and ends."""
    shape = getattr(value, "shape", None)
    if shape is not None and len(shape) > 0 and value.size > 6:
        return f"array of shape {shape}, dtype {value.dtype}"
    text = repr(value)
    return text if "\n" not in text else " ".join(text.split())
