r"""What the optimiser and the studies can aim at: the registry of measures, objectives and constraints.

Definitions
-----------
measure
    A number of one evaluated design, taken from the row of the sweep unit of work
    :func:`kinematics.sweep.evaluate_design` (so every design is computed once and cached in a
    :class:`~kinematics.sweep.ResultCache`) or derived from the design; the registry
    :data:`MEASURES` lists them. A new measure (e.g. the GCI when the engine reports it) is one
    :func:`register_measure` call.
objective
    ``"name"`` maximises the measure, ``"-name"`` minimises it. Internally every objective is
    minimised: ``f = -value`` for a maximised one, ``f = value`` otherwise.
constraint
    ``"flag"`` (a boolean measure such as ``boundary_complete`` must be true) or
    ``"name>=bound"`` / ``"name<=bound"``. The violation passed to pymoo (feasible when ``<= 0``)
    is ``0/1`` for a flag and ``(bound - value) / max(|bound|, 1)`` (resp. ``(value - bound) /
    max(|bound|, 1)``) otherwise. Every run has one more constraint, ``evaluated``: a design the
    model rejects (e.g. ``d_s > r``) or whose evaluation failed (an exception, a dead Dask worker)
    gets violation 1, so it is infeasible -- a lost point costs that point, never the run -- and
    is listed in ``failed``.

The registry holds the workspace measures of :mod:`kinematics.measures`, the orientation, task,
dexterity and total-orientation measures (each needs its evaluation: ``needs_orientation``,
``needs_task``...), two derived sizes (``footprint``, ``l_max``), and every numeric design or
preset parameter (size objectives: minimise ``l_s``, ``base_radius``...).
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from .design import PARAMS, ParameterError
from .presets import PRESETS

__all__ = ["Measure", "MEASURES", "register_measure", "Objective", "Constraint", "parse_objectives",
           "parse_constraint"]


# ================================================================================================
# the measure registry


@dataclasses.dataclass(frozen=True)
class Measure:
    """One measure an objective or a constraint can name.

    Attributes:
        name: the name users write (``volume``, ``TI_1``, ``footprint``...).
        description: one line, with the definition or the module that defines it.
        key: the entry of :func:`kinematics.sweep.evaluate_design`'s row holding the value.
        derive: instead of ``key``: ``f(row) -> value`` (the row holds ``"design"``).
        flag: a boolean measure (usable as a constraint only).
        needs_orientation: the row must be evaluated with orientation settings (TI_1, TI_2).
        needs_task: the row must be evaluated with a task (``OptimizeSettings.task``).
        needs_dexterity: the row must be evaluated with the dexterity field (``gci``).
        needs_total_orientation: the row must be evaluated with the total-orientation workspace
            (``OptimizeSettings.total_orientation``).
        fields: the fields of ``WorkspaceMeasures`` the value is made of (an evaluation computes
            only those its objectives and constraints name); ``None``: ``key`` (or ``name``) when
            that is such a field and there is no ``derive``, none for an orientation measure, else
            every field (a derived measure that says nothing may read anything).
        general: it exists for a general mechanism's design (a preset's
            :class:`~kinematics.presets.PresetDesign`: the position workspace's measures and the
            preset's parameters); ``False`` for the paper model's own (TI, task, gci, footprint...).
        parameter: the value is a design parameter (``row["design"][name]``): it exists for the
            designs that have that parameter.
    """

    name: str
    description: str
    key: str | None = None
    derive: Callable[[dict], Any] | None = None
    flag: bool = False
    needs_orientation: bool = False
    needs_task: bool = False
    needs_dexterity: bool = False
    needs_total_orientation: bool = False
    fields: tuple[str, ...] | None = None
    general: bool = True
    parameter: bool = False

    def measure_fields(self) -> tuple[str, ...] | None:
        """The ``WorkspaceMeasures`` fields this measure needs (``None``: all of them)."""
        from .measures import MEASURE_FIELDS

        if self.fields is not None:
            return self.fields
        if self.needs_orientation or self.needs_task or self.needs_dexterity or self.needs_total_orientation:
            return ()  # its value comes from the row's own step (orientation maps, task, ...), not the measures
        own = self.key or self.name
        return (own,) if self.derive is None and own in MEASURE_FIELDS else None

    def value(self, row: Mapping[str, Any]) -> float | None:
        """The measure of an evaluated row (``None`` when the row lacks it or it is not finite)."""
        raw = self.derive(dict(row)) if self.derive is not None else row.get(self.key or self.name)
        if raw is None:
            return None
        if self.flag:
            return 1.0 if bool(raw) else 0.0
        try:
            v = float(raw)
        except (TypeError, ValueError):
            return None
        return v if math.isfinite(v) else None


MEASURES: dict[str, Measure] = {}


def register_measure(measure: Measure) -> Measure:
    """Add (or replace) a measure of the registry; returns it."""
    MEASURES[measure.name] = measure
    return measure


def _footprint(row: dict) -> float:
    d = row["design"]
    return float(d["r"]) + float(d["l_min"]) + float(d["l_s"])


def _l_max(row: dict) -> float:
    d = row["design"]
    if "l_max" in d:  # a preset's own parameter (gough-stewart, 6-pups)
        return float(d["l_max"])
    if "leg_length" in d:  # fixed-length legs (6-pss)
        return float(d["leg_length"])
    return float(d["l_min"]) + float(d["l_s"])


def _extent(axis: int) -> Callable[[dict], float | None]:
    def f(row: dict) -> float | None:
        ext = row.get("extents")
        return None if not ext else float(ext[axis])
    return f


for _m in (
    Measure("volume", "workspace volume V = N h^3 (kinematics.measures)"),
    Measure("hollowness", "underside cavity ratio H / (H + V) (kinematics.measures, 'hull')"),
    Measure("void_ratio", "enclosed void volume / (V + void volume) (kinematics.measures)"),
    Measure("void_volume", "volume of the enclosed voids (kinematics.measures)"),
    Measure("solidity", "V / convex hull volume (kinematics.measures)"),
    Measure("hull_volume", "volume of the convex hull of the reachable voxels (kinematics.measures)"),
    Measure("components", "number of connected components of the workspace"),
    Measure("voids", "number of enclosed voids"),
    Measure("genus", "total genus of the outer boundary (kinematics.measures)"),
    Measure("largest_component_fraction", "volume fraction of the largest connected component"),
    Measure("box_contact_fraction", "fraction of the grid box's face voxels that are reachable"),
    Measure("height", "z extent of the workspace's bounding box", derive=_extent(2), fields=("extents",)),
    Measure("width", "x extent of the workspace's bounding box", derive=_extent(0), fields=("extents",)),
    Measure("TI_1", "tilt index TI_1 of eq. (28) (kinematics.orientation)", needs_orientation=True,
            general=False),
    Measure("TI_2", "tilt index TI_2 of eq. (28) (kinematics.orientation)", needs_orientation=True,
            general=False),
    Measure("footprint", "r + l_min + l_s: base radius plus the longest leg (our size proxy)",
            derive=_footprint, fields=(), general=False),
    Measure("l_max", "longest leg: l_min + l_s (paper), a preset's l_max, or 6-pss's leg_length", derive=_l_max,
            fields=()),
    Measure("boundary_complete", "the workspace boundary is complete (kinematics.measures)", flag=True),
    Measure("boundary_closed", "the workspace boundary is closed (kinematics.measures)", flag=True),
    Measure("pieces", "components holding >= 1 % of the volume (kinematics.measures, stable in h)"),
    Measure("fragment_volume_fraction", "volume fraction of the components below 1 % (kinematics.measures)"),
    Measure("stable_genus", "genus of the open-close filtered solid (kinematics.measures, stable in h)"),
    Measure("boundary_closed_stable", "one piece, not cut by the box (kinematics.measures, stable in h)",
            flag=True),
    Measure("task_fraction", "share of the task reachable (kinematics.task: volume of a region, poses of a list)",
            needs_task=True, general=False),
    Measure("task_margin", "how far the task region could grow (< 0: must shrink), or a pose list's smallest leg "
            "slack (kinematics.task)", needs_task=True, general=False),
    Measure("contains_task", "the task is reachable everywhere (kinematics.task)", flag=True, needs_task=True,
            general=False),
    Measure("gci", "global conditioning index: mean 1/kappa over the workspace (kinematics.dexterity)",
            needs_dexterity=True, general=False),
    Measure("total_orientation_volume", "volume of the total-orientation workspace (kinematics.dexterous; "
            "OptimizeSettings.total_orientation)", needs_total_orientation=True, general=False),
):
    register_measure(_m)


def _param(name: str) -> Callable[[dict], float]:
    def f(row: dict) -> float:
        return float(row["design"][name])
    return f


for _p in PARAMS:  # the design's own sizes, for size objectives (minimise l_s, d_s, eta_s, r...)
    if _p not in MEASURES:
        register_measure(Measure(_p, f"the design parameter {_p} ({PARAMS[_p].description})", derive=_param(_p),
                                 fields=(), parameter=True))
for _spec in PRESETS.values():  # the presets' numeric parameters (minimise lift, base_radius...)
    for _q in _spec.params:
        if _q.numeric and _q.name not in MEASURES:
            register_measure(Measure(_q.name, f"the preset parameter {_q.name} ({_q.description})",
                                     derive=_param(_q.name), fields=(), parameter=True))


def _measure(name: str, field: str) -> Measure:
    if name not in MEASURES:
        raise ParameterError(field, name, "one of " + ", ".join(MEASURES))
    return MEASURES[name]


# ================================================================================================
# objectives and constraints


@dataclasses.dataclass(frozen=True)
class Objective:
    """A measure to maximise (default) or minimise (written with a leading ``-``)."""

    measure: str
    minimize: bool = False

    @property
    def label(self) -> str:
        """The user's spelling: ``"volume"`` or ``"-footprint"``."""
        return ("-" if self.minimize else "") + self.measure

    def to_minimise(self, value: float) -> float:
        """The value pymoo minimises: ``value`` or ``-value``."""
        return value if self.minimize else -value


