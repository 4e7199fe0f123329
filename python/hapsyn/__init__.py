"""hapsyn in Python: load a study, run it, evaluate designs, and write metrics in Python.

The same studies as the ``hapsyn`` program (a JSON problem file wiring a mechanism, a scene,
metrics and a solver, each a plugin), from Python::

    >>> import hapsyn
    >>> study = hapsyn.load("problems/fivebar-table2-best-gii.json", set=["threads=1"])
    >>> result = study.run()                  # the solver, as `hapsyn run`
    >>> result.best_objectives                # doctest: +ELLIPSIS
    {'gdi': 0.6218..., 'gii': 0.7827...}
    >>> study.evaluate(result.best_design)["status"]
    'feasible'

(The example runs in the tests, from the source directory.)

Errors in the input raise :class:`hapsyn.Error` (a ``ValueError``) with exactly the message
the command-line program prints after ``hapsyn: error:``.

Plugins are found as the program finds them: the directories of ``plugin_path`` first, then
``HAPSYN_PLUGIN_PATH``, then the ``hapsyn/plugins`` directory next to ``libhapsyn``.
"""
from __future__ import annotations

import json as _json
import os as _os
import shutil as _shutil
import tempfile as _tempfile
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Union

import numpy as _np

from . import _hapsyn
from ._hapsyn import Error

# Worker threads a run or an evaluation may ask for (the program's limit, docs/limits.md).
_MAX_THREADS = 1024

__all__ = [
    "Error",
    "Result",
    "Scene",
    "Study",
    "describe",
    "load",
    "plugins",
    "register_metric",
    "registered_metrics",
    "unregister_metric",
    "version",
]

__version__ = _hapsyn.version()


def __dir__() -> List[str]:
    """hapsyn's own names only (not the typing helpers this module imports)."""
    return sorted(__all__ + ["__version__"])

Error.__doc__ = (
    "Bad input (problem files, overrides, options, designs): a ValueError whose message is "
    "'<component>: <path> = <value>: <rule>', exactly as the hapsyn program prints it."
)

_PathLike = Union[str, "_os.PathLike[str]"]


def version() -> str:
    """The version of the hapsyn library the package is built against."""
    return _hapsyn.version()


def _paths(plugin_path: Union[None, _PathLike, Sequence[_PathLike]]) -> List[str]:
    if plugin_path is None:
        return []
    if isinstance(plugin_path, (str, _os.PathLike)):
        return [_os.fspath(plugin_path)]
    return [_os.fspath(p) for p in plugin_path]


def _is_numeric(value: Any) -> bool:
    """True for a number or a (nested) list or array of numbers."""
    try:
        return _np.asarray(value).dtype.kind in "iuf"
    except (TypeError, ValueError):
        return False


