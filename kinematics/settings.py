"""Settings tables: one rule per numeric setting, read by every entry point.

A :class:`Setting` is a named number ``v`` with a default, a unit, a one-line label and a range::

    valid(v)  <=>  v is a finite number  and  lo <= v <= hi      (lo < v <= hi when lo_open;
                                                                   v an integer when integer)

Each settings object has one table (a dict name -> Setting) here: :data:`WORKSPACE` for
:class:`~kinematics.workspace.WorkspaceSettings`, :data:`ORIENTATION` for
:class:`~kinematics.orientation.OrientationSettings`, :data:`OPTIMIZE` for
:class:`~kinematics.optimize.OptimizeSettings`, :data:`TOTAL_ORIENTATION` for the total-orientation
workspace (:func:`~kinematics.dexterous.total_orientation_workspace`) and :data:`TILT_TORSION` for
:class:`~kinematics.tilt_torsion.TiltTorsionSettings` and :data:`TASK` for
:class:`~kinematics.task.TaskSettings` (a task's sampling and its region's numbers) and :data:`DEXTERITY` for
the dexterity field (:func:`~kinematics.dexterity.dexterity_field`). The core's
validation, the URL parser's ranges,
the REST models' bounds (and the OpenAPI document's), the CLI flags' messages and the explorer's
slider specs are all derived from these entries, so a bound is written once and the message
(:meth:`Setting.range_text`) is the same everywhere. The design parameters' table is
:data:`kinematics.design.PARAMS`; the joint options' is :data:`kinematics.joints.JOINT_RANGES`.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from typing import Any

from .design import ParameterError


@dataclasses.dataclass(frozen=True)
class Setting:
    """One numeric setting: its range, default, unit, label and (optionally) the explorer's slider.

    ``slider`` is ``(lo, hi, step)`` of the slider (a practical sub-range; the number box beside it
    takes any valid value), or ``None`` where the explorer has no slider for the setting.
    """

    name: str
    default: float
    lo: float
    hi: float
    label: str
    unit: str = ""
    lo_open: bool = False
    integer: bool = False
    slider: tuple[float, float, float] | None = None

    def range_text(self, with_unit: bool = True) -> str:
        """``"[lo, hi]"`` (``"(lo, hi]"`` when open at ``lo``), plus the unit: the one message text."""
        lo, hi = (f"{int(self.lo)}", f"{int(self.hi)}") if self.integer else (f"{self.lo:g}", f"{self.hi:g}")
        text = f"{'(' if self.lo_open else '['}{lo}, {hi}]"
        return f"{text} {self.unit}" if (with_unit and self.unit) else text

    def contains(self, value: float) -> bool:
        """Whether ``value`` (a finite float) lies in the range."""
        return (value > self.lo if self.lo_open else value >= self.lo) and value <= self.hi

    def check(self, value: Any) -> float | int:
        """``value`` validated (a number of the right kind inside the range), else ParameterError
        naming the setting and its range. Strings are not numbers here (see :meth:`parse`)."""
        if self.integer:
            ok = (isinstance(value, numbers.Integral) and not isinstance(value, bool)
                  and self.contains(float(value)))
            if not ok:
                raise ParameterError(self.name, value, self.range_text() + " (an integer)")
            return int(value)
        ok = isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)
        if not ok or not self.contains(float(value)):
            raise ParameterError(self.name, value, self.range_text())
        return float(value)

    def parse(self, raw: Any) -> float | int:
        """A command-line or form text read as this setting's number, then :meth:`check`-ed."""
        try:
            v: float | int = int(str(raw).strip()) if self.integer else float(raw)
        except (TypeError, ValueError):
            kind = "an integer" if self.integer else "a number"
            raise ParameterError(self.name, raw, f"{self.range_text()} ({kind})") from None
        return self.check(v)


def _table(*settings: Setting) -> dict[str, Setting]:
    return {s.name: s for s in settings}


#: :class:`~kinematics.workspace.WorkspaceSettings`'s numbers.
WORKSPACE: dict[str, Setting] = _table(
    Setting("voxel", 2.0, 0.25, 100.0, "voxel edge h", slider=(1.0, 10.0, 0.5)),
    Setting("eta_step", 0.5, 0.01, 10.0, "arc-stroke sample spacing", "degrees"),
    Setting("z_floor", 0.0, -1e4, 1e4, "lowest platform height of derived bounds"),
    Setting("bracket_refine", 2, 0, 3, "halvings of the bracket's boundary cubes", integer=True),
)

