"""The command line's design and joint flags, shared by its commands (:mod:`paraspace.app.cli`,
:mod:`paraspace.app.report_cli`).

Each design flag is derived from its entry of ``kinematics.design.PARAMS`` (default, the paper's
range and the accepted range in its help; the value checked by :class:`~kinematics.design.Design`,
whose message names the field and its valid range), each joint flag from
``kinematics.joints.JOINT_RANGES`` (checked by :class:`~kinematics.joints.Joints`).
"""

from __future__ import annotations

import argparse
from typing import Any

from paraspace.kinematics.design import ETA_RANGES, PARAMS, Design, ParameterError, paper_range_text

__all__ = ["add_design_flags", "add_joint_flags", "design_of", "joints_of"]


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