def _whole_number(value: Any, name: str, lowest: int, highest: int) -> int:
    """``value`` as an int within [lowest, highest], else :class:`Error` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, _np.integer)) or not lowest <= value <= highest:
        raise Error(f"python: {name} = {value!r}: must be an integer from {lowest} to {highest}")
    return int(value)


def _to_json(value: Any) -> str:
    """JSON text of a Python value; NumPy scalars and arrays become numbers and lists."""

    def default(o: Any) -> Any:
        if isinstance(o, _np.ndarray):
            return o.tolist()
        if isinstance(o, _np.generic):
            return o.item()
        if isinstance(o, _os.PathLike):
            return _os.fspath(o)
        raise TypeError(f"hapsyn: {type(o).__name__} is not JSON serialisable")

    return _json.dumps(value, default=default, allow_nan=False)


def plugins(plugin_path: Union[None, _PathLike, Sequence[_PathLike]] = None) -> List[Dict[str, str]]:
    """Every plugin in the search path, as `hapsyn plugins` lists them.

    Returns a list of dicts with ``name``, ``kind`` (mechanism, scene, metric, solver),
    ``version``, ``description``, ``thread_safety`` and ``file``. Files that fail to load are
    left out (as the program reports them separately).
    """
    found, _errors = _hapsyn.plugins(_paths(plugin_path))
    return list(found)


def describe(name: str, plugin_path: Union[None, _PathLike, Sequence[_PathLike]] = None) -> Dict[str, Any]:
    """The options schema of plugin ``name`` as a dict: what ``hapsyn describe NAME --json`` prints.

    Raises :class:`Error` for an unknown plugin (the message names the nearest known one).
    """
    return _json.loads(_hapsyn.describe(name, _paths(plugin_path)))


# ---------------------------------------------------------------------------------------------
# Metrics written in Python

_registered: Dict[str, Any] = {}


def register_metric(name: str, metric: Any) -> None:
    """Makes a Python metric available to studies under ``name`` (an objective's ``"metric"``).

    ``metric`` is a class (instantiated once per objective with the objective's ``"options"`` as
    keyword arguments) or an instance (used as is; its objective must have no options). It
    provides:

    - ``locals``: list of ``(name, reduction, unit)``; reduction ``"min"``, ``"max"`` or ``"sum"``
      (as a C++ metric's ``locals()``).
    - ``needs``: list of quantity names the mechanism must compute: ``"jacobian"``,
      ``"inertia"``, ``"effective_mass"``, ``"gravity"``, ``"max_velocity"``/``"max_torque"``,
      ``"joint_velocity"``, ``"joint_acceleration"``, ``"velocity_torque"`` (the last three need a
      scene with the demanded motion: ``twist`` / ``twist_rate`` attributes).
    - ``local_batch(q) -> array``: the local values of a chunk of samples, shape
      ``(n, len(locals))`` (or ``(n,)`` for one local). ``q`` is a dict of NumPy arrays over the
      chunk: ``sample`` (indices), ``status`` (0 reachable, 1 unreachable, 2 singular,
      3 invalid), ``pose`` (n x scene dimension), ``q`` (joint angles) and the quantities in
      ``needs`` (e.g. ``jacobian``: n x rows x cols), NaN where a sample is not reachable, and
      ``attributes`` (the scene attributes listed in the optional ``scene_attributes``).
      Worst-case metrics (only min/max reductions) see reachable samples only; averaging ones
      see every sample. Called once per chunk, not per sample.
    - optional ``combine(reduced, samples) -> float``: the metric's value from the reduced
      locals (default ``reduced[0]``); also called on partial reductions.
    - optional ``scene_attributes`` (list of names) and ``batch_size`` (samples per chunk,
      default 4096).

    The framework calls it from one thread at a time with the GIL held (it is declared
    ``ThreadSafety::kSerialized``). Registering a name again replaces the earlier metric.
    """
    if not isinstance(name, str) or not name:
        raise TypeError("hapsyn.register_metric: name must be a non-empty string")
    for attribute in ("locals", "local_batch"):
        if not hasattr(metric, attribute):
            raise TypeError(f"hapsyn.register_metric: metric '{name}' has no '{attribute}'")
    _registered[name] = metric


def unregister_metric(name: str) -> None:
    """Forgets a metric registered with :func:`register_metric` (no error when unknown)."""
    _registered.pop(name, None)


def registered_metrics() -> Dict[str, Any]:
    """The Python metrics registered so far, by name."""
    return dict(_registered)


def _factory(name: str, metric: Any) -> Callable[[str, str], Any]:
    def make(options_json: str, json_path: str) -> Any:
        options = _json.loads(options_json)
        if isinstance(metric, type):
            try:
                return metric(**options)
            except TypeError as e:
                raise Error(f"problem: {json_path}.options = {options_json}: {e}") from None
        if options:
            raise Error(
                f"problem: {json_path}.options = {options_json}: the Python metric '{name}' is an instance "
                "and takes no options (register its class to pass options)"
            )
        return metric

    return make


# ---------------------------------------------------------------------------------------------
# Results


class Result:
    """The outcome of :meth:`Study.run`: the content of result.json with NumPy views of it.

    Attributes:
        status: ``"converged"``, ``"budget_exhausted"``, ``"infeasible"``, ``"stopped"`` or
            ``"failed"``.
        message: the solver's message.
        best_design: the best design's variables (``{"l1": 0.3, ...}``; a vector variable as a
            list), or None for a solver that returns a front.
        best_objectives: the best design's objective values by name, or None.
        front: the Pareto front as an array (points x objectives), or None.
        front_designs: the front's free design values (points x free variables), or None.
        objective_names: the objectives, in the order of the front's columns.
        free_names: the free design components, in the order of front_designs' columns.
        statistics: the solver's figures (result.json's "statistics").
        info: the rest of result.json (seed, threads, machine, evaluations, times, scene...).
        output_directory: where result.json was written, or None when it was a temporary
            directory (removed again).
    """

    def __init__(self, document: Dict[str, Any], objective_names: Sequence[str], free_names: Sequence[str],
                 output_directory: Optional[str]) -> None:
        self._doc = document
        self.status: str = document["status"]
        self.message: str = document.get("message", "")
        self.objective_names: List[str] = list(objective_names)
        self.free_names: List[str] = list(free_names)
        best = document.get("best")
        self.best_design: Optional[Dict[str, Any]] = dict(best["design"]) if best else None
        self.best_objectives: Optional[Dict[str, float]] = dict(best["objectives"]) if best else None
        self.best_score: Optional[float] = best["score"] if best else None
        front = document.get("front")
        if front:
            self.front: Optional[_np.ndarray] = _np.array(
                [[p["objectives"][n] for n in self.objective_names] for p in front], dtype=float)
            self.front_designs: Optional[_np.ndarray] = _np.array(
                [[_component(p["design"], n) for n in self.free_names] for p in front], dtype=float)
        else:
            self.front = None
            self.front_designs = None
        self.statistics: Dict[str, Any] = document.get("statistics", {})
        self.info: Dict[str, Any] = {k: v for k, v in document.items()
                                     if k not in ("status", "message", "best", "front", "statistics")}
        self.output_directory = output_directory

    def to_dict(self) -> Dict[str, Any]:
        """result.json as a dict (a deep copy: the same JSON the program writes)."""
        return _json.loads(_json.dumps(self._doc))

    def to_pandas(self) -> Any:
        """The front (or the best design) as a pandas DataFrame: one row per point, the free
        design components then the objectives as columns.

        Raises ImportError when pandas is not installed.
        """
        try:
            import pandas
        except ImportError as e:
            raise ImportError(
                "hapsyn.Result.to_pandas needs pandas, which is not installed for this interpreter "
                "(Debian: apt install python3-pandas; else: pip install pandas); "
                "Result.front / front_designs / to_dict() work without it") from e
        points = self._doc.get("front") or ([self._doc["best"]] if self._doc.get("best") else [])
        rows = []
        for p in points:
            row = {n: _component(p["design"], n) for n in self.free_names}
            row.update({n: p["objectives"][n] for n in self.objective_names})
            rows.append(row)
        return pandas.DataFrame(rows, columns=self.free_names + self.objective_names)

    def __repr__(self) -> str:
        what = (f"best={self.best_objectives}" if self.best_objectives is not None
                else f"front={None if self.front is None else self.front.shape[0]} points")
        return f"<hapsyn.Result status={self.status!r} {what}>"


def _component(design: Mapping[str, Any], name: str) -> float:
    """Value of component "l1" or "l[2]" in a grouped design dict."""
    if name in design:
        return float(design[name])
    variable, _, index = name.partition("[")
    return float(design[variable][int(index.rstrip("]"))])


class Scene:
    """The samples of a study's scene (read-only NumPy views into the study's memory; they keep
    the study alive).

    Attributes:
        samples: array (samples x coordinates), one pose per row.
        coordinates: the names of the columns (e.g. ``["x", "y"]``).
        unit: the position unit.
        attributes: per-sample attribute arrays by name (one row per sample).
        weights: per-sample weights, or None (every weight 1).
        info: what the scene reports about itself (result.json's "scene").
    """

    def __init__(self, d: Dict[str, Any]) -> None:
        self.samples: _np.ndarray = d["samples"]
        self.coordinates: List[str] = list(d["coordinates"])
        self.unit: str = d["unit"]
        self.attributes: Dict[str, _np.ndarray] = dict(d["attributes"])
        self.weights: Optional[_np.ndarray] = d["weights"]
        self.info: Dict[str, Any] = _json.loads(d["info"])

    def __len__(self) -> int:
        return int(self.samples.shape[0])

    def __repr__(self) -> str:
        return f"<hapsyn.Scene {len(self)} samples ({', '.join(self.coordinates)}; {self.unit})>"


# ---------------------------------------------------------------------------------------------
# Studies


class Study:
    """A validated, ready-to-run study (see :func:`load`)."""

    def __init__(self, handle: Any) -> None:
        self._handle = handle
        self.resolved: Dict[str, Any] = _json.loads(handle.resolved())
        """The problem with defaults and overrides applied (result.json's "problem")."""
        self.free_names: List[str] = list(handle.free_names())
        """The free design components ("l1", "l[2]"), in the order of design arrays."""
        self.objective_names: List[str] = list(handle.objective_names())
        """The objectives, in the order of objective arrays."""
        self.local_names: List[str] = list(handle.local_names())
        """"<metric>.<local>" for every local value, in the order of per-sample local arrays."""
        self._scene: Optional[Scene] = None

    @property
    def dimension(self) -> int:
        """The number of free design components."""
        return len(self.free_names)

    @property
    def scene(self) -> Scene:
        """The scene's samples (zero-copy views), attributes, weights and info."""
        if self._scene is None:
            self._scene = Scene(self._handle.scene())
        return self._scene

    def run(self, threads: Optional[int] = None, seed: Optional[int] = None,
            progress: Optional[Callable[[str], Any]] = None, out: Optional[_PathLike] = None,
            force: bool = False, write_samples: Optional[bool] = None, resume: bool = False) -> Result:
        """Runs the study's solver, as ``hapsyn run`` does, and returns its :class:`Result`.

        Args:
            threads: worker threads (None: the file's "threads", else all cores).
            seed: the random seed (None: the file's, else drawn; recorded in the result).
            progress: called with each progress line the solver writes (a str), from the
                calling thread with the GIL held; None = quiet.
            out: the output directory for result.json (and samples.csv, maps.csv); None = a
                temporary directory, removed after the run.
            force: overwrite a finished study in ``out``.
            write_samples: write samples.csv / maps.csv (default: only when ``out`` is given).
            resume: continue a stopped run from the checkpoint in ``out`` (as ``hapsyn run
                --resume``; a stopped run's message says when).

        The solver runs on a worker thread with the GIL released. Ctrl-C (KeyboardInterrupt)
        during the run asks the solver to stop: run() returns the best found so far with status
        ``"stopped"``. Raises :class:`Error` for an unusable output directory; an exception
        raised by ``progress`` or by a Python metric stops the run and is raised again.
        """
        if threads is not None:
            threads = _whole_number(threads, "threads", 0, _MAX_THREADS)
        if seed is not None:
            seed = _whole_number(seed, "seed", 0, 2**64 - 1)
        temporary = out is None
        directory = _tempfile.mkdtemp(prefix="hapsyn-run-") if temporary else _os.fspath(out)
        if write_samples is None:
            write_samples = not temporary
        try:
            if resume and temporary:
                raise Error("python: resume=True needs out= (the directory holding the stopped run's checkpoint)")
            text = self._handle.run(threads, seed, directory, force, write_samples, progress, resume)
        finally:
            if temporary:
                _shutil.rmtree(directory, ignore_errors=True)
        return Result(_json.loads(text), self.objective_names, self.free_names,
                      None if temporary else directory)

    def _free(self, design: Any) -> _np.ndarray:
        if isinstance(design, Mapping):
            for name, value in design.items():
                numbers = _np.asarray(value, dtype=float) if _is_numeric(value) else None
                if numbers is not None and not _np.all(_np.isfinite(numbers)):
                    raise Error(f"python: design.{name} = {value!r}: must be finite")
            return _np.asarray(self._handle.free_from_json(_to_json(dict(design))), dtype=float)
        return _np.asarray(design, dtype=float)

    def evaluate(self, design: Any, samples: bool = False, quantities: Optional[Iterable[str]] = None,
                 threads: int = 1) -> Dict[str, Any]:
        """Evaluates one design or a batch, as the solvers do (the full scene).

        Args:
            design: the free design values: a 1-D array (``dimension`` values, order
                ``free_names``), a dict of design variables (``{"l1": 0.3, "l": [..]}``; fixed
                ones may be left out) or a 2-D array (one design per row).
            samples: also return per-sample records (one design only): ``sample_status``
                (array of str: reachable, unreachable, singular, invalid), ``locals`` (samples x
                ``local_names``, NaN where not computed) and ``local_names``.
            quantities: also return these mechanism quantities per sample under
                ``"quantities"`` (one design only): names as in :func:`register_metric`'s
                ``needs``; each an array (samples x rows x cols, NaN where not reachable), plus
                ``q`` (joint angles).
            threads: >1 splits the samples over threads (Problem::evaluate_parallel).

        Returns:
            One design: ``{"status": str, "feasible": bool, "objectives": {name: value},
            "score": float, "samples_evaluated": int, "failed_sample": int}`` (objectives NaN
            when not feasible). A batch: ``{"status": list of str, "objectives": array (n x
            objectives), "score": array, "samples_evaluated": array, "failed_sample": array}``.

        Raises :class:`Error` for a design of the wrong size, outside its bounds or not finite.
        """
        threads = _whole_number(threads, "threads", 1, _MAX_THREADS)
        free = self._free(design)
        single = free.ndim == 1
        rows = free.reshape(1, -1) if single else free
        if rows.ndim != 2:
            raise Error(f"python: design: an array with {free.ndim} dimensions is neither one design nor a batch")
        if isinstance(quantities, str):
            raise Error(f"python: quantities = {quantities!r}: must be a list of names, e.g. [{quantities!r}]")
        want_samples = samples or quantities is not None
        if want_samples and not single:
            raise Error("python: design: samples=True and quantities need one design, not a batch")
        r = self._handle.evaluate(rows, threads)
        if not single:
            return r
        out: Dict[str, Any] = {
            "status": r["status"][0],
            "feasible": r["status"][0] == "feasible",
            "objectives": {n: float(v) for n, v in zip(self.objective_names, r["objectives"][0])},
            "score": float(r["score"][0]),
            "samples_evaluated": int(r["samples_evaluated"][0]),
            "failed_sample": int(r["failed_sample"][0]),
        }
        if want_samples:
            out.update(self._handle.evaluate_samples(rows[0], list(quantities or [])))
        return out

    def __repr__(self) -> str:
        return (f"<hapsyn.Study {self.resolved.get('name')!r}: {self.dimension} free variables, "
                f"objectives {self.objective_names}, solver {self.resolved['solver']['plugin']!r}>")


def load(problem: Union[_PathLike, Mapping[str, Any]], set: Sequence[str] = (),  # noqa: A002 (mirrors --set)
         plugin_path: Union[None, _PathLike, Sequence[_PathLike]] = None,
         metrics: Optional[Mapping[str, Any]] = None) -> Study:
    """Loads and validates a study, as ``hapsyn run FILE --set ...`` does before it runs.

    Args:
        problem: a problem file's path, or the problem as a dict (converted to JSON; NumPy
            values allowed).
        set: overrides ``"path=value"`` applied in order (``"threads=1"``,
            ``"objectives[0].metric=gdi"``; the value is JSON when it parses, else a string).
        plugin_path: directories searched for plugins before the default ones.
        metrics: Python metrics by name for this study only (classes or instances, see
            :func:`register_metric`); they take precedence over registered ones and plugins.

    Raises :class:`Error` with the program's message for any invalid input (malformed JSON, an
    unknown key or plugin, a bad option, bounds, ...). Nothing runs: the scene is built.
    """
    if isinstance(set, str):
        set = [set]  # noqa: A001
    chosen = dict(_registered)
    chosen.update(metrics or {})
    factories = {name: _factory(name, m) for name, m in chosen.items()}
    if isinstance(problem, Mapping):
        handle = _hapsyn.StudyHandle(_to_json(dict(problem)), False, list(set), _paths(plugin_path), factories)
    else:
        handle = _hapsyn.StudyHandle(_os.fspath(problem), True, list(set), _paths(plugin_path), factories)
    return Study(handle)
