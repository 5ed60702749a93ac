"""The "Numbers" panel: what the session has on screen, as one block of markdown.

At the end of the data path slider -> state -> job -> engine -> mesh -> scene, after the scene,
every controller calls :meth:`NumbersPanel.render` when what it shows changed: the workspace's
volume (preview or full), certified bracket, voids, hollowness, boundary and topology (from the
workspace job), TI_1 / TI_2 (from the orientation maps), the pose verdict (from the IK) and a
design that was not applied. :func:`numbers_markdown` builds the text from those values alone.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

import numpy as np

from paraspace.kinematics.mechanism_workspace import bracket_caveat

from .. import figures
from ..glossary import hover
from ..numfmt import significant
from ..textsafe import md_text
from ..urlstate import ExplorerState
from .session import SessionContext, ShellInfo

if TYPE_CHECKING:  # pragma: no cover - types only
    from paraspace.kinematics.bracket import VolumeBracket
    from paraspace.kinematics.joints import Joints
    from paraspace.kinematics.orientation import OrientationResult
    from paraspace.kinematics.redundancy import Resolution


def fmt(v: float | None, digits: int = 4) -> str:
    """``v`` to ``digits`` significant digits (:func:`~app.numfmt.significant`), ``-`` for none or non-finite."""
    if v is None:
        return "-"
    try:
        if not np.isfinite(v):
            return "-"
    except TypeError:
        return str(v)
    return significant(float(v), digits)


def bracket_text(br: VolumeBracket) -> str:
    """``inner ≤ V ≤ outer``; an outer bound of ``inf`` (a general mechanism's workspace may leave the
    bracket's grid) is said in words rather than shown as ``-``."""
    if not np.isfinite(br.volume_outer):
        return f"{fmt(br.volume_inner, 4)} ≤ V (no outer bound: the workspace may reach beyond the bracket's grid)"
    return f"{fmt(br.volume_inner, 4)} ≤ V ≤ {fmt(br.volume_outer, 4)}"


def joints_text(j: Joints) -> str:
    """One line for the joint options in force, e.g. "theta_U 45°, theta_S 40° (home axes), legs 10 + 1"."""
    parts = []
    if j.theta_u is not None:
        parts.append(f"theta_U {j.theta_u:g}°")
    if j.theta_s is not None:
        parts.append(f"theta_S {j.theta_s:g}°")
    if parts:
        parts[-1] += f" ({j.cone_axis} axes)"
    if j.leg_diameter > 0:
        parts.append(f"legs Ø {j.leg_diameter:g}" + (f" + clearance {j.clearance:g}" if j.clearance else ""))
    return ", ".join(parts)


def ori_current(s: ExplorerState, ori: OrientationResult | None) -> bool:
    """Whether ``ori`` holds the maps of ``s``: its scan settings, and its design (the paper) or its
    mechanism (a mechanism of the selector: a :class:`MechanismOrientationResult` of the same
    description)."""
    if ori is None or ori.settings != s.orientation_settings():
        return False
    mech = getattr(ori, "mechanism", None)
    if s.mechanism is None:
        return mech is None and ori.design == s.design
    return mech is not None and mech == s.mechanism.mechanism()


def numbers_markdown(s: ExplorerState, info: ShellInfo | None, res: Resolution | None, inside: bool | None,
                     ori: OrientationResult | None,
                     design_error: str | None, task_line: str | None = None, mechanism_lines: tuple[str, ...] = (),
                     pose_line: str | None = None, refused: str | None = None) -> str:
    """The panel's markdown for state ``s``: ``info`` describes the shell on screen (``ws_info`` of
    :class:`~app.session.SessionContext`, ``None`` before one), ``res`` the pose's IK, ``inside`` whether
    the pose is in the workspace, ``ori`` the orientation maps on screen (shown only when they are of
    ``s``'s design, z0 and joints). For a mechanism of the selector (``s.mechanism``),
    ``mechanism_lines`` (its name and the shell's bounds) lead and ``pose_line`` is its pose verdict.
    ``refused``: why the workspace of ``s`` is not computed (its grid refused): said in place of the
    numbers of the shell on screen, which are an older state's."""
    lines: list[str] = list(mechanism_lines)
    if not s.joints.is_default:
        lines.append(f"**Joints** {md_text(joints_text(s.joints))}  ")
    if refused is not None:
        lines.append(f"**Workspace not computed:** {md_text(refused)}"
                     + (". The shell on screen is the previous design's." if info is not None else ""))
    elif info is not None:
        m = info.measures
        kind = "preview" if info.preview else "full"
        lines.append(f"**{hover('Volume', 'volume')}** {fmt(info.volume, 4)} units³  ({kind}, h = {info.h:g})")
        br = info.bracket
        if br is not None and info.volume > 0:
            caveat = bracket_caveat(s.mechanism.mechanism()) if s.mechanism is not None else None
            lines.append(f"{hover('certified', 'bracket')}: {bracket_text(br)} (continuous workspace, units³)"
                         + (f"; {md_text(caveat)}" if caveat else "") + "  ")
        elif br is None and info.bracket_note is not None and info.volume > 0:
            lines.append(f"{hover('certified', 'bracket')} bracket {md_text(info.bracket_note)}  ")
        if info.volume == 0:
            lines.append("**Empty workspace:** no platform position is reachable at this orientation "
                         f"(psi, theta, phi) with this {'design' if s.mechanism is None else 'mechanism'}.")
        elif m is not None:
            # the measures that do not change with h lead; the raw voxel counts come last, labelled
            closed = "closed" if m.boundary_closed_stable else "open (cut or in pieces)"
            frag = (f" + {m.fragments} fragment{'s' if m.fragments != 1 else ''} "
                    f"({100 * m.fragment_volume_fraction:.2f} % of volume)" if m.fragments else "")
            pieces = f"{m.pieces} piece{'s' if m.pieces != 1 else ''}"
            lines.append(f"**{hover('Topology', 'topology')}** (stable in h) surface {closed}, {pieces}{frag}, genus "
                         f"{m.stable_genus} ({hover('ignoring features narrower than', 'features')} "
                         f"{fmt(2 * m.feature_radius, 3)} units)  ")
            if m.boundary_complete:
                lines.append(f"**{hover('Boundary', 'boundary')}** complete: one closed surface standing on the base  ")
            else:
                lines.append(f"**{hover('Boundary', 'boundary')}** incomplete: {md_text(m.completeness_reason)}  ")
            lines.append(f"**{hover('Hollowness', 'hollowness')}** {fmt(m.hollowness, 3)}  ")
            lines.append(f"**{hover('Voids', 'voids')}** {m.voids} ({100 * m.void_ratio:.2f} % of volume)  ")
            lines.append(f"<small>raw voxel counts (change with h): genus {m.genus}, {m.components} "
                         f"component{'s' if m.components != 1 else ''}</small>  ")
        elif info.stopped:
            lines.append("*measures: not computed (stopped); change a setting to compute them*  ")
        else:
            lines.append("*measures: computing...*  ")
        lines.append(f"**{hover('Compute', 'compute')}** {info.seconds:.2f} s workspace"
                     + (f", {info.shell_seconds:.2f} s shell" if info.shell_seconds else ""))
    else:
        lines.append("*workspace: computing...*")
    if ori_current(s, ori):
        assert ori is not None
        sat = {x.index for x in figures.orientation_saturation(ori)}
        flag = {k: (" (lower bound ⚠)" if k in sat else "") for k in ("TI_1", "TI_2")}
        lines.append(f"**{hover('TI₁', 'TI_1')}** {fmt(ori.ti1, 4)}{flag['TI_1']}  "
                     f"**{hover('TI₂', 'TI_2')}** {fmt(ori.ti2, 4)}{flag['TI_2']} "
                     f"deg·units  (z0 = {ori.settings.z0:g})")
        if sat:
            lines.append(f"⚠ {md_text(figures.saturation_warning(ori), 600)}")
    else:
        lines.append("**TI₁ / TI₂** *computing...*")
    if pose_line is not None:
        lines.append(f"**{hover('Pose', 'pose')}** {md_text(pose_line)}")
    elif res is not None:
        where = "" if inside is None else (" · inside the workspace" if inside else " · outside the workspace")
        if res.feasible:
            lines.append(f"**{hover('Pose', 'pose')}** reachable{where}")
        else:
            lines.append(f"**{hover('Pose', 'pose')}** {md_text(res.message)}{where}")
    if task_line:
        lines.append(f"**Task** {md_text(task_line)}")
    if design_error:
        lines.append(f"**Design not applied:** {md_text(design_error)}")
    return "\n\n".join(lines)


def summary_markdown(s: ExplorerState, info: ShellInfo | None, res: Resolution | None, inside: bool | None,
                     ori: OrientationResult | None, pose_line: str | None = None, refused: str | None = None) -> str:
    """The pinned strip above the tabs: volume with its bracket, boundary, TI_1, TI_2 and the pose,
    in two short lines (the Numbers below the tabs hold the rest). The same values and digits as
    :func:`numbers_markdown`; each name carries its definition as a hover text."""
    if refused is not None:
        first = f"**{hover('V', 'volume')}** not computed: voxel h is too fine for this design (see above)"
    elif info is None:
        first = "*workspace: computing...*"
    elif info.volume == 0:
        first = f"**{hover('V', 'volume')}** 0: empty workspace at this orientation"
    else:
        first = f"**{hover('V', 'volume')}** {fmt(info.volume, 4)} units³"
        br = info.bracket
        if br is not None:
            first += f" {hover('∈', 'bracket')} [{fmt(br.volume_inner, 4)}, {fmt(br.volume_outer, 4)}]"
        first += " (preview)" if info.preview else ""
        m = info.measures
        if m is not None:
            first += f" · {hover('boundary', 'boundary')} {'complete' if m.boundary_complete else 'incomplete'}"
    parts = []
    if ori_current(s, ori):
        assert ori is not None
        sat = {x.index for x in figures.orientation_saturation(ori)}
        for key, label, value in (("TI_1", "TI₁", ori.ti1), ("TI_2", "TI₂", ori.ti2)):
            parts.append(f"**{hover(label, key)}** {'≥ ' if key in sat else ''}{fmt(value, 4)}")
    else:
        parts.append("TI₁ / TI₂ *computing...*")
    if pose_line is not None:
        parts.append(f"{hover('pose', 'pose')} {'reachable' if pose_line.startswith('reachable') else 'not reachable'}")
    elif res is not None:
        parts.append(f"{hover('pose', 'pose')} {'reachable' if res.feasible else 'not reachable'}")
    return first + "  \n" + " · ".join(parts)


class NumbersPanel:
    """Renders :func:`numbers_markdown` of a session into its "Numbers" markdown element."""

    def __init__(self, ctx: SessionContext) -> None:
        self.ctx = ctx
        #: renders run on several threads (GUI callbacks, jobs' ends): each takes a number with its
        #: snapshot, and one whose snapshot is older than the last one written writes nothing, so a
        #: late render of an older state never overwrites a newer one (nor leaves the Numbers and the
        #: summary from two states)
        self._taken = 0
        self._written = 0
        self._write_lock = threading.Lock()

    def render(self) -> None:
        """Redraw the panel from what the session has on screen now."""
        ctx = self.ctx
        if ctx.closed:  # the browser left: its GUI handles lead nowhere
            return
        with ctx.lock:
            self._taken += 1
            ticket = self._taken
            info = ctx.ws_info  # immutable: replaced, never changed in place
            res = ctx.resolution
            inside = ctx.in_workspace
            ori = ctx.orientation
            s = ctx.state
            shown = ctx.bundle if info is not None and not info.preview else ctx.preview
            drawn = ctx.mechanism_pose
            refused = ctx.ws_refused
        mech_lines: tuple[str, ...] = ()
        pose_line = None
        if s.mechanism is not None:
            from .mechanism_panel import mechanism_lines, mechanism_pose_line

            result = shown.result if shown is not None and shown.mechanism == s.mechanism else None
            mech_lines = mechanism_lines(s.mechanism, result)
            pose_line = mechanism_pose_line(drawn, inside)
        numbers = numbers_markdown(s, info, res, inside, ori, ctx.design_error, ctx.task_line, mech_lines, pose_line,
                                   refused)
        summary = summary_markdown(s, info, res, inside, ori, pose_line, refused)
        with self._write_lock:
            if ticket < self._written:
                return
            self._written = ticket
            ctx.panels.numbers.content = numbers
            ctx.panels.summary.content = summary