def parse_objectives(spec: str | Sequence[str], field: str = "objectives") -> tuple[Objective, ...]:
    """``"volume,TI_1,-footprint"`` (or a list of such words) -> objectives; a leading ``-``
    minimises.

    Raises:
        ParameterError: empty, unknown, a flag measure, or a measure named twice.
    """
    words = [w.strip() for w in (spec.split(",") if isinstance(spec, str) else list(spec))]
    words = [w for w in words if w]
    if not words:
        raise ParameterError(field, spec, "one or more measures, comma-separated, e.g. volume,-footprint")
    out: list[Objective] = []
    for w in words:
        if not isinstance(w, str):
            raise ParameterError(field, w, "measure names")
        name, minimize = (w[1:].strip(), True) if w.startswith("-") else (w.lstrip("+").strip(), False)
        m = _measure(name, field)
        if m.flag:
            raise ParameterError(field, w, "a numeric measure (flags such as boundary_complete are constraints)")
        if any(o.measure == name for o in out):
            raise ParameterError(field, w, "each measure at most once")
        out.append(Objective(name, minimize))
    return tuple(out)


_CONSTRAINT_RE = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(>=|<=)\s*(\S+)\s*$")


@dataclasses.dataclass(frozen=True)
class Constraint:
    """``flag`` true, or ``measure >= bound`` / ``measure <= bound``."""

    measure: str
    op: str = "true"
    bound: float | None = None

    @property
    def label(self) -> str:
        return self.measure if self.op == "true" else f"{self.measure}{self.op}{self.bound:g}"

    def violation(self, value: float | None) -> float:
        """pymoo's inequality value (feasible when ``<= 0``); 1 for a missing value."""
        if value is None:
            return 1.0
        if self.op == "true":
            return 0.0 if value >= 0.5 else 1.0
        scale = max(abs(float(self.bound)), 1.0)  # type: ignore[arg-type]
        if self.op == ">=":
            return (float(self.bound) - value) / scale  # type: ignore[arg-type]
        return (value - float(self.bound)) / scale  # type: ignore[arg-type]


