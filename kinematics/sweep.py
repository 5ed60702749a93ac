"""Parameter studies: workspace measures against one design parameter (paper Fig. 4) and over a
2-D grid of two parameters (paper Fig. 5).

A study's design is the paper's :class:`~kinematics.design.Design` or a preset's
:class:`~kinematics.presets.PresetDesign` (any mechanism preset: its numeric parameters are the
parameters, :func:`param_range` their valid ranges, its study ranges :func:`study_values`'s, and
each point runs :func:`kinematics.mechanism_workspace.compute_mechanism_workspace`).

The unit of work is :func:`evaluate_design`, a pure module-level function of picklable arguments
(a :class:`~kinematics.design.Design`, a :class:`~kinematics.workspace.WorkspaceSettings`, an
optional :class:`~kinematics.orientation.OrientationSettings`) that returns a JSON-serializable
dict, so it can run on any worker (threads, processes, Dask). :func:`sweep_1d` and
:func:`sweep_2d` call it point by point, with progress, cancellation between and inside points,
and an optional :class:`ResultCache` keyed by a stable hash of (design fields, workspace settings
fields, orientation settings fields, code version).

Note (paper): Sec. III-E is titled "Combined effect of a and l_s" but Fig. 5 and its text vary
``a`` and ``d_s``; :func:`sweep_2d` takes any two parameters.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import hashlib
import json
import os
import pathlib
import tempfile
import threading
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from .bytecache import ByteLRU
from .design import PARAMS, Design, ParameterError
from .orientation import OrientationSettings, orientation_workspace
from .presets import PresetDesign
from .progress import CancelToken, ProgressFn, Reporter, check
from .serialize import jsonable
from .workspace import WorkspaceSettings, compute_workspace

#: Bump when the meaning of a cached result changes without a change of the kinematics sources.
CACHE_SCHEMA = "sweep-2"  # sweep-2: rows carry TI_saturated and saturation_note


# --------------------------------------------------------------------------------------------
# the unit of work


def evaluate_design(design: Design | PresetDesign, settings: WorkspaceSettings, *,
                    orientation: OrientationSettings | None = None, cancel: CancelToken = None,
                    task: Any = None, dexterity: bool = False,
                    total_orientation: tuple[float, float, float] | None = None,
                    measures: Sequence[str] | None = None, length_step: float | None = None) -> dict:
    """Measures of one design: its position workspace and, optionally, its orientation indices.

    Parameters
    ----------
    design : Design or PresetDesign
        The mechanism's dimensions: the paper's :class:`Design`, or a preset's parameters
        (:class:`~kinematics.presets.PresetDesign`: its workspace is
        :func:`kinematics.mechanism_workspace.compute_mechanism_workspace`'s, the paper's engine for
        the paper preset, the general engine otherwise; the orientation indices, the task, the
        dexterity and the total orientation are then refused, naming the argument).
    settings : WorkspaceSettings
        The workspace computation (:func:`compute_workspace` then :func:`measure_workspace`).
    orientation : OrientationSettings, optional
        Also compute the indices TI_1, TI_2 of eq. (28).
    task : kinematics.task.TaskSpec, optional
        Also ``task_fraction``, ``task_margin``, ``contains_task`` and ``task_binding`` of the task.
    dexterity : bool, optional
        Also ``gci``: the mean ``1/kappa`` over the workspace (:mod:`kinematics.dexterity`, resolved
        carriages).
    total_orientation : (tilt, torsion, angle_step), optional
        Also ``total_orientation_volume``: the volume of the total-orientation workspace
        (:mod:`kinematics.dexterous`) on the same grid.
    cancel : threading.Event or callable, optional
        Stops the computation when set.
    measures : sequence of str, optional
        Only these fields of ``WorkspaceMeasures`` (and the size and box fields that are always
        there, :func:`kinematics.measures.measure_fields`), each computed with only the steps it
        needs and equal to the full evaluation's; ``None`` (default): every field.
    length_step : float, optional
        A :class:`PresetDesign`'s sampled prismatic spacing (default 1; only with one).

    Returns
    -------
    dict
        JSON-serializable: every field of ``WorkspaceMeasures.to_dict()`` (or those of ``measures``)
        (``volume``, ``voids``, ``genus``...), ``"design"`` (the design's fields), with ``orientation`` also ``"TI_1"``,
        ``"TI_2"``, ``"orientation_deltas"`` (the 18 Deltas and 9 products, named as in the paper),
        ``"TI_saturated"`` (an angle Delta of TI_1 or TI_2 equals the scan range: the index measures
        the scan, not the mechanism) and ``"saturation_note"`` (which Deltas; '' when none), and
        ``"compute_seconds"`` (wall time of this call; every other entry is deterministic).

    Raises
    ------
    Cancelled
        When ``cancel`` is set.

    Examples
    --------
    >>> import paraspace as ps
    >>> row = ps.evaluate_design(ps.Design(), ps.WorkspaceSettings(voxel=10.0))
    >>> row["volume"], row["voids"], row["design"]["d_s"]
    (5116000.0, 0, 50.0)
    """
    from .measures import measure_fields, measure_workspace  # imported here: a sibling module of the core

    names = _measure_names(measures)
    t0 = time.perf_counter()
    check(cancel)
    if isinstance(design, PresetDesign):
        return _evaluate_preset(design, settings, names, t0, cancel, length_step, orientation=orientation,
                                task=task, dexterity=dexterity, total_orientation=total_orientation)
    if length_step is not None:
        raise ParameterError("length_step", length_step, "only with a preset's design (PresetDesign)")
    result = compute_workspace(design, settings, cancel=cancel)
    check(cancel)
    out: dict[str, Any] = (dict(measure_workspace(result, cancel=cancel).to_dict()) if names is None
                           else dict(measure_fields(result, names, cancel=cancel)))
    if orientation is not None:
        ori = orientation_workspace(design, orientation, cancel=cancel)
        out["TI_1"] = ori.ti1
        out["TI_2"] = ori.ti2
        out["orientation_deltas"] = dict(ori.deltas)
        out["saturation_note"] = ori.saturation_note()
        out["TI_saturated"] = bool(out["saturation_note"])
    if task is not None:  # a kinematics.task.TaskSpec: task_fraction, task_margin, contains_task
        out.update(task.measures(design, cancel=cancel))
    if dexterity:
        from .dexterity import dexterity_field

        out["gci"] = dexterity_field(result, cancel=cancel).summary()["gci"]
    if total_orientation is not None:
        from .dexterous import total_orientation_workspace

        tilt, torsion, step = total_orientation
        out["total_orientation_volume"] = total_orientation_workspace(design, tilt, torsion, step, settings,
                                                                      position=result, cancel=cancel).volume
    out["design"] = design.to_dict()
    out["compute_seconds"] = time.perf_counter() - t0
    return jsonable(out)


def _evaluate_preset(design: PresetDesign, settings: WorkspaceSettings, names: tuple[str, ...] | None, t0: float,
                     cancel: CancelToken, length_step: float | None, **refused: Any) -> dict:
    """:func:`evaluate_design` of a preset's design: the measures of its position workspace."""
    from .measures import measure_fields, measure_workspace
    from .mechanism_workspace import compute_mechanism_workspace

    for name, value in refused.items():
        if value not in (None, False):
            raise ParameterError(name, value if not hasattr(value, "to_dict") else type(value).__name__,
                                 f"none for a preset's design ({design.preset}): only the position workspace's "
                                 "measures")
    result = compute_mechanism_workspace(design.mechanism(), settings, 1.0 if length_step is None else length_step,
                                         cancel=cancel)
    check(cancel)
    out: dict[str, Any] = (dict(measure_workspace(result, cancel=cancel).to_dict()) if names is None
                           else dict(measure_fields(result, names, cancel=cancel)))
    out["engine"] = result.engine
    out["design"] = design.to_dict()
    out["compute_seconds"] = time.perf_counter() - t0
    return jsonable(out)


def _measure_names(measures: Sequence[str] | None) -> tuple[str, ...] | None:
    """``measures`` validated (fields of ``WorkspaceMeasures``), without repeats, sorted; ``None`` stays."""
    if measures is None:
        return None
    from .measures import MEASURE_FIELDS

    if isinstance(measures, str) or not all(isinstance(m, str) for m in measures):
        raise ParameterError("measures", measures, "a sequence of WorkspaceMeasures field names")
    bad = [m for m in measures if m not in MEASURE_FIELDS]
    if bad:
        raise ParameterError("measures", bad[0], "fields of WorkspaceMeasures: " + ", ".join(MEASURE_FIELDS))
    return tuple(sorted(set(measures)))


# --------------------------------------------------------------------------------------------
# cache


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """Version string of the numerical core: a hash of the sources of ``kinematics/*.py`` and
    :data:`CACHE_SCHEMA` (so an on-disk cache never serves results of other code)."""
    h = hashlib.sha256(CACHE_SCHEMA.encode())
    for path in sorted(pathlib.Path(__file__).resolve().parent.glob("*.py")):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return f"{CACHE_SCHEMA}+{h.hexdigest()[:16]}"


def _canon(obj: Any) -> Any:
    """Canonical form for hashing: ints as floats (``2`` and ``2.0`` are the same setting)."""
    if isinstance(obj, dict):
        return {str(k): _canon(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_canon(v) for v in obj]
    if isinstance(obj, bool) or obj is None or isinstance(obj, str):
        return obj
    if isinstance(obj, (int, float, np.integer, np.floating)):
        return float(obj)
    return str(obj)


def cache_key(design: Design | PresetDesign, settings: WorkspaceSettings,
              orientation: OrientationSettings | None = None, version: str | None = None, task: Any = None,
              measures: Sequence[str] | None = None, **extra: Any) -> str:
    """Stable hash (hex sha256) of the design fields, the workspace and orientation settings fields,
    the task (when given), the code version and, when only some measures are asked for
    (``measures``), their names."""
    payload: dict[str, Any] = {
        "design": design.to_dict(),
        "settings": dataclasses.asdict(settings),
        "orientation": None if orientation is None else dataclasses.asdict(orientation),
        "version": code_version() if version is None else version,
    }
    if task is not None:
        payload["task"] = task.to_dict()
    for name, value in sorted(extra.items()):  # further measures asked of evaluate_design (dexterity...)
        if value not in (None, False):
            payload[name] = value
    names = _measure_names(measures)
    if names is not None:
        payload["measures"] = list(names)
    text = json.dumps(_canon(payload), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


class ResultCache:
    """Thread-safe cache of :func:`evaluate_design` results: an in-memory
    :class:`~kinematics.bytecache.ByteLRU` of at most ``max_entries`` entries and ``max_bytes``
    bytes, backed by an optional directory of JSON files (one per key).

    Values are deep-copied in and out, so callers may mutate what they get.
    """

    def __init__(self, max_entries: int = 256, directory: str | os.PathLike | None = None,
                 version: str | None = None, *, max_bytes: int = 64 << 20) -> None:
        if not isinstance(max_entries, int) or isinstance(max_entries, bool) or max_entries < 0:
            raise ParameterError("max_entries", max_entries, "an integer >= 0")
        if not isinstance(max_bytes, int) or isinstance(max_bytes, bool) or max_bytes < 0:
            raise ParameterError("max_bytes", max_bytes, "an integer >= 0")
        self.max_entries = max_entries
        self.directory = None if directory is None else pathlib.Path(directory)
        if self.directory is not None:
            self.directory.mkdir(parents=True, exist_ok=True)
        self.version = version
        self._mem = ByteLRU(max_bytes, max_entries=max_entries)
        self._lock = threading.RLock()
        self.hits = 0
        self.misses = 0

    def key(self, design: Design | PresetDesign, settings: WorkspaceSettings,
            orientation: OrientationSettings | None = None, task: Any = None,
            measures: Sequence[str] | None = None, **extra: Any) -> str:
        """:func:`cache_key` with this cache's version."""
        return cache_key(design, settings, orientation, self.version, task, measures, **extra)

    def _path(self, key: str) -> pathlib.Path | None:
        return None if self.directory is None else self.directory / f"{key}.json"

    def get(self, key: str) -> dict | None:
        """The cached value (a copy), or ``None``."""
        with self._lock:
            hit = self._mem.get(key)
            if hit is not None:
                self.hits += 1
                return copy.deepcopy(hit)
            path = self._path(key)
            if path is not None and path.is_file():
                try:
                    value = json.loads(path.read_text())["value"]
                except (OSError, ValueError, KeyError, TypeError):
                    value = None
                if isinstance(value, dict):
                    self._mem.put(key, value)
                    self.hits += 1
                    return copy.deepcopy(value)
            self.misses += 1
            return None

    def put(self, key: str, value: dict) -> None:
        """Store a copy of ``value`` (JSON-serializable) in memory and, if configured, on disk."""
        value = copy.deepcopy(value)
        with self._lock:
            self._mem.put(key, value)
            path = self._path(key)
            if path is not None:
                fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=".json", dir=str(path.parent))
                try:
                    with os.fdopen(fd, "w") as fh:
                        json.dump({"key": key, "value": value}, fh)
                    os.replace(tmp, path)
                except BaseException:
                    if os.path.exists(tmp):
                        os.unlink(tmp)
                    raise

    def clear(self) -> None:
        """Forget the in-memory entries (the directory is left alone)."""
        with self._lock:
            self._mem.clear()

    def __len__(self) -> int:
        with self._lock:
            return len(self._mem)

    def __contains__(self, key: str) -> bool:
        with self._lock:
            path = self._path(key)
            return key in self._mem or (path is not None and path.is_file())


# --------------------------------------------------------------------------------------------
# sweeps


def _preset_params(design: PresetDesign) -> list[Any]:
    from .presets import PRESETS

    return [q for q in PRESETS[design.preset].params if q.numeric]


def _check_param(param: Any, field: str = "param", design: Design | PresetDesign | None = None) -> str:
    if isinstance(design, PresetDesign):
        names = [q.name for q in _preset_params(design)]
        if not isinstance(param, str) or param not in names:
            raise ParameterError(field, param, f"a parameter of preset {design.preset!r}: {', '.join(names)}")
        return param
    if not isinstance(param, str) or param not in PARAMS:
        raise ParameterError(field, param, "one of " + ", ".join(PARAMS))
    return param


def param_range(design: Design | PresetDesign, param: str, field: str = "param") -> tuple[float, float]:
    """The valid range ``(lo, hi)`` of a study parameter: the paper's model range of a
    :class:`Design` field, or a preset parameter's ``[lo, hi]`` (an unknown name raises
    ParameterError naming ``field``)."""
    _check_param(param, field, design)
    if isinstance(design, PresetDesign):
        q = next(q for q in _preset_params(design) if q.name == param)
        return (q.lo, q.hi)
    return (PARAMS[param].model_min, PARAMS[param].model_max)


def param_value(design: Design | PresetDesign, param: str) -> float:
    """The value of a study parameter in a design."""
    return float(dict(design.values)[param]) if isinstance(design, PresetDesign) else float(getattr(design, param))


def _engine_kw(design: Design | PresetDesign, length_step: float | None) -> dict[str, Any]:
    """``length_step`` for a preset's design (the general engine's); refused for the paper's Design."""
    if isinstance(design, PresetDesign):
        return {"length_step": 1.0 if length_step is None else float(length_step)}
    if length_step is not None:
        raise ParameterError("length_step", length_step, "only with a preset's design (PresetDesign)")
    return {}


def _designs(design: Design | PresetDesign, param: str, values: Sequence[float]) -> list[Any]:
    """Validate every value up front (``Design`` raises ``ParameterError`` naming the field)."""
    try:
        vals = list(values)
    except TypeError:
        raise ParameterError("values", values, "a sequence of numbers") from None
    return [design.replace(**{param: v}) for v in vals]


def _evaluate_cached(design: Design | PresetDesign, settings: WorkspaceSettings,
                     orientation: OrientationSettings | None, cancel: CancelToken, cache: ResultCache | None,
                     task: Any = None, measures: Sequence[str] | None = None, **extra: Any) -> dict:
    key = cache.key(design, settings, orientation, task, measures, **extra) if cache is not None else None
    if cache is not None:
        hit = cache.get(key)  # type: ignore[arg-type]
        if hit is None and measures is not None:
            hit = cache.get(cache.key(design, settings, orientation, task, **extra))  # a full row: every measure
        if hit is not None:
            return hit
    value = evaluate_design(design, settings, orientation=orientation, cancel=cancel, task=task, measures=measures,
                            **extra)
    if cache is not None:
        cache.put(key, value)  # type: ignore[arg-type]
    return value


def sweep_1d(design: Design | PresetDesign, param: str, values: Sequence[float], settings: WorkspaceSettings, *,
             orientation: OrientationSettings | None = None, progress: ProgressFn | None = None,
             cancel: CancelToken = None, cache: ResultCache | None = None, task: Any = None,
             measures: Sequence[str] | None = None, length_step: float | None = None) -> list[dict]:
    """Measures against one design parameter (paper Fig. 4).

    Parameters
    ----------
    design : Design or PresetDesign
        The base design: ``param`` is set to each of ``values``, the other fields stay.
    param : str
        A design field (``"a"``, ``"d_s"``, ... see ``PARAMS``), or a preset design's numeric parameter.
    values : sequence of float
        The values of ``param``.
    settings : WorkspaceSettings
        The workspace computation of each point.
    orientation : OrientationSettings, optional
        Also compute TI_1, TI_2 (eq. (28)) of each point.
    progress : callable, optional
        ``progress(fraction, message)``.
    cancel : threading.Event or callable, optional
        Stops the sweep when set.
    cache : ResultCache, optional
        Points computed before are taken from it.
    task : kinematics.task.TaskSpec, optional
        Also ``task_fraction``, ``task_margin``, ``contains_task`` of each point.
    measures : sequence of str, optional
        Only these measures at each point (:func:`evaluate_design`); default every one.
    length_step : float, optional
        A preset design's sampled prismatic spacing (default 1; only with a ``PresetDesign``).

    Returns
    -------
    list of dict
        One dict per value, ``{"param": param, "value": v, **evaluate_design(...)}``.

    Raises
    ------
    ParameterError
        Unknown ``param`` or a value outside the parameter's valid range (checked for every value
        before any computation).
    Cancelled
        When ``cancel`` is set.

    Examples
    --------
    >>> import paraspace as ps
    >>> rows = ps.sweep_1d(ps.Design(), "d_s", [40.0, 60.0], ps.WorkspaceSettings(voxel=10.0))
    >>> [(row["value"], row["volume"]) for row in rows]
    [(40.0, 3800000.0), (60.0, 6216000.0)]
    """
    _check_param(param, "param", design)
    _measure_names(measures)
    extra = _engine_kw(design, length_step)
    designs = _designs(design, param, values)
    rep = Reporter(progress)
    out: list[dict] = []
    n = len(designs)
    for i, dsg in enumerate(designs):
        check(cancel)
        rep(i / n, f"{param} = {param_value(dsg, param):g} ({i + 1}/{n})")
        res = _evaluate_cached(dsg, settings, orientation, cancel, cache, task, measures, **extra)
        out.append({"param": param, "value": param_value(dsg, param), **res})
    rep(1.0, "done")
    return out


def sweep_2d(design: Design | PresetDesign, param_x: str, values_x: Sequence[float], param_y: str,
             values_y: Sequence[float], settings: WorkspaceSettings, *,
             orientation: OrientationSettings | None = None, progress: ProgressFn | None = None,
             cancel: CancelToken = None, cache: ResultCache | None = None, task: Any = None,
             measures: Sequence[str] | None = None, length_step: float | None = None) -> dict:
    """Measures over the grid ``values_x x values_y`` of two design parameters (paper Fig. 5).

    Parameters
    ----------
    design : Design or PresetDesign
        The base design.
    param_x, param_y : str
        Two different design fields (or a preset design's numeric parameters).
    values_x, values_y : sequence of float
        Their values.
    settings : WorkspaceSettings
        The workspace computation of each point.
    orientation : OrientationSettings, optional
        Also compute TI_1, TI_2 (eq. (28)) of each point.
    progress : callable, optional
        ``progress(fraction, message)``.
    cancel : threading.Event or callable, optional
        Stops the sweep when set.
    cache : ResultCache, optional
        Points computed before are taken from it.
    task : kinematics.task.TaskSpec, optional
        Also ``task_fraction``, ``task_margin``, ``contains_task`` of each point.
    measures : sequence of str, optional
        Only these measures at each point (:func:`evaluate_design`); default every one.
    length_step : float, optional
        A preset design's sampled prismatic spacing (default 1; only with a ``PresetDesign``).

    Returns
    -------
    dict
        ``{"param_x", "param_y", "values_x", "values_y", "volume": [iy][ix], "grids": {measure:
        [iy][ix]} for every numeric scalar measure, "points": [...]}``; the points are in row-major
        order (``iy`` outer) and each is ``{"param_x", "param_y", "x", "y", "ix", "iy",
        **evaluate_design(...)}``.

    Raises
    ------
    ParameterError
        Unknown parameter, ``param_x == param_y``, or an invalid value.
    Cancelled
        When ``cancel`` is set.

    Examples
    --------
    >>> import paraspace as ps
    >>> grid = ps.sweep_2d(ps.Design(), "d_s", [40.0, 60.0], "a", [90.0, 110.0], ps.WorkspaceSettings(voxel=10.0))
    >>> grid["volume"]  # rows: a = 90, 110; columns: d_s = 40, 60
    [[1680000.0, 1880000.0], [1048000.0, 1220000.0]]
    """
    _check_param(param_x, "param_x", design)
    _check_param(param_y, "param_y", design)
    if param_x == param_y:
        raise ParameterError("param_y", param_y, f"a parameter other than param_x={param_x!r}")
    _measure_names(measures)
    extra = _engine_kw(design, length_step)
    xs = [param_value(d, param_x) for d in _designs(design, param_x, values_x)]
    ys = [param_value(d, param_y) for d in _designs(design, param_y, values_y)]
    grid_designs = [[design.replace(**{param_x: x, param_y: y}) for x in xs] for y in ys]
    rep = Reporter(progress)
    n = len(xs) * len(ys)
    points: list[dict] = []
    for iy, row in enumerate(grid_designs):
        for ix, dsg in enumerate(row):
            check(cancel)
            k = iy * len(xs) + ix
            rep(k / max(n, 1), f"{param_x} = {xs[ix]:g}, {param_y} = {ys[iy]:g} ({k + 1}/{n})")
            res = _evaluate_cached(dsg, settings, orientation, cancel, cache, task, measures, **extra)
            points.append({"param_x": param_x, "param_y": param_y, "x": xs[ix], "y": ys[iy],
                           "ix": ix, "iy": iy, **res})
    rep(1.0, "done")
    scalar_names = [k for k, v in (points[0].items() if points else [])
                    if isinstance(v, (int, float)) and not isinstance(v, bool)
                    and k not in ("x", "y", "ix", "iy")]
    grids = {name: [[points[iy * len(xs) + ix].get(name) for ix in range(len(xs))] for iy in range(len(ys))]
             for name in scalar_names}
    return {"param_x": param_x, "param_y": param_y, "values_x": xs, "values_y": ys,
            "volume": grids.get("volume", [[None] * len(xs) for _ in ys]), "grids": grids, "points": points}


def sweep_preset(name: str, param: str, values: Sequence[float], params: dict | None = None,
                 settings: WorkspaceSettings = WorkspaceSettings(), length_step: float = 1.0,
                 progress: ProgressFn | None = None, cancel: CancelToken = None) -> list[dict]:
    """Workspace measures against one parameter of the preset ``name`` (the others from ``params``,
    else the preset's defaults): one row per value with the parameter's value, the engine, voxels,
    volume, compute seconds and every measure of :func:`kinematics.measures.measure_workspace`.
    A thin layer over :func:`kinematics.sweep.sweep_1d` of a :class:`~kinematics.presets.PresetDesign`
    (2-D: :func:`kinematics.sweep.sweep_2d`, Dask: :func:`kinematics.distributed.sweep_grid`, the
    same designs). The paper preset runs the paper's engine (the same numbers as ``sweep_1d``)."""
    design = PresetDesign.of(name, params)
    values = list(values)
    if not 1 <= len(values) <= 1000:
        raise ParameterError("values", f"{len(values)} values", "1 to 1000 values")
    rows = sweep_1d(design, param, values, settings, progress=progress, cancel=cancel, length_step=length_step)
    return [{param: row["value"], **{k: v for k, v in row.items() if k not in ("param", "value", "design")}}
            for row in rows]


def study_values(param: str, n: int = 10, design: Design | PresetDesign | None = None) -> list[float]:
    """``n`` values evenly over the paper's Table I range of ``param`` (``PARAMS[param].slider_*``),
    or over a preset parameter's study range (``PresetParam.study_range``) when ``design`` is a
    :class:`PresetDesign`, both ends included."""
    _check_param(param, "param", design)
    if not isinstance(n, (int, np.integer)) or isinstance(n, bool) or n < 1:
        raise ParameterError("n", n, "an integer >= 1")
    if isinstance(design, PresetDesign):
        lo, hi = next(q.study_range for q in _preset_params(design) if q.name == param)
    else:
        lo, hi = PARAMS[param].slider_min, PARAMS[param].slider_max
    return [float(v) for v in np.linspace(lo, hi, int(n))]
