"""Type stubs of the hapsyn Python package (see __init__.py for the documentation)."""
import os
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Protocol, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_PathLike = Union[str, os.PathLike[str]]
_PluginPath = Union[None, _PathLike, Sequence[_PathLike]]

__version__: str

class Error(ValueError):
    """Bad input: '<component>: <path> = <value>: <rule>', as the hapsyn program prints it."""

class PythonMetric(Protocol):
    """What register_metric expects of a metric (class or instance)."""
    locals: Sequence[Tuple[str, str, str]]
    needs: Sequence[str]
    def local_batch(self, q: Dict[str, Any]) -> npt.ArrayLike: ...
    # optional: def combine(self, reduced: np.ndarray, samples: int) -> float
    # optional: scene_attributes: Sequence[str]; batch_size: int

class Result:
    status: str
    message: str
    objective_names: List[str]
    free_names: List[str]
    best_design: Optional[Dict[str, Any]]
    best_objectives: Optional[Dict[str, float]]
    best_score: Optional[float]
    front: Optional[npt.NDArray[np.float64]]
    front_designs: Optional[npt.NDArray[np.float64]]
    statistics: Dict[str, Any]
    info: Dict[str, Any]
    output_directory: Optional[str]
    def to_dict(self) -> Dict[str, Any]: ...
    def to_pandas(self) -> Any: ...

class Scene:
    samples: npt.NDArray[np.float64]
    coordinates: List[str]
    unit: str
    attributes: Dict[str, npt.NDArray[np.float64]]
    weights: Optional[npt.NDArray[np.float64]]
    info: Dict[str, Any]
    def __len__(self) -> int: ...

class Study:
    resolved: Dict[str, Any]
    free_names: List[str]
    objective_names: List[str]
    local_names: List[str]
    @property
    def dimension(self) -> int: ...
    @property
    def scene(self) -> Scene: ...
    def run(
        self,
        threads: Optional[int] = ...,
        seed: Optional[int] = ...,
        progress: Optional[Callable[[str], Any]] = ...,
        out: Optional[_PathLike] = ...,
        force: bool = ...,
        write_samples: Optional[bool] = ...,
        resume: bool = ...,
    ) -> Result: ...
    def evaluate(
        self,
        design: Union[npt.ArrayLike, Mapping[str, Any]],
        samples: bool = ...,
        quantities: Optional[Iterable[str]] = ...,
        threads: int = ...,
    ) -> Dict[str, Any]: ...

def version() -> str: ...
def load(
    problem: Union[_PathLike, Mapping[str, Any]],
    set: Sequence[str] = ...,
    plugin_path: _PluginPath = ...,
    metrics: Optional[Mapping[str, Any]] = ...,
) -> Study: ...
def plugins(plugin_path: _PluginPath = ...) -> List[Dict[str, str]]: ...
def describe(name: str, plugin_path: _PluginPath = ...) -> Dict[str, Any]: ...
def register_metric(name: str, metric: Any) -> None: ...
def unregister_metric(name: str) -> None: ...
def registered_metrics() -> Dict[str, Any]: ...