def parse_constraint(text: str, field: str = "constraint") -> Constraint:
    """``"boundary_complete"``, ``"volume>=2e6"``, ``"hollowness<=0.3"`` -> a :class:`Constraint`.

    Raises:
        ParameterError: unknown measure, a flag compared with a number, or a numeric measure
            without a bound.
    """
    if not isinstance(text, str) or not text.strip():
        raise ParameterError(field, text, "a flag such as boundary_complete, or MEASURE>=NUMBER / MEASURE<=NUMBER")
    m = _CONSTRAINT_RE.match(text)
    if m is None:
        m_ = _measure(text.strip(), field)
        if not m_.flag:
            raise ParameterError(field, text, f"a bound, e.g. {m_.name}>=NUMBER or {m_.name}<=NUMBER "
                                              f"(only flags stand alone: "
                                              f"{', '.join(k for k, v in MEASURES.items() if v.flag)})")
        return Constraint(m_.name)
    name, op, num = m.groups()
    m_ = _measure(name, field)
    if m_.flag:
        raise ParameterError(field, text, f"{name} alone (it is a flag)")
    try:
        bound = float(num)
    except ValueError:
        raise ParameterError(field, text, f"{name}{op}NUMBER") from None
    if not math.isfinite(bound):
        raise ParameterError(field, text, "a finite bound")
    return Constraint(name, op, bound)
