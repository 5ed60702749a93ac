"""The Pose tab: pose sliders, the drag gizmo, the carriage mode and hand-set carriages, and the
mechanism drawn at the pose with its table of chains.

A pose change takes the short branch of the data path slider -> state -> job -> engine -> mesh ->
scene: slider -> state -> inverse kinematics (redundancy resolved, or the hand-set carriages; about
2 ms) -> the mechanism in the scene (:class:`~app.scene.MechanismScene`), inside
``client.atomic()``, with no workspace job -- except when the orientation (psi, theta, phi)
changed, which asks the workspace controller for a new workspace.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

import numpy as np
import viser

from paraspace.kinematics.design import ParameterError
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.redundancy import Resolution, inverse_kinematics, resolve_redundancy
from paraspace.kinematics.workspace import reachable

from ..numfmt import fixed
from ..urlstate import POSE_KEYS, POSE_RANGES, POSE_SLIDERS, ExplorerState
from .mechanism_scene import GeneralMechanismScene, mechanism_pose, show_paper_drawing
from .numbers_panel import NumbersPanel
from .panels import pose_slider_span
from .scene import LEG_STATE_TEXT, MechanismScene, rotation_wxyz
from .session import NewestMessage, SessionContext

log = logging.getLogger(__name__)


def resolve(state: ExplorerState) -> Resolution:
    """Inverse kinematics of ``state``: the hand-set carriages in manual mode, else redundancy resolved."""
    if state.carriages == "manual":
        return inverse_kinematics(state.design, state.pose, state.d, state.eta, state.joints)
    return resolve_redundancy(state.design, state.pose, state.joints)


def state_badge(status: str) -> str:
    """A leg's state for the pose table (bold when it is not inside its limits)."""
    text = LEG_STATE_TEXT.get(status, status)
    if status == "inside":
        return f"({text})"
    return f"**({text})**"


def pose_table(s: ExplorerState, res: Resolution) -> str:
    """Markdown of the pose's verdict and its table of chains (carriages, leg lengths, margins)."""
    rows = ["| chain | d | η (°) | leg 1 | leg 2 | margin |", "|---|---|---|---|---|---|"]
    for c in res.chains:
        legs = [f"{fixed(c.lengths[j])} {state_badge(c.leg_status[j])}" for j in range(2)]
        rows.append(f"| {c.chain + 1} | {fixed(c.d)} | {fixed(c.eta)} | {legs[0]} | {legs[1]} | {fixed(c.margin)} |")
    verdict = ("**reachable**" if res.feasible else f"**{res.message}**")
    cond = "-" if res.condition_number is None or not np.isfinite(res.condition_number) else \
        f"{res.condition_number:.3g}"
    return (f"{verdict}  \ncarriages: {res.mode}; legs in [{s.design.l_min:g}, {s.design.l_max:g}]; "
            f"cond(J) = {cond}\n\n" + "\n".join(rows))


