from typing import Any

from ._native import Device as Device
from ._native import bifurcation as bifurcation
from ._native import check_image as check_image
from ._native import drive_map as drive_map
from ._native import image as image
from ._native import lyapunov as lyapunov
from ._native import poincare as poincare
from ._native import run_scene as run_scene
from ._native import simulate as simulate

class Result(dict[str, Any]):
    """A dict whose keys are attributes too (as SciPy's OdeResult)."""

    def __getattr__(self, name: str) -> Any: ...
