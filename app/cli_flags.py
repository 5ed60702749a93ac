"""The command line's shared flags and their readers (:mod:`paraspace.app.cli` and the commands'
modules: ``sweep_cli``, ``optimize_cli``, ``task_cli``, ``report_cli``).

Each design flag is derived from its entry of ``kinematics.design.PARAMS`` (default, the paper's
range and the accepted range in its help; the value checked by :class:`~kinematics.design.Design`,
whose message names the field and its valid range), each joint flag from
``kinematics.joints.JOINT_RANGES`` (checked by :class:`~kinematics.joints.Joints`), each scan flag
and ``--voxel`` / ``--bracket-refine`` from their ``kinematics.settings`` tables. ``--mechanism``
(:func:`mechanism_of`) refuses by name the flags a description replaces.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from paraspace.kinematics.design import ETA_RANGES, PARAMS, Design, ParameterError, paper_range_text

__all__ = ["DESIGN_FLAGS", "JOINT_FLAGS", "SCAN_FLAGS", "add_design_flags", "add_joint_flags", "add_scan_flags",
           "bracket_refine_of", "design_of", "emit_json", "float_of", "floats_of", "given", "joints_of",
           "length_step_of", "mechanism_of", "scan_of", "voxel_of"]


def add_design_flags(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("design (paper Table I; defaults are the paper's design)")
    for name, spec in PARAMS.items():
        g.add_argument(f"--{name.replace('_', '-')}", dest=name, default=spec.default, metavar="V",
                       help=f"{spec.description} (default {spec.default:g}; {paper_range_text(name)}; "
                            f"accepted [{spec.model_min:g}, {spec.model_max:g}]{' deg' if spec.unit else ''})")
    g.add_argument("--eta-range", dest="eta_range", default="centered", metavar="|".join(ETA_RANGES),
                   help="zero of the arc stroke: eta in [-eta_s/2, eta_s/2] (centered) or [0, eta_s]")


def design_of(ns: argparse.Namespace) -> Design:
    values: dict[str, Any] = {}
    for name in PARAMS:
        raw = getattr(ns, name)
        try:
            values[name] = float(raw)
        except (TypeError, ValueError):
            raise ParameterError(name, raw,
                                 f"[{PARAMS[name].model_min:g}, {PARAMS[name].model_max:g}] (a number)") from None
    return Design(**values, eta_range=ns.eta_range)


def add_joint_flags(p: argparse.ArgumentParser) -> None:
    from paraspace.kinematics.joints import CONE_AXES, JOINT_RANGES

    g = p.add_argument_group("joints (default: the paper's model, strokes only; see README 'Joint limits')")
    g.add_argument("--u-cone", dest="theta_u", metavar="DEG",
                   help=f"half-angle of every U joint's cone, {JOINT_RANGES['theta_u'][3]}")
    g.add_argument("--s-cone", dest="theta_s", metavar="DEG",
                   help=f"half-angle of every S joint's cone, {JOINT_RANGES['theta_s'][3]}")
    g.add_argument("--cone-axis", dest="cone_axis", default="normal", metavar="|".join(CONE_AXES),
                   help="cone axes: base / platform normal (default) or the legs' home directions")
    g.add_argument("--leg-diameter", dest="leg_diameter", default=0.0, metavar="W",
                   help=f"legs are capsules of this diameter, {JOINT_RANGES['leg_diameter'][3]}; two legs closer "
                        "than W + C interfere (default 0: off)")
    g.add_argument("--clearance", default=0.0, metavar="C",
                   help=f"extra distance between legs, {JOINT_RANGES['clearance'][3]} (default 0)")


def joints_of(ns: argparse.Namespace):
    """The joint flags as :class:`~kinematics.joints.Joints` (which validates every value)."""
    from paraspace.kinematics.joints import Joints

    return Joints(theta_u=ns.theta_u, theta_s=ns.theta_s, cone_axis=ns.cone_axis, leg_diameter=ns.leg_diameter,
                  clearance=ns.clearance)


#: The orientation scan's flags (``orientation``, ``sweep``, ``optimize``): flag -> table entry name.
SCAN_FLAGS: dict[str, str] = {"--angle-range": "angle_range", "--angle-step": "angle_step",
                              "--position-step": "position_step"}


def add_scan_flags(p: argparse.ArgumentParser) -> None:
    """The orientation scan's flags, each derived from its entry of ``kinematics.settings.ORIENTATION``
    (help: label, valid range, default)."""
    from paraspace.kinematics.settings import ORIENTATION

    g = p.add_argument_group("orientation scan (TI_1, TI_2)")
    for flag, name in SCAN_FLAGS.items():
        spec = ORIENTATION[name]
        g.add_argument(flag, dest=f"scan_{name}", default=None, metavar="V",
                       help=f"{spec.label}; valid range {spec.range_text()} (default {spec.default:g})")


def scan_of(ns: argparse.Namespace) -> dict[str, Any]:
    """The scan flags given, read and checked by their table entries (the others keep their defaults)."""
    from paraspace.kinematics.settings import ORIENTATION

    return {name: float(ORIENTATION[name].parse(getattr(ns, f"scan_{name}"))) for name in SCAN_FLAGS.values()
            if getattr(ns, f"scan_{name}", None) is not None}


def bracket_refine_of(ns: argparse.Namespace) -> int:
    """``--bracket-refine``, read by its one definition (kinematics.settings.WORKSPACE)."""
    from paraspace.kinematics.settings import WORKSPACE

    return int(WORKSPACE["bracket_refine"].parse(ns.bracket_refine))


def voxel_of(ns: argparse.Namespace) -> float:
    """``--voxel`` read and checked by its table entry (:data:`kinematics.settings.WORKSPACE`)."""
    from paraspace.kinematics.settings import WORKSPACE

    return float(WORKSPACE["voxel"].parse(ns.voxel))


def floats_of(field: str, text: str, count: int | None = None) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",") if v.strip() != ""]
    except ValueError:
        raise ParameterError(field, text, "comma-separated numbers") from None
    if not vals or (count is not None and len(vals) != count):
        raise ParameterError(field, text, f"{count} comma-separated numbers" if count else "at least one number")
    if not all(math.isfinite(v) for v in vals):
        raise ParameterError(field, text, "finite numbers")
    return vals


def float_of(field: str, raw: Any, valid: str) -> float:
    try:
        v = float(raw)
    except (TypeError, ValueError):
        raise ParameterError(field, raw, f"{valid} (a number)") from None
    if not math.isfinite(v):
        raise ParameterError(field, raw, valid)
    return v


def emit_json(obj: Any) -> None:
    json.dump(obj, sys.stdout, indent=2)
    sys.stdout.write("\n")


#: flags that set the paper's design or the global joint options: a mechanism description replaces them
DESIGN_FLAGS: dict[str, str] = {**{f"--{n.replace('_', '-')}": n for n in PARAMS}, "--eta-range": "eta_range"}


JOINT_FLAGS: dict[str, str] = {"--u-cone": "theta_u", "--s-cone": "theta_s", "--cone-axis": "cone_axis",
                                "--leg-diameter": "leg_diameter", "--clearance": "clearance"}


def given(ns: argparse.Namespace, flag: str, dest: str) -> bool:
    """Whether ``flag`` was written on the command line (or its value differs from the default)."""
    tokens = {t.split("=", 1)[0] for t in getattr(ns, "argv", []) if t.startswith("--")}
    if flag in tokens:
        return True
    default = _DEFAULTS.get(dest)
    value = getattr(ns, dest, None)
    return value not in (None, False) and value != default and str(value) != str(default)


_DEFAULTS: dict[str, Any] = {**{n: spec.default for n, spec in PARAMS.items()}, "eta_range": "centered",
                             "cone_axis": "normal", "leg_diameter": 0.0, "clearance": 0.0, "angle_step": 5.0,
                             "dexterity_mode": "resolved", "bracket_refine": 2, "method": "blocks",
                             "backend": "cpu"}


def mechanism_of(ns: argparse.Namespace, paper_only: dict[str, str]) -> tuple[Any, Design | None]:
    """``--mechanism FILE|PRESET [--param NAME=VALUE]...``: ``(mechanism, design)`` where ``design`` is the
    equivalent paper :class:`Design` (the paper's engine and every option apply) or ``None`` (a general
    mechanism: the flags of ``paper_only``, the design flags and the joint flags are refused by name).
    Without ``--mechanism``: ``(None, the design flags' Design)``."""
    if getattr(ns, "mechanism", None) is None:
        for flag, dest in (("--param", "param"), ("--length-step", "length_step")):
            if getattr(ns, dest, None):
                raise ParameterError(flag, getattr(ns, dest) if dest != "param" else ns.param[0],
                                     "only with --mechanism FILE|PRESET")
        return None, design_of(ns)
    from paraspace.kinematics.mechanism_workspace import paper_design

    from .mechanism_cli import resolve_mechanism

    for flag, dest in DESIGN_FLAGS.items():
        if given(ns, flag, dest):
            raise ParameterError(flag, getattr(ns, dest), "not with --mechanism: set a preset's parameters with "
                                 "--param NAME=VALUE (paraspace mechanism presets lists them)")
    mech = resolve_mechanism(ns.mechanism, ns.param)
    design = paper_design(mech)
    if design is None:
        for flag, dest in JOINT_FLAGS.items():
            if given(ns, flag, dest):
                raise ParameterError(flag, getattr(ns, dest), "only for the paper's mechanism: a description "
                                     "carries its own cones (u_cone, s_cone per leg)")
        for flag, dest in paper_only.items():
            if given(ns, flag, dest):
                raise ParameterError(flag, getattr(ns, dest), f"only for the paper's mechanism, not {mech.name!r}")
    return mech, design


def length_step_of(ns: argparse.Namespace) -> float:
    from paraspace.kinematics.mechanism_workspace import check_length_step

    raw = getattr(ns, "length_step", None)
    return check_length_step(float_of("length_step", raw, "[0.01, 100]")) if raw is not None else 1.0