class PoseController:
    """The pose, its mechanism and the gizmo of one session (module docstring).

    Args:
        ctx: the session's shared state (the IK result goes to ``ctx.resolution``).
        numbers: the numbers panel (``render``), which shows the pose's verdict.
        submit_workspace: asks for the workspace of the current state (an orientation change).
        on_state_change: called after the pose or the carriages changed the state (the link follows).
    """

    def __init__(self, ctx: SessionContext, *, numbers: NumbersPanel, submit_workspace: Callable[[], None],
                 on_state_change: Callable[[], None]) -> None:
        self.ctx = ctx
        self.numbers = numbers
        self.submit_workspace = submit_workspace
        self.on_state_change = on_state_change
        self.mechanism: MechanismScene
        self.gizmo: viser.TransformControlsHandle
        self.general: GeneralMechanismScene | None = None  # the selector's mechanism drawn (not the paper's)
        #: the gizmo's position and orientation of the user's newest drag message, until a callback takes it
        self.dragged: NewestMessage[tuple[np.ndarray, np.ndarray]] = NewestMessage(
            lambda: (np.array(self.gizmo.position, float), np.array(self.gizmo.wxyz, float)))

    def build_scene(self, res: Resolution) -> None:
        """Draw the mechanism at ``res`` and the drag gizmo (the caller holds ``client.atomic()``)."""
        ctx = self.ctx
        s = ctx.state
        scene = ctx.client.scene
        self.mechanism = MechanismScene(scene, s.design, s.pose, res.d, res.eta, res.leg_status)
        lim_x, lim_y, lim_z = ((POSE_SLIDERS[k].lo, POSE_SLIDERS[k].hi) for k in ("x", "y", "z"))
        self.gizmo = scene.add_transform_controls(
            "/gizmo", scale=max(25.0, 0.9 * s.design.a), position=s.pose.position,
            wxyz=self.mechanism.platform.wxyz, depth_test=False, opacity=0.8,
            translation_limits=(lim_x, lim_y, lim_z))

    def wire(self) -> None:
        """Attach the Pose tab's controls and the gizmo."""
        p, cb = self.ctx.panels, self.ctx.callback
        for key in ("x", "y", "z"):
            p.pose[key].on_update(cb(lambda: self.on_pose_input(orientation_changed=False)))
        for key in ("psi", "theta", "phi"):
            p.pose[key].on_update(cb(lambda: self.on_pose_input(orientation_changed=True)))
        p.gizmo.on_update(cb(self.on_gizmo_toggle))

        # update_mechanism (another thread, after the drag before) may write the shown pose into the
        # gizmo before the thread callback reads it (seen in CI: the state stayed at z = 380 after a
        # drag back to 140): the pose is recorded as the message arrives (NewestMessage)
        self.dragged.watch(self.gizmo)
        self.gizmo.on_update(self._on_gizmo)
        p.carriages.on_update(cb(self.on_carriage_mode))
        for h in p.d + p.eta:
            h.on_update(cb(self.on_manual_carriage))

    # ----- state -> IK -> scene -------------------------------------------------------------------
    def update_mechanism(self) -> Resolution:
        """IK at the current state and move the mechanism (the latest state always wins)."""
        ctx = self.ctx
        with ctx.mech_lock:
            with ctx.lock:
                s = ctx.state
            if s.mechanism is not None:
                self._update_general(s)
                return None  # type: ignore[return-value]
            if self.general is not None and not ctx.closed:  # back to the paper's design: its own drawing
                with ctx.client.atomic():
                    self.general.remove()
                    self.general = None
                    show_paper_drawing(self.mechanism, True)
            res = resolve(s)
            inside = bool(reachable(s.design, s.pose.position[None, :], (s.pose.psi, s.pose.theta, s.pose.phi),
                                    joints=s.joints)[0])
            if ctx.closed:  # the browser left during the IK: no scene to move
                return res
            with ctx.client.atomic():
                if s.design != self.mechanism.design:
                    self.mechanism.set_design(s.design, s.pose, res.d, res.eta, res.leg_status)
                else:
                    self.mechanism.update_pose(s.pose, res.d, res.eta, res.leg_status)
                self.mechanism.set_reachable(inside)
                self.gizmo.position = s.pose.position
                self.gizmo.wxyz = self.mechanism.platform.wxyz
            with ctx.lock:
                ctx.resolution = res
                ctx.in_workspace = inside
            self._update_pose_views(res)
            ctx.event("mechanism")
            return res

    def _update_general(self, s: ExplorerState) -> None:
        """IK of the selector's mechanism (``mechanism_ik``: each chain's legs furthest inside their
        ranges) and its drawing (``app/mechanism_scene.py``); the caller holds ``mech_lock``."""
        from paraspace.kinematics.mechanism_workspace import mechanism_ik, platform_rotation, reachable_general

        from .mechanism_panel import mechanism_pose_table

        ctx = self.ctx
        assert s.mechanism is not None
        mech = s.mechanism.mechanism()
        orientation = (s.pose.psi, s.pose.theta, s.pose.phi)
        iks = mechanism_ik(mech, s.pose.position, orientation)
        rot = platform_rotation(mech, orientation)
        inside = bool(reachable_general(mech, s.pose.position[None, :], orientation)[0])
        geo = mechanism_pose(mech, [ik.q for ik in iks], s.pose.position, rot)
        if ctx.closed:
            return
        with ctx.client.atomic():
            if self.general is None or self.general.mech != mech:
                if self.general is not None:
                    self.general.remove()
                show_paper_drawing(self.mechanism, False)
                self.general = GeneralMechanismScene(ctx.client.scene, mech, geo)
            self.general.update(geo, inside)
            self.mechanism.set_reachable(inside)
            self.mechanism.platform.position = s.pose.position
            self.mechanism.platform.wxyz = rotation_wxyz(rot)
            self.gizmo.position = s.pose.position
            self.gizmo.wxyz = self.mechanism.platform.wxyz
        with ctx.lock:
            ctx.resolution = None
            ctx.in_workspace = inside
            ctx.mechanism_pose = geo
            ctx.mechanism_ik = iks
        ctx.panels.pose_table.content = mechanism_pose_table(s.mechanism, iks, geo)
        self.numbers.render()
        ctx.event("mechanism")

    def _update_pose_views(self, res: Resolution) -> None:
        if self.ctx.closed:
            return
        self.ctx.panels.pose_table.content = pose_table(self.ctx.state, res)
        self.numbers.render()

    # ----- input handlers -------------------------------------------------------------------------
    def on_pose_input(self, orientation_changed: bool) -> None:
        """A pose slider moved: IK only for x, y, z; the orientation also recomputes the workspace."""
        ctx = self.ctx
        p = ctx.panels
        with ctx.lock:  # read the sliders under the lock: a concurrent older callback cannot write last
            vals = {k: float(p.pose[k].value) for k in POSE_KEYS}
            old = ctx.state.pose
            try:
                pose = Pose(**vals)
            except ParameterError as exc:  # a typed value outside the pose's valid range
                ctx.notify("Pose not applied", str(exc), color="orange")
                return
            ctx.state = ctx.state.replace(pose=pose)
        self._after_pose(old, pose, orientation_changed)

    def set_pose(self, pose: Pose) -> None:
        """Move the platform to ``pose`` from elsewhere (the Task tab's path slider): the pose
        sliders, the state, the mechanism and the link follow, as for a slider move."""
        ctx = self.ctx
        with ctx.lock:
            old = ctx.state.pose
            ctx.state = ctx.state.replace(pose=pose)
            design = ctx.state.design
        with ctx.programmatic():
            for k in POSE_KEYS:
                h = ctx.panels.pose[k]
                v = float(getattr(pose, k))
                h.min, h.max = pose_slider_span(k, design, v)
                h.value = v
        self._after_pose(old, pose, True)

    def _after_pose(self, old: Pose, pose: Pose, orientation_may_change: bool) -> None:
        self.update_mechanism()
        if orientation_may_change and (old.psi, old.theta, old.phi) != (pose.psi, pose.theta, pose.phi):
            self.submit_workspace()
        self.on_state_change()

    def _on_gizmo(self, _event: Any = None) -> None:
        if self.ctx.closed or self.ctx.is_programmatic():
            return
        try:
            self.on_gizmo_drag()
        except Exception:  # noqa: BLE001
            log.exception("gizmo callback failed")

    def on_gizmo_drag(self) -> None:
        """The platform was dragged: set the pose sliders from the gizmo (0.1 resolution)."""
        import viser.transforms as vtf

        from paraspace.kinematics.rotation import euler_zyx_from_matrix

        ctx = self.ctx
        dragged = self.dragged.take()  # the newest drag's pose (see wire)
        if dragged is None:  # already applied by the callback of an earlier message
            return
        pos, wxyz = dragged
        rot = vtf.SO3(wxyz).as_matrix()
        psi, theta, phi = np.degrees(euler_zyx_from_matrix(rot))
        vals = {"x": pos[0], "y": pos[1], "z": pos[2], "psi": psi, "theta": theta, "phi": phi}
        vals = {k: round(float(v), 1) + 0.0 for k, v in vals.items()}
        bad = [f"{k} = {v:g} outside {POSE_RANGES[k].text()}" for k, v in vals.items()
               if not POSE_RANGES[k].lo <= v <= POSE_RANGES[k].hi]
        if bad:
            ctx.notify("Pose not applied", "; ".join(bad) + " (valid range)", color="orange")
            with ctx.programmatic():
                self.gizmo.position = ctx.state.pose.position
                self.gizmo.wxyz = self.mechanism.platform.wxyz
            return
        with ctx.programmatic():
            for k in POSE_KEYS:
                h = ctx.panels.pose[k]
                h.min, h.max = pose_slider_span(k, ctx.state.design, vals[k])
                h.value = vals[k]
        with ctx.lock:
            old = ctx.state.pose
            pose = Pose(**vals)
            ctx.state = ctx.state.replace(pose=pose)
        self._after_pose(old, pose, True)

    def on_gizmo_toggle(self) -> None:
        """Show or hide the drag gizmo on the platform."""
        self.gizmo.visible = bool(self.ctx.panels.gizmo.value)

    def on_carriage_mode(self) -> None:
        """auto <-> manual. Entering manual starts from the resolved carriage values."""
        ctx = self.ctx
        p = ctx.panels
        mode = str(p.carriages.value)
        with ctx.lock:
            res = ctx.resolution
            s = ctx.state
            if mode == "manual" and res is not None:
                d = tuple(float(np.clip(round(v, 2), 0.0, s.design.d_s)) for v in res.d)
                lo, hi = s.design.eta_limits
                eta = tuple(float(np.clip(round(v, 2), lo, hi)) + 0.0 for v in res.eta)
            else:
                d, eta = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
            ctx.state = s.replace(carriages=mode, d=d, eta=eta)
        with ctx.programmatic():
            for i in range(3):
                p.d[i].value = d[i]
                p.eta[i].value = eta[i]
                p.d[i].visible = mode == "manual"
                p.eta[i].visible = mode == "manual"
        self.update_mechanism()
        self.on_state_change()

    def on_manual_carriage(self) -> None:
        """A hand-set carriage slider moved (manual mode): IK with those carriage values."""
        ctx = self.ctx
        p = ctx.panels
        with ctx.lock:
            if ctx.state.carriages != "manual":
                return
            d = tuple(float(h.value) for h in p.d)
            eta = tuple(float(h.value) for h in p.eta)
            ctx.state = ctx.state.replace(d=d, eta=eta)
        self.update_mechanism()
        self.on_state_change()
