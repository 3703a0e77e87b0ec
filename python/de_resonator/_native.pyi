"""Type stubs of de_resonator._native (the Rust extension). Units are SI, named in keys."""

from os import PathLike
from typing import Any, Literal, Optional, Union

import numpy as np
import numpy.typing as npt

from . import Result

ArrayLike = npt.ArrayLike
Method = Literal[
    "reference",
    "reference-radau",
    "rk4-f32",
    "rk4-f64",
    "verlet-f32",
    "verlet-f64",
    "implicit-midpoint-f32",
    "implicit-midpoint-f64",
]

class Device:
    """A dielectric elastomer resonator (docs/model.md). Keywords: the device file's keys in
    SI units; absent keys take the reference device's values, an absent `jlim` makes it
    neo-Hookean (`jlim=None` says so). ValueError with the model's reason if it refuses a
    value; TypeError for a value that is no number (a bool included). `tolerance` declares a
    batch (docs/model.md §10): {key: fraction (0.1 for ±10%) or (low, high) in SI units}."""

    def __init__(
        self,
        *,
        shear_modulus: float = ...,
        jlim: Optional[float] = ...,
        relative_permittivity: float = ...,
        density: float = ...,
        breakdown_field: float = ...,
        thickness: float = ...,
        length_active: float = ...,
        length_passive: float = ...,
        width: float = ...,
        bar_mass: float = ...,
        prestretch_1: float = ...,
        prestretch_2: float = ...,
        damping: float = ...,
        tolerance: Optional[dict[str, Union[float, tuple[float, float]]]] = ...,
    ) -> None: ...
    @staticmethod
    def reference() -> Device:
        """The reference device of docs/model.md §9."""
    @staticmethod
    def from_file(path: Union[str, PathLike[str]]) -> Device:
        """A device file (TOML, SI units), as `host-sim --device FILE` reads it
        (FileNotFoundError if it is not there)."""
    @staticmethod
    def from_toml(text: str) -> Device:
        """A device file's text."""
    @property
    def material(self) -> Literal["gent", "neo_hookean"]: ...
    @property
    def source(self) -> str: ...
    @property
    def tolerance(self) -> Optional[dict[str, tuple[float, float]]]:
        """The tolerances as ranges (SI units); None without any."""
    def to_dict(self) -> dict[str, Any]:
        """The keys and values (SI), and `tolerance` if any: `Device(**d)` makes the same
        device."""
    def __getitem__(self, key: str) -> float: ...
    def __eq__(self, other: object) -> bool: ...
    def safe(self, margin: float = 0.05) -> Result:
        """The safe region: `limit` (mode, volts V, stretch, natural_frequency_hz Hz),
        `max_bias_volts` (V), `tunable_range_hz` (Hz), `zero_bias_frequency_hz` (Hz); with
        tolerances `guaranteed` (the certified limit of every device, its cap and range)."""
    def tune(self, target_hz: float, margin: float = 0.05) -> Result:
        """The smallest bias for `target_hz`: `bias_volts` (V), `stretch`,
        `natural_frequency_hz` (Hz) and the safe region; with tolerances `band_hz` (the
        batch's frequencies at that bias) and `every_device_reaches`. ValueError out of
        reach, or above a batch's guaranteed cap."""
    def frequency(self, bias_volts: ArrayLike) -> Union[float, npt.NDArray[np.float64]]:
        """The natural frequency (Hz) at each bias (V, an int or float dtype); NaN where no
        equilibrium holds it (below 0 V, or past the limit)."""
    def tune_many(self, targets_hz: ArrayLike, margin: float = 0.05) -> Result:
        """`tune` for each target: arrays `bias_volts` (V), `stretch`,
        `natural_frequency_hz` (Hz) with NaN where out of reach, `ok` (bool), and `reason`
        (a list, None where tuned); with tolerances `band_low_hz`, `band_high_hz` (Hz) and
        `every_device_reaches` (bool)."""
    def curve(
        self, points: int = 200, margin: float = 0.05, target_hz: Optional[float] = None
    ) -> Result:
        """The tuning curve to the limit: arrays `bias_volts` (V), `natural_frequency_hz`
        (Hz), `stretch`, `beyond_margin`; `limit`, `max_bias_volts`, `tunable_range_hz`,
        `target`, `problem`."""
    def family(
        self,
        prestretch_1: Optional[ArrayLike] = None,
        prestretch_2: Optional[ArrayLike] = None,
        points: int = 200,
        margin: float = 0.05,
        target_hz: Optional[float] = None,
    ) -> list[Result]:
        """A `curve` for each pre-stretch pair (λ1p × λ2p)."""
    def lut(
        self,
        points: Optional[int] = None,
        margin: float = 0.05,
        out: Optional[Union[str, PathLike[str]]] = None,
    ) -> Result:
        """The tuning table to flash: `data` (bytes), float32 arrays `natural_frequency_hz` (Hz) and
        `bias_volts` (V), `crc32`, `interpolation_error`; `out` writes it (.csv: points)."""
    def sweep(
        self,
        bias_volts: Optional[float] = None,
        ac_volts: Optional[float] = None,
        quality_factor: float = 200.0,
        from_ratio: float = 0.3,
        to_ratio: float = 2.4,
        points: int = 211,
        periods: float = 400.0,
        steps_per_period: float = 48.0,
    ) -> Result:
        """The frequency response: arrays `drive_hz` (Hz), `ratio`, `amplitude` (NaN where a
        run stopped), `crossed`; `peaks`, `natural_frequency_hz`, `damping` (N·s)."""

