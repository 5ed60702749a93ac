"""``paraspace task``: does a design hold a region (with an orientation set) or follow a pose list, by
what margin and which limit binds (:mod:`kinematics.task`; a general mechanism:
:mod:`kinematics.mechanism_task`); and the task flags that ``sweep`` and ``optimize`` share.
"""

from __future__ import annotations

import argparse
import csv
import io
import os
from typing import Any

from paraspace.kinematics.design import ParameterError

from .cli_flags import (
    add_design_flags,
    add_joint_flags,
    emit_json,
    floats_of,
    joints_of,
    length_step_of,
    mechanism_of,
    voxel_of,
)
from .fileout import write_atomic
from .mechanism_cli import add_mechanism_flags
from .progressline import progress_line


def _task_of(ns: argparse.Namespace) -> Any:
    """The task of ``--box`` / ``--cylinder`` / ``--sphere`` / ``--points`` (exactly one)."""
    from paraspace.kinematics.task import MAX_CSV_BYTES, Region, read_pose_csv

    given = [s for s in ("box", "cylinder", "sphere", "points") if getattr(ns, s, None) is not None]
    if len(given) != 1:
        raise ParameterError("task", ",".join(given) or None,
                             "exactly one of --box CX,CY,CZ,LX,LY,LZ, --cylinder CX,CY,CZ,R,H, --sphere CX,CY,CZ,R "
                             "or --points FILE.csv")
    kind = given[0]
    if kind == "points":
        path = ns.points
        if not os.path.isfile(path):
            raise ParameterError("points", path, "an existing CSV file with the header x,y,z,psi,theta,phi[,t]")
        size = os.path.getsize(path)
        if size > MAX_CSV_BYTES:
            raise ParameterError("points", f"{size:,} bytes", f"at most {MAX_CSV_BYTES:,} bytes (at most "
                                 f"{MAX_CSV_BYTES // 100:,} poses)")
        with open(path, "rb") as fh:
            return read_pose_csv(fh.read())
    return Region.parse(kind, floats_of(kind, getattr(ns, kind)))


def _task_orientations(ns: argparse.Namespace) -> Any:
    from paraspace.kinematics.task import OrientationSet

    o = floats_of("orientation", ns.orientation, 3) if ns.orientation else [0.0, 0.0, 0.0]
    return OrientationSet(tilt=ns.tilt, torsion=ns.torsion, fixed=(o[0], o[1], o[2]), step=ns.angle_step)


def _task_settings(ns: argparse.Namespace) -> Any:
    from paraspace.kinematics.task import TaskSettings

    return TaskSettings(voxel=ns.voxel, eta_step=ns.eta_step, margin_range=ns.margin_range,
                        carriage_margin=ns.carriage_margin, joints=joints_of(ns))


def study_task(ns: argparse.Namespace, joints: Any) -> Any:
    """The ``TaskSpec`` of a study's task flags (``sweep``, ``optimize``), or ``None`` when none is given."""
    if not any(getattr(ns, k, None) is not None for k in ("box", "cylinder", "sphere", "points")):
        return None
    from paraspace.kinematics.task import OrientationSet, TaskSettings, TaskSpec

    return TaskSpec(_task_of(ns), OrientationSet(tilt=ns.tilt, torsion=ns.torsion, step=ns.task_angle_step),
                    TaskSettings(voxel=voxel_of(ns), margin_range=ns.margin_range, joints=joints))


def add_study_task_flags(p: argparse.ArgumentParser, title: str) -> None:
    """The task flags of a study (``sweep``, ``optimize``): the region or pose list, its orientation set
    and sampling (the task's cells are the study's voxels)."""
    from paraspace.kinematics.settings import TASK, TOTAL_ORIENTATION

    add_task_flags(p, title)
    for name in ("tilt", "torsion"):
        spec = TOTAL_ORIENTATION[name]
        p.add_argument(f"--{name}", metavar="DEG", help=f"the task region's {spec.label} (optimize: also the "
                                                        f"orientation set of total_orientation_volume); valid range "
                                                        f"{spec.range_text()}")
    p.add_argument("--task-angle-step", dest="task_angle_step", default=TASK["angle_step"].default, metavar="DEG",
                   help=f"the task's {TASK['angle_step'].label}; valid range {TASK['angle_step'].range_text()}")
    p.add_argument("--margin-range", dest="margin_range", default=TASK["margin_range"].default, metavar="V",
                   help=f"the task's {TASK['margin_range'].label}; valid range {TASK['margin_range'].range_text()}")


def add_task_flags(p: argparse.ArgumentParser, title: str) -> None:
    """``--box | --cylinder | --sphere | --points`` (``task`` and ``optimize``)."""
    from paraspace.kinematics.settings import TASK

    g = p.add_argument_group(title)
    size = TASK["size"].range_text()
    g.add_argument("--box", metavar="CX,CY,CZ,LX,LY,LZ", help=f"a box: centre and edges (edges {size})")
    g.add_argument("--cylinder", metavar="CX,CY,CZ,R,H", help=f"a cylinder with a vertical axis (R, H {size})")
    g.add_argument("--sphere", metavar="CX,CY,CZ,R", help=f"a sphere (R {size})")
    g.add_argument("--points", metavar="FILE.csv",
                   help="a pose list: header x,y,z,psi,theta,phi[,t], degrees and seconds; at most "
                        f"{int(TASK['max_poses'].hi):,} poses")