#: :class:`~kinematics.orientation.OrientationSettings`'s numbers (z_max and s_max, optional and
#: bounded by other fields, stay in that class).
ORIENTATION: dict[str, Setting] = _table(
    Setting("z0", 130.0, -1e4, 1e4, "height of the x and y' lines", slider=(0.0, 350.0, 1.0)),
    Setting("angle_range", 90.0, 0.0, 180.0, "angles scanned in [-angle_range, angle_range]", "degrees",
            lo_open=True, slider=(10.0, 180.0, 5.0)),
    Setting("angle_step", 0.5, 0.01, 30.0, "angle sample spacing", "degrees", slider=(0.25, 5.0, 0.25)),
    Setting("position_step", 1.0, 0.01, 100.0, "position sample spacing"),
    Setting("eta_step", 0.5, 0.01, 10.0, "arc-stroke sample spacing", "degrees"),
    Setting("z_min", 0.0, -1e4, 1e4, "lower end of the z line"),
)

#: :class:`~kinematics.optimize.OptimizeSettings`'s numbers.
OPTIMIZE: dict[str, Setting] = _table(
    Setting("population", 16, 4, 1000, "designs per generation", integer=True),
    Setting("generations", 12, 1, 1000, "generations", integer=True),
    Setting("seed", 1, 0, 2**32 - 1, "random seed", integer=True),
    Setting("step", 0.01, 1e-6, 10.0, "parameter resolution"),
)


#: The total-orientation workspace's numbers (:func:`kinematics.dexterous.total_orientation_workspace`).
TOTAL_ORIENTATION: dict[str, Setting] = _table(
    Setting("tilt", 15.0, 0.0, 90.0, "every tilt up to T (all azimuths)", "degrees", slider=(0.0, 45.0, 1.0)),
    Setting("torsion", 15.0, 0.0, 180.0, "every torsion in [-S, S]", "degrees", slider=(0.0, 90.0, 1.0)),
    Setting("angle_step", 5.0, 0.25, 30.0, "orientation sample spacing", "degrees", slider=(2.5, 15.0, 2.5)),
)

#: :class:`~kinematics.tilt_torsion.TiltTorsionSettings`'s numbers (``tolerance`` is bounded by
#: ``coarse_step`` and stays in that class).
TILT_TORSION: dict[str, Setting] = _table(
    Setting("azimuth_step", 5.0, 0.1, 90.0, "azimuth spacing of the tilt search", "degrees"),
    Setting("coarse_step", 1.0, 0.0, 30.0, "coarse tilt step before the bisection", "degrees", lo_open=True),
    Setting("tilt_limit", 90.0, 0.0, 180.0, "largest tilt searched", "degrees", lo_open=True),
    Setting("torsion_limit", 180.0, 0.0, 180.0, "largest torsion searched", "degrees", lo_open=True),
    Setting("eta_step", 0.5, 0.01, 10.0, "arc-stroke sample spacing", "degrees"),
)


#: :class:`~kinematics.task.TaskSettings`'s numbers and the task region's (:mod:`kinematics.task`); the
#: orientation set's tilt and torsion are :data:`TOTAL_ORIENTATION`'s, the sample spacing ``voxel`` (a
#: region's cells are voxels) and ``eta_step`` are :data:`WORKSPACE`'s.
TASK: dict[str, Setting] = _table(
    Setting("angle_step", 5.0, 0.25, 30.0, "orientation sample spacing", "degrees", slider=(2.5, 15.0, 2.5)),
    Setting("margin_range", 10.0, 0.0, 1000.0, "how far outside a region its margin is searched"),
    Setting("carriage_margin", 1.0, 0.0, 1000.0, "leg/cone slack the carriage choice keeps when it can"),
    Setting("center", 0.0, -1e4, 1e4, "a region's centre coordinate"),
    Setting("size", 10.0, 0.0, 1e4, "a region's edge, radius or height"),
    Setting("max_poses", 10000, 1, 10000, "poses of a pose list", integer=True),
)


#: The dexterity field's numbers (:func:`kinematics.dexterity.dexterity_field`; the tolerance is
#: defined in :mod:`kinematics.dexterity_neighbour`).
DEXTERITY: dict[str, Setting] = _table(
    Setting("margin_tolerance", 2.0, 0.0, 1000.0,
            "largest margin gap of the neighbour search's carriage poses to the full search's"),
)

#: The dexterity field's carriage searches, the default first, with their words (the CLI's help).
DEXTERITY_SEARCHES: dict[str, str] = {
    "neighbour": "a local climb from the neighbour voxel's carriage pose, checked against the full search on a "
                 "sample (tolerance on the margin; kinematics/dexterity_neighbour.py)",
    "sweep": "the resolver's exact carriage poses, pruned (kinematics/dexterity_sweep.py)",
    "full": "the resolver's full search at every voxel and numpy's SVD (the slow path)",
}