def simulate(
    device: Device,
    bias_volts: float,
    *,
    duration_seconds: float,
    ac_volts: float = 0.0,
    ac_hz: Optional[float] = None,
    method: Method = "reference",
    rtol: Optional[float] = None,
    atol: Optional[float] = None,
    step_seconds: Optional[float] = None,
    start: Literal["equilibrium", "prestretch"] = "equilibrium",
    damping: Optional[float] = None,
    stop_at_limit: bool = True,
    y0: Optional[ArrayLike] = None,
    t_eval: Optional[ArrayLike] = None,
) -> Result:
    """The motion under Φ(t) = bias_volts + ac_volts·sin(2π·ac_hz·t), checked against
    docs/model.md §6: a Result like SciPy's OdeResult (`t` s, `y` 2 × n: stretch and dλ/dt
    1/s, `volts` V, `status` 0 or 1, `message`, `success`, `t_events`, `y_events`, `limit`,
    `min_stretch`, `max_stretch`, `nfev`). `y0`: a start (stretch, dλ/dt 1/s) over `start`;
    `t_eval`: the times to give the state at, as SciPy's."""

def poincare(
    device: Device,
    bias_volts: float,
    ac_volts: float,
    ac_hz: float,
    *,
    periods: int = 200,
    transient_periods: int = 0,
    y0: Optional[ArrayLike] = None,
    damping: Optional[float] = None,
    quality_factor: Optional[float] = None,
    rtol: Optional[float] = None,
) -> Result:
    """A Poincaré section at the drive's phase 0: `stretch`, `velocity` (1/s) at `t` = k/ac_hz,
    k from `transient_periods` on; `y0` one start (stretch, dλ/dt) or an n × 2 array (rows);
    default the rest state at the bias. `limit`, `limit_time_seconds`, `stopped` per run."""

def bifurcation(
    device: Device,
    bias_volts: ArrayLike,
    ac_hz: ArrayLike,
    ac_volts: ArrayLike,
    *,
    periods: int = 50,
    transient_periods: int = 100,
    direction: Literal["up", "down", "both"] = "both",
    y0: Optional[ArrayLike] = None,
    damping: Optional[float] = None,
    quality_factor: Optional[float] = None,
    rtol: Optional[float] = None,
) -> Result:
    """A bifurcation diagram by continuation over the one of `bias_volts`, `ac_hz`, `ac_volts`
    given as an increasing array: `parameter` and `direction` per row, `varied`, `stretch` and
    `velocity` (rows × periods), `limit`, `limit_time_seconds`, `stopped` per row."""

def lyapunov(
    device: Device,
    bias_volts: float,
    ac_volts: float = 0.0,
    ac_hz: float = 0.0,
    *,
    periods: int = 200,
    transient_periods: int = 20,
    y0: Optional[ArrayLike] = None,
    damping: Optional[float] = None,
    quality_factor: Optional[float] = None,
    rtol: Optional[float] = None,
) -> Result:
    """The largest Lyapunov exponent, 1/s (`exponent`), with its convergence (`t` s,
    `estimate` 1/s), `interval_seconds`, `limit`, `limit_time_seconds`, `stopped`."""

def drive_map(
    device: Optional[Device] = None,
    *,
    ac_volts: ArrayLike,
    ac_hz: ArrayLike,
    target_hz: Optional[float] = None,
    periods: float = 200.0,
    quality_factor: Optional[float] = None,
    settings: Optional[Union[str, PathLike[str]]] = None,
    gain: float = 4000.0,
) -> Result:
    """The safe drive map at the board's bias for `target_hz`: `max_swing`, `safe` (the full
    simulation inside §6), `accepted` and `refusal` (the board's checks), `limit`, `stopped`,
    each len(ac_volts) × len(ac_hz); `bias_volts`, `stretch`, `natural_frequency_hz`,
    `duration_seconds`, `damping`, `disagreements` (accepted yet not safe)."""

def run_scene(scene: Union[str, PathLike[str]]) -> Result:
    """A scene (a file's path, or its TOML text) as `host-sim run` runs it: the report
    (`run --json`'s keys) and `history` (per tick: `time_seconds` s, `dac_code`, `dac_on`,
    `enable`, `phase`, `stretch`, `membrane_volts` V, `current_amps` A)."""

def image(
    device: Optional[Device] = None,
    *,
    settings: Optional[Union[str, PathLike[str]]] = None,
    target_hz: Optional[float] = None,
    dac_reference_volts: float = 2.5,
    gain: float = 4000.0,
    rail_volts: Optional[float] = None,
    power_up: Optional[Literal["wait", "drive"]] = None,
    scene: Optional[Union[str, PathLike[str]]] = None,
    out: Optional[Union[str, PathLike[str]]] = None,
) -> Result:
    """The configuration image to flash: `data` (bytes) and what it holds (`verdict`, `table`,
    `settings`, `amplifier`); ValueError if the firmware's boot would refuse it. `power_up`:
    `wait` (the default) or `drive`; a `scene`'s image drives unless it says `wait`."""

def check_image(image: Union[bytes, str, PathLike[str]]) -> Result:
    """What an image or a table holds, and whether the firmware's boot accepts it."""

def _device_from_keys(keys: dict[str, float]) -> Device: ...