def task_csv(out: dict[str, Any]) -> str:
    """A pose list's answer one pose per row (index, t, reachable, leg slack, the 12 actuator values), or a
    region's answer as one row of its scalars."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    if out["kind"] == "poses":
        names = out["actuator_names"]
        w.writerow(["index", "t", "reachable", "leg_slack", *names])
        for r in out["poses"]:
            w.writerow([r["index"], r.get("t", ""), int(r["reachable"]), repr(r["leg_slack"]), *map(repr, r["q"])])
    else:
        keys = ["fraction", "contained", "certified", "margin", "margin_saturated", "sample_points",
                "reachable_points", "orientation_samples", "seconds"]
        w.writerow(keys + ["binding"])
        w.writerow([out[k] for k in keys] + [out["binding"]["message"]])
    return buf.getvalue()


def cmd_task(ns: argparse.Namespace) -> int:
    """``paraspace task``: does the design hold a region or follow a pose list, by what margin."""
    from paraspace.kinematics.task import evaluate_task
    from paraspace.kinematics.workspace import warm_up

    mech, design = mechanism_of(ns, {})
    task = _task_of(ns)
    oset = _task_orientations(ns)
    settings = _task_settings(ns)
    if ns.points is not None and (ns.tilt is not None or ns.torsion is not None or ns.orientation):
        raise ParameterError("tilt", ns.tilt if ns.tilt is not None else ns.torsion,
                             "not with --points (each pose carries its orientation)")
    progress, done = progress_line("task")
    try:
        if design is None:  # a general mechanism (kinematics/mechanism_task.py)
            from paraspace.kinematics.mechanism_task import evaluate_mechanism_task
            from paraspace.kinematics.mechanism_workspace import warm_up_general

            warm_up_general()
            res = evaluate_mechanism_task(mech, task, oset, settings, length_step_of(ns), progress)
        else:
            warm_up()
            res = evaluate_task(design, task, oset, settings, progress)
    finally:
        done()
    from paraspace.kinematics.serialize import jsonable

    out = jsonable(res.to_dict())
    if ns.csv:
        write_atomic(ns.csv, task_csv(out))
    if ns.json:
        emit_json(out)
        return 0
    what = (f"{out['count']} poses" if out["kind"] == "poses" else
            f"{out['region']['shape']} of {out['sample_points']} sample points x {out['orientation_samples']} "
            f"orientations")
    print(f"task            {what}")
    print(f"fraction        {out['fraction']:.4g}  (contained: {'yes' if out['contained'] else 'no'})")
    print(f"certified       {out['certified']}")
    sat = " (at least: no unreachable point within margin_range)" if out.get("margin_saturated") else ""
    print(f"margin          {out['margin']:.4g}{sat}")
    print(f"binding         {out['binding']['message']}")
    if out["kind"] == "poses" and design is None:
        if out["unreachable"]:
            print(f"unreachable     {', '.join(map(str, out['unreachable'][:20]))}"
                  + (" ..." if len(out["unreachable"]) > 20 else ""))
    elif out["kind"] == "poses":
        car = out["carriage"]
        print(f"carriage travel d {car['travel_d']:.4g}, eta {car['travel_eta']:.4g} deg"
              + (f"; max speed d {car['max_speed_d']:.4g}/s, eta {car['max_speed_eta']:.4g} deg/s"
                 if "max_speed_d" in car else ""))
        jumps = sorted({j["index"] for j in out["discontinuities"]})
        print(f"discontinuities {', '.join(map(str, jumps)) if jumps else 'none'}")
        if out["unreachable"]:
            print(f"unreachable     {', '.join(map(str, out['unreachable'][:20]))}"
                  + (" ..." if len(out["unreachable"]) > 20 else ""))
        for a in out["actuators"]:
            print(f"  {a['name']:<7} {a['min']:9.3f} .. {a['max']:9.3f}  of [{a['stroke'][0]:g}, {a['stroke'][1]:g}]"
                  f"  ({100 * a['used_fraction']:.0f} % used)")
    print(f"seconds         {out['seconds']:.2f}")
    return 0


def add_task_parser(sub: Any) -> None:
    from paraspace.kinematics.settings import TASK, TOTAL_ORIENTATION

    t = sub.add_parser("task", help="does the design hold a region (with an orientation set) or follow a pose list")
    add_design_flags(t)
    add_task_flags(t, "the task (exactly one)")
    o = t.add_argument_group("orientation set of a region (default: the home orientation)")
    for name in ("tilt", "torsion"):
        spec = TOTAL_ORIENTATION[name]
        o.add_argument(f"--{name}", metavar="DEG", help=f"{spec.label}; valid range {spec.range_text()}")
    o.add_argument("--orientation", metavar="PSI,THETA,PHI", help="one fixed orientation instead (eq. (2), degrees)")
    from paraspace.kinematics.settings import WORKSPACE

    for name in ("voxel", "angle_step", "eta_step", "margin_range", "carriage_margin"):
        spec = WORKSPACE[name] if name in ("voxel", "eta_step") else TASK[name]
        t.add_argument(f"--{name.replace('_', '-')}", dest=name, default=spec.default, metavar="V",
                       help=f"{spec.label}; valid range {spec.range_text()} (default {spec.default:g})")
    t.add_argument("--json", action="store_true", help="one JSON object: fraction, contained, certified, margin, "
                                                      "worst, binding (and poses, discontinuities for a pose list)")
    t.add_argument("--csv", metavar="OUT", help="write the answer as CSV (a pose list: one row per pose)")
    add_joint_flags(t)
    add_mechanism_flags(t)
    t.set_defaults(func=cmd_task)
