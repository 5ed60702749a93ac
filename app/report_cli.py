"""``paraspace report``: the design report (:mod:`paraspace.app.report`) from the command line.

    paraspace report [design flags] [joint flags] [--voxel H] [--compare NAME=V[,NAME=V...]]...
                     [--no-orientation] [--z0 Z] [--link-base URL] --out FILE.html

The design flags give the first design; each ``--compare`` adds one more, written as the first
design with the given parameters changed (``--compare a=80`` or ``--compare d_s=10,eta_s=60``), up
to :data:`~paraspace.app.report.MAX_DESIGNS` in all. Every design gets the explorer link that
restores it (on ``--link-base``, the explorer's address; default ``http://127.0.0.1:8080/``).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import threading
from typing import Any

import paraspace
from paraspace.kinematics.design import PARAMS, Design, ParameterError

from .cli_flags import add_design_flags, add_joint_flags, design_of, joints_of
from .fileout import write_atomic
from .progressline import progress_line

__all__ = ["add_report_parser", "cmd_report", "parse_change"]


def parse_change(base: Design, text: str) -> Design:
    """``base`` with the changes of ``text`` (``"a=80,d_s=10"``); a bad name or value raises
    :class:`ParameterError` naming it and its valid range."""
    changes: dict[str, Any] = {}
    for part in (p.strip() for p in text.split(",") if p.strip()):
        name, sep, value = part.partition("=")
        name = name.strip()
        if not sep or name not in (*PARAMS, "eta_range"):
            raise ParameterError("compare", part, "NAME=VALUE with NAME one of " + ", ".join((*PARAMS, "eta_range")))
        if name == "eta_range":
            changes[name] = value.strip()
            continue
        spec = PARAMS[name]
        try:
            changes[name] = float(value)
        except ValueError:
            raise ParameterError(name, value, f"[{spec.model_min:g}, {spec.model_max:g}] (a number)") from None
    if not changes:
        raise ParameterError("compare", text, "NAME=VALUE[,NAME=VALUE...], e.g. a=80")
    return dataclasses.replace(base, **changes)


def _name(base: Design, d: Design) -> str:
    diff = [f"{k} = {getattr(d, k):g}" for k in PARAMS if getattr(d, k) != getattr(base, k)]
    if d.eta_range != base.eta_range:
        diff.append(f"eta_range = {d.eta_range}")
    return ", ".join(diff) if diff else "the design"


def cmd_report(ns: argparse.Namespace) -> int:
    from paraspace.kinematics.orientation import OrientationSettings
    from paraspace.kinematics.settings import ORIENTATION, WORKSPACE
    from paraspace.kinematics.workspace import WorkspaceSettings

    from .report import MAX_DESIGNS, compute_entry, report_html
    from .urlstate import ExplorerState, encode_query

    if not str(ns.out).lower().endswith((".html", ".htm")):
        raise ParameterError("out", ns.out, "a file name ending in .html")
    base = design_of(ns)
    designs = [base] + [parse_change(base, c) for c in ns.compare or ()]
    if len(designs) > MAX_DESIGNS:
        raise ParameterError("compare", len(designs) - 1, f"at most {MAX_DESIGNS - 1} designs to compare")
    voxel = float(WORKSPACE["voxel"].parse(ns.voxel))
    joints = joints_of(ns)
    settings = WorkspaceSettings(voxel=voxel, joints=joints)
    orientation = None if ns.no_orientation else OrientationSettings(z0=float(ORIENTATION["z0"].parse(ns.z0)),
                                                                     joints=joints)
    progress, done = progress_line("report")
    total = len(designs)
    entries = []
    try:
        for k, d in enumerate(designs):
            def say(text: str, k: int = k) -> None:
                if progress is not None:
                    progress(k / total, f" {k + 1}/{total} {text}")

            state = ExplorerState(design=d, voxel=voxel, joints=joints,
                                  z0=orientation.z0 if orientation is not None else ExplorerState().z0)
            link = ns.link_base.rstrip("/") + "/?" + encode_query(state)
            name = "the design" if k == 0 else _name(base, d)
            entries.append(compute_entry(name, d, settings, orientation, link=link, cancel=threading.Event(),
                                         say=say))
    finally:
        done()
    html_text = report_html(entries, title=ns.title, version=paraspace.__version__)
    write_atomic(ns.out, html_text.encode("utf-8"))
    sys.stdout.write(f"wrote {ns.out} ({len(entries)} design{'s' if len(entries) != 1 else ''}, "
                     f"{len(html_text) / 1e6:.1f} MB)\n")
    return 0


def add_report_parser(sub: Any) -> None:
    """The ``report`` sub-command on ``sub`` (the CLI's sub-parsers)."""
    r = sub.add_parser("report", help="a self-contained HTML report of a design (or several, side by side)")
    add_design_flags(r)
    r.add_argument("--compare", action="append", metavar="NAME=V[,NAME=V]",
                   help="add a design: the one above with these parameters changed (repeatable)")
    r.add_argument("--voxel", default=4.0, help="voxel edge h (default 4)")
    r.add_argument("--z0", default=130.0, help="height of the orientation maps' x and y' lines (default 130)")
    r.add_argument("--no-orientation", dest="no_orientation", action="store_true",
                   help="leave out the orientation maps and TI_1, TI_2 (faster)")
    r.add_argument("--title", default="paraspace design report", help="the report's title")
    r.add_argument("--link-base", dest="link_base", default="http://127.0.0.1:8080/", metavar="URL",
                   help="the explorer's address, for the links that restore each design")
    r.add_argument("--out", required=True, metavar="FILE.html", help="where to write the report")
    add_joint_flags(r)
    r.set_defaults(func=cmd_report)
