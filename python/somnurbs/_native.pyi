"""Type stubs of the Rust extension (python/src/lib.rs)."""

from os import PathLike
from typing import Any, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str
SPECS: tuple[str, ...]

class Problem:
    """One control-net problem: minimise the thesis' Eq. 6.2 over the control points."""

    name: str
    function_id: int
    dataset: str
    grid: str
    net: str
    parameterisation: str
    reading: str
    spec: str
    profile: Optional[str]
    box_label: str
    dimension: int
    x0: npt.NDArray[np.float64]
    b: float
    lower: npt.NDArray[np.float64]
    upper: npt.NDArray[np.float64]
    lower_data: npt.NDArray[np.float64]
    upper_data: npt.NDArray[np.float64]
    has_exact_solver: bool
    def f(self, x: npt.ArrayLike) -> Union[float, npt.NDArray[np.float64]]: ...
    def exact(self, box: str = "spec") -> dict[str, Any]:
        """The certified optimum: ``interval`` = (``lower_bound``, ``f``) holds min f over the box;
        ``f`` is the value at ``x`` (an upper bound), ``gap`` = f - lower_bound, ``converged``,
        ``iterations``."""
        ...
    def has_exact(self, box: str = "spec") -> bool: ...
    def metadata(self) -> dict[str, Any]: ...

def problems(
    spec: str = "ch6_same",
    profile: Optional[str] = None,
    reading: Optional[str] = None,
    set: Optional[Sequence[str]] = None,
    data_dir: Optional[Union[str, PathLike[str]]] = None,
) -> list[Problem]: ...
