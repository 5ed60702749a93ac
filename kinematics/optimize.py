r"""Multi-objective optimal design: the Pareto front of workspace measures over design parameters.

The paper's title promises "geometric parameter optimization" but it stops at one-at-a-time sweeps.
:func:`optimize` searches the free design parameters (default ``a, d_s, eta_s, l_s`` over paper
Table I's ranges) for the designs that trade several measures off optimally, with pymoo's
evolutionary algorithms:

* 1 or 2 objectives: NSGA-II (Deb et al. 2002: non-dominated sorting + crowding distance);
* 3 or more objectives: NSGA-III (Deb & Jain 2014) with as many reference directions as the
  population (Riesz s-energy directions, seeded), since crowding distance loses selection pressure
  from 3 objectives on. ``algorithm="nsga2" | "nsga3" | "agemoea"`` overrides the choice.

Definitions (our own, documented here)
--------------------------------------
measure, objective, constraint
    What an objective or a constraint can name, and how each is read and scored:
    :mod:`kinematics.objectives` (the registry :data:`~kinematics.objectives.MEASURES`).
parameter resolution
    Every decision variable is rounded to a multiple of ``step`` (default 0.01, far below any
    voxel edge) and clipped to its bounds before evaluation, so designs print cleanly and a
    design revisited by the search is a cache hit.
front
    The feasible non-dominated set of **every design evaluated so far** (an archive, not only the
    last population), with duplicates in objective space kept once (the first evaluated).
hypervolume per generation
    The hypervolume dominated by the front after each generation, in objective space
    normalised per objective to ``[0, 1]`` by the ideal and nadir points over all generations'
    fronts, with reference point ``1.1`` on every axis (so 1.1^M bounds it). Because the front
    is an archive the series never decreases.

Determinism: pymoo >= 0.6.2 draws from a per-algorithm ``numpy.random.Generator`` seeded by
``seed``; every measure except the wall-clock ``compute_seconds`` is deterministic; so the same
settings and seed give the same front serially and on Dask (whatever order points complete in).

This module is part of the numerical core: no web packages (pymoo and Dask are numerical
libraries, imported lazily).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from .design import PARAMS, Design, ParameterError
from .joints import Joints
from .objectives import MEASURES, Constraint, Objective, parse_constraint, parse_objectives
from .orientation import OrientationSettings
from .presets import PRESETS, PresetDesign
from .progress import Cancelled, CancelToken, ProgressFn, check, is_cancelled
from .serialize import jsonable
from .settings import OPTIMIZE
from .workspace import WorkspaceSettings

__all__ = ["OptimizeSettings", "OptimizeResult", "optimize", "non_dominated", "normalised_hypervolume",
           "evaluate_population", "DEFAULT_PARAMS", "ALGORITHMS"]

#: Free parameters by default (paper Sec. III's four studied parameters).
DEFAULT_PARAMS: tuple[str, ...] = ("a", "d_s", "eta_s", "l_s")
ALGORITHMS: tuple[str, ...] = ("auto", "nsga2", "nsga3", "agemoea")
#: Objective value given to pymoo for a point without a value (it is infeasible anyway).
_PENALTY = 1e30


# ================================================================================================
# settings


@dataclasses.dataclass(frozen=True)
class OptimizeSettings:
    """What to optimise and how (all validated on construction, naming the field).

    Attributes:
        params: free design parameters (default ``a, d_s, eta_s, l_s``).
        bounds: ``{param: (lo, hi)}`` for some of ``params``; the others use paper Table I's range
            (``PARAMS[p].slider_min/max``). ``lo < hi`` within the parameter's model range.
        objectives: tuple of :class:`Objective` (or a string for :func:`parse_objectives`).
        constraints: tuple of :class:`Constraint` (or strings for :func:`parse_constraint`).
        design: the base design; its fields that are not free stay fixed.
        workspace: sampling of each design's workspace (voxel edge ``h``...).
        orientation: sampling of the orientation workspace, used only when a measure needs it
            (TI_1, TI_2); ``None``: ``OrientationSettings()`` with the workspace's joints then.
            Its joints must be the workspace's (one mechanism per run: a TI objective of other
            joints than the volume's would not describe the designs it ranks).
        population: individuals per generation, [4, 1000].
        generations: generations, [1, 1000]; evaluations <= population x generations.
        seed: random seed, [0, 2^32 - 1].
        step: parameter resolution (see module docstring), [1e-6, 10].
        algorithm: ``"auto"`` (NSGA-II up to 2 objectives, NSGA-III from 3), ``"nsga2"``,
            ``"nsga3"`` or ``"agemoea"``.
        task: a :class:`kinematics.task.TaskSpec` for the measures ``task_fraction``,
            ``task_margin`` and the constraint ``contains_task`` (its joints must be the workspace's).
        total_orientation: ``(tilt, torsion, angle_step)`` of ``total_orientation_volume`` (degrees;
            ``None``: the defaults of :data:`kinematics.settings.TOTAL_ORIENTATION`).
        preset: a preset's name (:data:`kinematics.presets.PRESETS`) instead of the paper's
            ``design``: ``params`` are then the preset's numeric parameters, their default bounds
            each parameter's ``PresetParam.study_range`` and their valid range ``[lo, hi]``. The
            ``paper`` preset is the paper's model (``design`` from ``preset_values``, every measure);
            any other preset's designs are :class:`~kinematics.presets.PresetDesign` evaluated by
            the general engine, and the measures that do not exist for it (``Measure.general``,
            another mechanism's parameters) are refused by name, as are ``workspace.joints``.
        preset_values: the preset's fixed parameters (the others take their defaults).
        length_step: a general preset's sampled prismatic spacing
            (:func:`kinematics.mechanism_workspace.check_length_step`).
    """

    params: tuple[str, ...] = DEFAULT_PARAMS
    bounds: Mapping[str, tuple[float, float]] = dataclasses.field(default_factory=dict)
    objectives: Any = ("volume", "-footprint")
    constraints: Any = ()
    design: Design = dataclasses.field(default_factory=Design)
    workspace: WorkspaceSettings = dataclasses.field(default_factory=lambda: WorkspaceSettings(voxel=4.0))
    orientation: OrientationSettings | None = None
    population: int = 16
    generations: int = 12
    seed: int = 1
    step: float = 0.01
    algorithm: str = "auto"
    task: Any = None
    total_orientation: tuple[float, float, float] | None = None
    preset: str | None = None
    preset_values: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    length_step: float = 1.0

    def __post_init__(self) -> None:
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731
        self._check_preset()
        free = self._free_params()
        params = self.params.split(",") if isinstance(self.params, str) else list(self.params)
        params = [p.strip() for p in params if isinstance(p, str) and p.strip()] if all(
            isinstance(p, str) for p in params) else params
        if not params:
            raise ParameterError("params", self.params, "one or more of " + ", ".join(free))
        for p in params:
            if p not in free:
                raise ParameterError("params", p, ("design parameters " if self.preset is None else
                                                   f"numeric parameters of preset {self.preset!r}: ")
                                     + ", ".join(free))
        if len(set(params)) != len(params):
            raise ParameterError("params", self.params, "each parameter at most once")
        set_("params", tuple(params))
        if not isinstance(self.bounds, Mapping):
            raise ParameterError("bounds", self.bounds, "a mapping param -> (lo, hi)")
        bounds: dict[str, tuple[float, float]] = {}
        for name, lohi in self.bounds.items():
            if name not in params:
                raise ParameterError("bounds", name, "bounds of free parameters only (params: "
                                                     + ", ".join(params) + ")")
            vmin, vmax = free[name]
            try:
                lo, hi = (float(lohi[0]), float(lohi[1]))
            except (TypeError, ValueError, IndexError, KeyError):
                raise ParameterError(name, lohi, "a pair lo:hi of numbers") from None
            rng = f"[{vmin:g}, {vmax:g}]"
            for v in (lo, hi):
                if not (math.isfinite(v) and vmin <= v <= vmax):
                    raise ParameterError(name, v, f"bounds within {rng}")
            if not lo < hi:
                raise ParameterError(name, f"{lo:g}:{hi:g}", "lo < hi (to fix a parameter leave it out of params)")
            bounds[name] = (lo, hi)
        set_("bounds", bounds)
        objectives = (parse_objectives(self.objectives) if isinstance(self.objectives, str) or not all(
            isinstance(o, Objective) for o in self.objectives) else tuple(self.objectives))
        if not objectives:
            raise ParameterError("objectives", self.objectives, "one or more measures")
        set_("objectives", objectives)
        cons = self.constraints
        if isinstance(cons, (str, Constraint)):
            cons = [cons]
        cons = tuple(c if isinstance(c, Constraint) else parse_constraint(c) for c in cons)
        set_("constraints", cons)
        if not isinstance(self.design, Design):
            raise ParameterError("design", self.design, "a Design")
        if not isinstance(self.workspace, WorkspaceSettings):
            raise ParameterError("workspace", self.workspace, "WorkspaceSettings")
        if self.orientation is not None and not isinstance(self.orientation, OrientationSettings):
            raise ParameterError("orientation", self.orientation, "OrientationSettings or None")
        if self.orientation is not None and self.orientation.joints != self.workspace.joints:
            raise ParameterError("orientation.joints", self.orientation.joints.to_dict(),
                                 f"the workspace's joints {self.workspace.joints.to_dict()}")
        for name in ("population", "generations", "seed"):
            set_(name, OPTIMIZE[name].check(getattr(self, name)))
        set_("step", float(OPTIMIZE["step"].parse(self.step)))  # a number or its text (the CLI's)
        if self.algorithm not in ALGORITHMS:
            raise ParameterError("algorithm", self.algorithm, " or ".join(ALGORITHMS))
        if self.task is not None:
            from .task import TaskSpec

            if not isinstance(self.task, TaskSpec):
                raise ParameterError("task", self.task, "a TaskSpec")
            if self.task.settings.joints != self.workspace.joints:
                raise ParameterError("task.joints", self.task.settings.joints.to_dict(),
                                     f"the workspace's joints {self.workspace.joints.to_dict()}")
        if self.total_orientation is not None:
            from .dexterous import orientation_samples

            try:
                tilt, torsion, step = (float(v) for v in self.total_orientation)
            except (TypeError, ValueError):
                raise ParameterError("total_orientation", self.total_orientation,
                                     "three numbers tilt, torsion, angle_step (degrees)") from None
            orientation_samples(tilt, torsion, step)  # validates them
            set_("total_orientation", (tilt, torsion, step))
        needs = [o.measure for o in objectives] + [c.measure for c in cons]
        self._check_measures(needs, free)
        if self.task is None and any(MEASURES[n].needs_task for n in needs):
            raise ParameterError("task", None, "a task (--box, --cylinder, --sphere or --points) for "
                                 + ", ".join(n for n in needs if MEASURES[n].needs_task))

    # ----- a preset's design space --------------------------------------------------------------
    def _check_preset(self) -> None:
        """Validate ``preset``, ``preset_values`` and ``length_step``; the paper preset sets ``design``."""
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731
        if not isinstance(self.preset_values, Mapping):
            raise ParameterError("preset_values", self.preset_values, "a mapping parameter -> value")
        if self.preset is None:
            if self.preset_values:
                raise ParameterError("preset_values", dict(self.preset_values), "only with a preset")
            return
        if self.design != Design():
            raise ParameterError("design", self.design.to_dict(), "the default with a preset (set its parameters in "
                                                                  "preset_values)")
        from .mechanism_workspace import check_length_step

        base = PresetDesign.of(self.preset, self.preset_values)  # names the preset, a bad name or value
        set_("preset_values", dict(base.values))
        set_("length_step", check_length_step(self.length_step))
        if self.preset == "paper":
            set_("design", Design(**dict(base.values)))  # type: ignore[arg-type]  # the paper preset's values
        elif isinstance(self.workspace, WorkspaceSettings) and self.workspace.joints != Joints():
            raise ParameterError("workspace.joints", self.workspace.joints.to_dict(),
                                 "none for a general mechanism: its legs carry their own u_cone/s_cone")

    @property
    def general(self) -> bool:
        """Whether the designs are a general preset's (:class:`PresetDesign`, the general engine)."""
        return self.preset is not None and self.preset != "paper"

    def _free_params(self) -> dict[str, tuple[float, float]]:
        """The parameters that may be free, with their valid ranges."""
        if self.preset is None or self.preset == "paper":
            return {p: (spec.model_min, spec.model_max) for p, spec in PARAMS.items()}
        return {q.name: (q.lo, q.hi) for q in PRESETS[self.preset].params if q.numeric}

    def _check_measures(self, names: Sequence[str], free: Mapping[str, Any]) -> None:
        """Refuse, by name, a measure that does not exist for these designs."""
        for name in names:
            m = MEASURES[name]
            field = "objectives" if any(o.measure == name for o in self.objectives) else "constraints"
            mech = "the paper's design" if not self.general else f"preset {self.preset!r}"
            if m.parameter and name not in free:
                raise ParameterError(field, name, f"a parameter of {mech}: {', '.join(free)}")
            if self.general and not m.general:
                raise ParameterError(field, name, f"a measure of a general mechanism (preset {self.preset!r}): "
                                     + ", ".join(k for k, v in MEASURES.items() if v.general and not v.parameter)
                                     + f" or its parameters; {name} exists for the paper's model only")

    @property
    def engine_extra(self) -> dict[str, Any]:
        """Keyword arguments of :func:`kinematics.sweep.evaluate_design` the designs need
        (``length_step`` of a general preset; empty otherwise)."""
        return {"length_step": self.length_step} if self.general else {}

    def design_of(self, values: Mapping[str, Any]) -> Design | PresetDesign:
        """The design of a row's ``design`` dict (a :class:`Design` or a :class:`PresetDesign`)."""
        return PresetDesign.from_dict(values) if self.general else Design.from_dict(dict(values))

    # ----- derived ---------------------------------------------------------------------------
    def bounds_of(self, param: str) -> tuple[float, float]:
        """``(lo, hi)`` of a free parameter (given, else Table I's range, or the preset parameter's
        ``study_range``)."""
        if param in self.bounds:
            return self.bounds[param]
        if self.general:
            return next(q.study_range for q in PRESETS[str(self.preset)].params if q.name == param)
        spec = PARAMS[param]
        return (spec.slider_min, spec.slider_max)

    @property
    def needs_orientation(self) -> bool:
        """Whether some objective or constraint needs the orientation workspace."""
        names = [o.measure for o in self.objectives] + [c.measure for c in self.constraints]
        return any(MEASURES[n].needs_orientation for n in names)

    @property
    def measure_fields(self) -> tuple[str, ...] | None:
        """The ``WorkspaceMeasures`` fields an evaluation computes: those the objectives and
        constraints name (``None``: every field, when a measure does not say what it reads)."""
        out: list[str] = []
        for name in [o.measure for o in self.objectives] + [c.measure for c in self.constraints]:
            got = MEASURES[name].measure_fields()
            if got is None:
                return None
            out.extend(got)
        return tuple(sorted(set(out)))

    @property
    def orientation_used(self) -> OrientationSettings | None:
        """The orientation settings evaluations run with (``None`` when no measure needs them)."""
        if not self.needs_orientation:
            return None
        if self.orientation is not None:
            return self.orientation
        return OrientationSettings(joints=self.workspace.joints)

    @property
    def algorithm_used(self) -> str:
        """The algorithm ``"auto"`` resolves to."""
        if self.algorithm != "auto":
            return self.algorithm
        return "nsga2" if len(self.objectives) <= 2 else "nsga3"

    def design_at(self, x: Sequence[float]) -> Design | PresetDesign:
        """The design of a decision vector: rounded to ``step``, clipped to the bounds.

        Raises:
            ParameterError: the combination is invalid for the model (e.g. ``d_s > r``, ``l_max <= l_min``).
        """
        if self.general:
            return PresetDesign.of(str(self.preset), {**self.preset_values, **self.values_at(x)})
        return self.design.replace(**self.values_at(x))

    def values_at(self, x: Sequence[float]) -> dict[str, float]:
        """``{param: value}`` of a decision vector after rounding to ``step`` and clipping."""
        out: dict[str, float] = {}
        for p, v in zip(self.params, x):
            lo, hi = self.bounds_of(p)
            q = round(round(float(v) / self.step) * self.step, 10)
            out[p] = float(min(hi, max(lo, q)))
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON form (also what :meth:`key` hashes)."""
        return jsonable({
            "params": list(self.params),
            "bounds": {p: list(self.bounds_of(p)) for p in self.params},
            "objectives": [o.label for o in self.objectives],
            "constraints": [c.label for c in self.constraints],
            "design": (PresetDesign.of(str(self.preset), self.preset_values).to_dict() if self.general
                       else self.design.to_dict()),
            "workspace": dataclasses.asdict(self.workspace),
            "orientation": None if self.orientation_used is None else dataclasses.asdict(self.orientation_used),
            "population": self.population, "generations": self.generations, "seed": self.seed,
            "step": self.step, "algorithm": self.algorithm_used,
            "task": None if self.task_used is None else self.task_used.to_dict(),
            **({"extra": self.extra_used} if self.extra_used else {}),
            **({} if self.preset is None else {"mechanism": self.preset, "preset_values": dict(self.preset_values)}),
        })

    @property
    def task_used(self) -> Any:
        """The task evaluations run with (``None`` when no measure needs it)."""
        names = [o.measure for o in self.objectives] + [c.measure for c in self.constraints]
        return self.task if any(MEASURES[n].needs_task for n in names) else None

    @property
    def extra_used(self) -> dict[str, Any]:
        """Further keyword arguments of :func:`kinematics.sweep.evaluate_design` the measures need
        (``dexterity``, ``total_orientation``); empty when none."""
        from .settings import TOTAL_ORIENTATION

        names = [o.measure for o in self.objectives] + [c.measure for c in self.constraints]
        out: dict[str, Any] = dict(self.engine_extra)
        if any(MEASURES[n].needs_dexterity for n in names):
            out["dexterity"] = True
        if any(MEASURES[n].needs_total_orientation for n in names):
            out["total_orientation"] = self.total_orientation or tuple(
                float(TOTAL_ORIENTATION[k].default) for k in ("tilt", "torsion", "angle_step"))
        return out

    def key(self) -> tuple:
        """Hashable identity of the run (equal settings give the same front)."""
        import json

        return ("optimize", json.dumps(self.to_dict(), sort_keys=True))


# ================================================================================================
# evaluation of a population


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    text = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return text if len(text) <= 500 else text[:497] + "..."


def evaluate_population(designs: Sequence[Design | PresetDesign], settings: WorkspaceSettings, *,
                        orientation: OrientationSettings | None = None, cache: Any = None,
                        client: Any = None, evaluate: Callable[..., dict] | None = None, retries: int = 1,
                        cancel: CancelToken = None,
                        on_point: Callable[[int, int], None] | None = None,
                        task: Any = None, extra: Mapping[str, Any] | None = None,
                        measures: Sequence[str] | None = None) -> tuple[list[dict], int]:
    """Evaluate a batch of designs with the sweep unit of work, each distinct design at most once.

    ``measures``: only these fields of ``WorkspaceMeasures`` (:func:`kinematics.sweep.evaluate_design`;
    default every one; not passed to a custom ``evaluate``).

    Cached designs (``cache``: a :class:`~kinematics.sweep.ResultCache`) are taken from the cache;
    the rest run serially in this process (``client=None``; numba's kernels use every core) or on
    the Dask ``client`` (one task per design, ``retries`` retries). Results are put in the cache.

    Returns:
        ``(rows, computed)``: one row per design in input order -- the ``evaluate_design`` dict
        with ``"ok": True``, or ``{"ok": False, "error": "one line", "design": {...}}`` for a
        design whose evaluation raised or whose worker died -- and the number of designs computed
        (not from the cache, not duplicates).
    Raises:
        Cancelled: when ``cancel`` is set (unfinished Dask tasks are cancelled).
    """
    from .sweep import evaluate_design

    more = dict(extra or {})
    keys = [cache.key(d, settings, orientation, task, measures, **more) if cache is not None else None
            for d in designs]
    given: dict[str, Any] = {**more, **({} if task is None else {"task": task})}  # every unit of work takes these
    fields: dict[str, Any] = {} if measures is None else {"measures": tuple(measures)}  # only evaluate_design
    results: dict[int, dict] = {}
    todo: dict[Any, int] = {}  # distinct key -> first index
    dup: dict[int, int] = {}
    for i, d in enumerate(designs):
        k = keys[i] if keys[i] is not None else d.key()
        if k in todo:
            dup[i] = todo[k]
            continue
        hit = cache.get(keys[i]) if cache is not None else None
        if hit is None and cache is not None and measures is not None:
            hit = cache.get(cache.key(d, settings, orientation, task, **more))  # a full row holds every measure
        if hit is not None:
            results[i] = {**hit, "ok": True}
            todo[k] = i
            continue
        todo[k] = i
    run = [i for i in todo.values() if i not in results]
    n_done = 0

    def finished(i: int, row: dict) -> None:
        nonlocal n_done
        results[i] = row
        if row.get("ok") and cache is not None:
            cache.put(keys[i], {k: v for k, v in row.items() if k != "ok"})
        n_done += 1
        if on_point is not None:
            on_point(n_done, len(run))

    if client is None:
        for i in run:
            check(cancel)
            try:
                if evaluate is None:
                    row = evaluate_design(designs[i], settings, orientation=orientation, cancel=cancel, **given,
                                          **fields)
                else:
                    row = evaluate(designs[i], settings, orientation=orientation, **given)
            except Cancelled:
                raise
            except Exception as e:  # noqa: BLE001 - a failed point is reported, not fatal
                finished(i, {"ok": False, "error": _one_line(e), "design": designs[i].to_dict()})
            else:
                finished(i, {**row, "ok": True})
    elif run:
        from distributed import as_completed

        fn = evaluate if evaluate is not None else evaluate_design
        futures = client.map(fn, [designs[i] for i in run], settings=settings, orientation=orientation,
                             retries=retries, pure=False, **given, **(fields if evaluate is None else {}))
        where = {f.key: i for f, i in zip(futures, run)}
        pending = set(where)
        ac = as_completed(futures)
        try:
            while pending:
                if is_cancelled(cancel):
                    raise Cancelled()
                batch = ac.next_batch(block=False) if ac.has_ready() else []
                if not batch:
                    time.sleep(0.01)
                    continue
                for fut in batch:
                    i = where[fut.key]
                    if fut.status in ("lost", "pending"):
                        # its result was computed, then lost with a worker that died: the scheduler
                        # recomputes it elsewhere, so wait for that rather than fail an innocent point
                        ac.add(fut)
                        continue
                    pending.discard(fut.key)
                    if fut.status == "finished":
                        try:
                            row = {**fut.result(), "ok": True}
                        except Exception as e:  # noqa: BLE001 - e.g. data lost with its worker
                            row = {"ok": False, "error": _one_line(e), "design": designs[i].to_dict()}
                    else:
                        try:
                            exc = fut.exception()
                        except Exception as e:  # noqa: BLE001 - cancelled futures raise here
                            exc = e
                        row = {"ok": False, "error": _one_line(exc) if exc else f"point {fut.status}",
                               "design": designs[i].to_dict()}
                    fut.release()
                    finished(i, row)
        finally:
            if pending:
                client.cancel([f for f in futures if f.key in pending])
    for i, j in dup.items():
        results[i] = results[j]
    return [results[i] for i in range(len(designs))], len(run)


# ================================================================================================
# fronts and hypervolume


def non_dominated(F: np.ndarray) -> np.ndarray:
    """Indices of the non-dominated rows of ``F`` (all objectives minimised; a row is dominated
    when another is ``<=`` everywhere and ``<`` somewhere). Rows equal to an earlier row are
    dropped (the first one is kept). Brute force, ``O(n^2 M)``."""
    F = np.asarray(F, dtype=float)
    n = len(F)
    keep = []
    for i in range(n):
        le = np.all(F <= F[i], axis=1)
        lt = np.any(F < F[i], axis=1)
        if np.any(le & lt):
            continue
        if np.any(np.all(F[:i] == F[i], axis=1)):
            continue
        keep.append(i)
    return np.asarray(keep, dtype=int)


def normalised_hypervolume(fronts: Sequence[np.ndarray], reference: float = 1.1) -> tuple[list[float], dict]:
    """Hypervolume of each front (minimised objectives) after normalising every objective to
    ``[0, 1]`` by the ideal and nadir points over all fronts, reference point ``reference`` on
    every axis (see module docstring). Uses pymoo's exact ``HV`` indicator.

    Returns:
        ``(values, {"ideal": [...], "nadir": [...], "reference": reference})``; the ideal and
        nadir are in the minimised objective space.
    """
    from pymoo.indicators.hv import HV

    nonempty = [np.asarray(f, dtype=float) for f in fronts if len(f)]
    if not nonempty:
        return [0.0 for _ in fronts], {"ideal": None, "nadir": None, "reference": reference}
    allf = np.vstack(nonempty)
    ideal, nadir = allf.min(axis=0), allf.max(axis=0)
    scale = np.where(nadir > ideal, nadir - ideal, 1.0)
    ind = HV(ref_point=np.full(allf.shape[1], reference))
    out = []
    for f in fronts:
        if not len(f):
            out.append(0.0)
            continue
        out.append(float(ind((np.asarray(f, dtype=float) - ideal) / scale)))
    return out, {"ideal": ideal.tolist(), "nadir": nadir.tolist(), "reference": reference}


# ================================================================================================
# the optimisation


@dataclasses.dataclass
class OptimizeResult:
    """The outcome of :func:`optimize` (see :meth:`to_dict` for the JSON form)."""

    settings: OptimizeSettings
    front: list[dict]
    hypervolume: list[float]
    hypervolume_normalisation: dict
    generations: list[dict]
    evaluations: int
    computed: int
    failed: list[dict]
    seconds: float
    backend: str

    def to_dict(self) -> dict[str, Any]:
        """``{"front": [{"design", "measures"}...], "hypervolume": [per generation], "settings",
        "generations", "evaluations", "computed", "failed", "seconds", "backend", ...}``."""
        return jsonable({
            "front": self.front, "hypervolume": self.hypervolume,
            "hypervolume_normalisation": self.hypervolume_normalisation,
            "settings": self.settings.to_dict(), "generations": self.generations,
            "evaluations": self.evaluations, "computed": self.computed, "failed": self.failed,
            "seconds": self.seconds, "backend": self.backend,
        })


def measures_of(row: Mapping[str, Any]) -> dict[str, Any]:
    """Every scalar measure of an evaluated row plus every registered derived measure (the
    ``"measures"`` of a front entry); the wall-clock ``compute_seconds`` is left out."""
    out: dict[str, Any] = {}
    for k, v in row.items():
        if k in ("compute_seconds", "ok", "design"):
            continue
        if isinstance(v, (bool, int, float, str)) or v is None:
            out[k] = v
    for name, m in MEASURES.items():
        if name not in out and (m.derive is not None or (m.key or name) in row):
            try:
                val = m.value(row)
            except (KeyError, TypeError, ValueError):
                val = None
            if val is not None:
                out[name] = bool(val) if m.flag else val
    return out


def _algorithm(settings: OptimizeSettings) -> Any:
    n_obj = len(settings.objectives)
    name = settings.algorithm_used
    pop = settings.population
    if name == "nsga2":
        from pymoo.algorithms.moo.nsga2 import NSGA2

        return NSGA2(pop_size=pop, eliminate_duplicates=True)
    if name == "agemoea":
        from pymoo.algorithms.moo.age import AGEMOEA

        return AGEMOEA(pop_size=pop, eliminate_duplicates=True)
    from pymoo.algorithms.moo.nsga3 import NSGA3
    from pymoo.util.ref_dirs import get_reference_directions

    if n_obj == 1:
        ref_dirs = np.ones((1, 1))
    else:
        ref_dirs = get_reference_directions("energy", n_obj, pop, seed=settings.seed)
    return NSGA3(ref_dirs=ref_dirs, pop_size=pop, eliminate_duplicates=True)


def optimize(settings: OptimizeSettings, *, scheduler: str | None = None, workers: int | None = None,
             client: Any = None, cache: Any = None, progress: ProgressFn | None = None,
             cancel: CancelToken = None, on_generation: Callable[[dict], None] | None = None,
             evaluate: Callable[..., dict] | None = None, retries: int = 1,
             connect_timeout: float = 10.0) -> OptimizeResult:
    """Pareto front of ``settings.objectives`` over ``settings.params`` (see module docstring).

    Args:
        settings: what to optimise.
        scheduler: address of a running Dask scheduler (``tcp://host:8786``); each generation's
            population runs there, one task per design.
        workers: run on a local Dask cluster of this many single-threaded process workers,
            started by the first run that asks for it and kept warm for later runs in this
            process (``None`` and no scheduler: evaluate in this process, whose compiled kernels
            already use every core; :func:`kinematics.distributed.default_workers` is the
            command line's default).
        client: an existing ``distributed.Client`` to use (instead of ``scheduler``/``workers``).
        cache: a :class:`~kinematics.sweep.ResultCache` shared with sweeps (default: a fresh
            in-memory one for this run).
        progress: ``progress(fraction, message)`` after each evaluated point and generation; the
            message names the generation, the evaluations and the best value of each objective.
        cancel: stop (raises :class:`~kinematics.progress.Cancelled`).
        on_generation: called after each generation with ``{"generation", "evaluations",
            "computed", "front_size", "best", "front"}`` (``front`` as in the result).
        evaluate: the unit of work (default :func:`kinematics.sweep.evaluate_design`).
        retries: Dask retries of a failing point.
        connect_timeout: seconds to reach ``scheduler``.

    Raises:
        ParameterError: bad settings, ``workers`` together with ``scheduler``, or an unreachable
            scheduler.
        Cancelled: when ``cancel`` is set.
    """
    from pymoo.core.evaluator import Evaluator
    from pymoo.core.problem import Problem
    from pymoo.problems.static import StaticProblem
    from pymoo.termination import get_termination

    from .sweep import ResultCache

    if not isinstance(settings, OptimizeSettings):
        raise ParameterError("settings", settings, "OptimizeSettings")
    if scheduler is not None and workers is not None:
        raise ParameterError("workers", workers, "omit it with a scheduler address (the scheduler's workers are used)")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= 256):
        raise ParameterError("workers", workers, "an integer in [1, 256]")
    if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
        raise ParameterError("scheduler", scheduler, "an address such as tcp://host:8786")
    if not isinstance(retries, int) or isinstance(retries, bool) or retries < 0:
        raise ParameterError("retries", retries, "an integer >= 0")
    if cache is None:
        cache = ResultCache(max_entries=max(256, settings.population * settings.generations))
    check(cancel)
    t0 = time.perf_counter()
    ori = settings.orientation_used
    objs, cons = settings.objectives, settings.constraints
    fields = settings.measure_fields if evaluate is None else None
    lows = np.array([settings.bounds_of(p)[0] for p in settings.params])
    highs = np.array([settings.bounds_of(p)[1] for p in settings.params])
    problem = Problem(n_var=len(settings.params), n_obj=len(objs), n_ieq_constr=1 + len(cons), xl=lows, xu=highs)
    algorithm = _algorithm(settings)
    algorithm.setup(problem, termination=get_termination("n_gen", settings.generations), seed=settings.seed,
                    verbose=False)

    own_client = None
    backend = "serial"
    if client is None and (scheduler is not None or workers is not None):
        from .distributed import shared_client

        # the process's warm client: kept (with its warmed workers) for later runs, closed at exit
        own_client = client = shared_client(scheduler, workers, connect_timeout=connect_timeout)
    if client is not None:
        backend = "dask " + (scheduler if scheduler is not None else f"local cluster ({workers or 'default'} workers)"
                             if own_client is not None else "client")

    archive_F: list[np.ndarray] = []
    archive_rows: list[dict] = []
    fronts: list[np.ndarray] = []
    history: list[dict] = []
    failed: list[dict] = []
    evaluations = computed = 0
    G = settings.generations
    front_idx = np.zeros(0, dtype=int)

    def report(fraction: float, message: str) -> None:
        if progress is not None:
            progress(min(1.0, max(0.0, fraction)), message)

    def best_text(best: dict) -> str:
        return ", ".join(f"{k.lstrip('-')} {v:.4g} ({'min' if k.startswith('-') else 'max'})"
                         for k, v in best.items() if v is not None)

    try:
        report(0.0, f"generation 1/{G}: evaluating {settings.population} designs ({backend})")
        gen = 0
        while algorithm.has_next():
            check(cancel)
            gen += 1
            pop = algorithm.ask()
            X = pop.get("X")
            designs: list[Design | PresetDesign | None] = []
            rows: list[dict | None] = []
            for x in X:
                try:
                    designs.append(settings.design_at(x))
                    rows.append(None)
                except ParameterError as e:
                    designs.append(None)
                    rows.append({"ok": False, "error": _one_line(e), "design": settings.values_at(x)})
            valid = [i for i, d in enumerate(designs) if d is not None]

            def on_point(done: int, total: int, gen: int = gen) -> None:
                report((gen - 1 + done / max(total, 1)) / G, f"generation {gen}/{G}: {done}/{total} designs")

            got, n_run = evaluate_population([d for d in designs if d is not None], settings.workspace,
                                             orientation=ori, cache=cache, client=client, evaluate=evaluate,
                                             retries=retries, cancel=cancel, on_point=on_point,
                                             task=settings.task_used, extra=settings.extra_used, measures=fields)
            for i, row in zip(valid, got):
                rows[i] = row
            computed += n_run
            evaluations += len(rows)
            F = np.full((len(rows), len(objs)), _PENALTY)
            Gv = np.zeros((len(rows), 1 + len(cons)))
            for i, maybe_row in enumerate(rows):
                assert maybe_row is not None
                row = maybe_row
                if not row.get("ok"):
                    Gv[i, :] = 1.0
                    failed.append({"generation": gen, "design": row.get("design"), "error": row.get("error")})
                    continue
                vals = [MEASURES[o.measure].value(row) for o in objs]
                if any(v is None for v in vals):
                    Gv[i, 0] = 1.0
                    failed.append({"generation": gen, "design": row.get("design"),
                                   "error": "missing measure: " + ", ".join(o.measure for o, v in zip(objs, vals)
                                                                          if v is None)})
                else:
                    F[i] = [o.to_minimise(float(v)) for o, v in zip(objs, vals)]  # type: ignore[arg-type]
                Gv[i, 1:] = [c.violation(MEASURES[c.measure].value(row)) for c in cons]
                if np.all(Gv[i] <= 0.0):
                    archive_F.append(F[i].copy())
                    archive_rows.append(row)
            Evaluator().eval(StaticProblem(problem, F=F, G=Gv), pop)
            algorithm.tell(infills=pop)
            AF = np.array(archive_F) if archive_F else np.zeros((0, len(objs)))
            front_idx = non_dominated(AF) if len(AF) else np.zeros(0, dtype=int)
            fronts.append(AF[front_idx] if len(front_idx) else np.zeros((0, len(objs))))
            best = {o.label: (None if not len(AF) else float(o.to_minimise(AF[:, k].min())))
                    for k, o in enumerate(objs)}
            info = {"generation": gen, "evaluations": evaluations, "computed": computed,
                    "front_size": int(len(front_idx)), "best": best}
            history.append(info)
            report(gen / G,
                   f"generation {gen}/{G}, {evaluations} evaluations, best: {best_text(best) or 'none feasible'}")
            if on_generation is not None:
                on_generation({**info, "front": _front_entries(archive_rows, AF, front_idx)})
        if fields is not None and len(front_idx):
            # the front's designs with every measure (the evaluations computed only the named ones)
            front_rows = [archive_rows[i] for i in front_idx]
            full, n_full = evaluate_population([settings.design_of(r["design"]) for r in front_rows],
                                               settings.workspace, orientation=ori, cache=cache, client=client,
                                               retries=retries, cancel=cancel, extra=settings.engine_extra)
            for i, row in zip(front_idx, full):
                if row.get("ok"):
                    archive_rows[i] = row
            computed += n_full
    except BaseException:
        if own_client is not None and own_client.status != "running":
            from .distributed import discard_client

            discard_client(own_client)
        raise
    AF = np.array(archive_F) if archive_F else np.zeros((0, len(objs)))
    hv, norm = normalised_hypervolume(fronts)
    norm = {**norm, "objectives": [o.label for o in objs],
            "note": "objectives minimised (maximised ones negated), normalised by ideal/nadir over all fronts"}
    return OptimizeResult(settings=settings, front=_front_entries(archive_rows, AF, front_idx), hypervolume=hv,
                          hypervolume_normalisation=norm, generations=history, evaluations=evaluations,
                          computed=computed, failed=failed, seconds=time.perf_counter() - t0, backend=backend)


def _front_entries(rows: list[dict], F: np.ndarray, idx: np.ndarray) -> list[dict]:
    """Front entries ``{"design", "measures"}`` sorted by the first objective (best first)."""
    order = sorted((int(i) for i in idx), key=lambda i: tuple(F[i]))
    return [{"design": dict(rows[i]["design"]), "measures": measures_of(rows[i])} for i in order]
