"""The Design tab: design sliders and number boxes, the arc-range convention, Reset, the voxel edge
and the Joints group.

The first step of the data path slider -> state -> job -> engine -> mesh -> scene: a design slider
becomes a validated :class:`~kinematics.design.Design` in the state (:meth:`DesignController.apply_design`;
hand-set carriages are moved into the new strokes), then the mechanism is redrawn at once
(``app/pose_controller.py``) and a workspace job is asked for (``app/workspace_controller.py``). A
value typed outside a slider's Table I range is applied once typing pauses (:data:`TYPING_PAUSE`),
so "80" never computes "8" first; an invalid design is refused with its field and valid range.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.workspace import WorkspaceResult

from ..textsafe import md_text
from ..urlstate import D_KEYS, DESIGN_KEYS, DESIGN_SLIDERS, ETA_KEYS
from .numbers_panel import NumbersPanel
from .panels import pose_slider_span, slider_span
from .session import SessionContext

#: Seconds of quiet after which a value typed outside a slider's range is applied (see on_design_input).
TYPING_PAUSE = 0.8


class DesignController:
    """The design, voxel and joint controls of one session (module docstring).

    Args:
        ctx: the session's shared state (an invalid design's message goes to ``ctx.design_error``).
        numbers: the numbers panel (``render``), which says when a design was not applied.
        update_mechanism: redraws the mechanism at the current state (IK).
        submit_workspace: asks for the workspace of the current state.
        on_state_change: called after the design, voxel or joints changed the state (the link follows).
    """

    def __init__(self, ctx: SessionContext, *, numbers: NumbersPanel, update_mechanism: Callable[[], Any],
                 submit_workspace: Callable[[], None], on_state_change: Callable[[], None]) -> None:
        self.ctx = ctx
        self.numbers = numbers
        self.update_mechanism = update_mechanism
        self.submit_workspace = submit_workspace
        self.on_state_change = on_state_change
        self._timer: threading.Timer | None = None  # pending typed design value

    def wire(self) -> None:
        """Attach the Design tab's controls."""
        p, cb = self.ctx.panels, self.ctx.callback
        for key in DESIGN_KEYS:
            p.design[key].on_update(cb(self.on_design_input))
        p.eta_range.on_update(cb(self.on_design_input))
        p.reset.on_click(cb(self.reset_design))
        for h in p.joints.handles():
            h.on_update(cb(self.on_joints_input))
        p.voxel.on_update(cb(self.on_voxel))

    def close(self) -> None:
        """The browser left: a pending typed value is never applied."""
        with self.ctx.lock:
            if self._timer is not None:
                self._timer.cancel()

    # ----- design -----------------------------------------------------------------------------------
    def on_design_input(self) -> None:
        """A design slider or the arc-range convention changed. Reading the sliders and applying the
        design happen under ``input_lock`` (viser runs one session's callbacks concurrently; the newest
        slider values must win). Worker threads never take ``input_lock``, so it cannot invert the
        ``view_lock`` -> ``lock`` order of the workspace controller's ``publish``."""
        ctx = self.ctx
        p = ctx.panels
        typed = [k for k in DESIGN_KEYS
                 if not DESIGN_SLIDERS[k].lo <= float(p.design[k].value) <= DESIGN_SLIDERS[k].hi]
        with ctx.input_lock:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
            if typed:
                # a value outside the slider's Table I range can only come from the number box, where
                # every keystroke arrives ("80" is "8" first): apply it once typing pauses
                self._timer = threading.Timer(TYPING_PAUSE, ctx.callback(self._apply_typed_design))
                self._timer.daemon = True
                self._timer.start()
                return
            self._apply_sliders()

    def _apply_typed_design(self) -> None:
        with self.ctx.input_lock:
            self._timer = None
            self._apply_sliders()

    def _apply_sliders(self) -> None:
        """Read the design controls and apply them, or say why not (the caller holds ``input_lock``)."""
        ctx = self.ctx
        p = ctx.panels
        fields: dict[str, Any] = {k: float(p.design[k].value) for k in DESIGN_KEYS}
        fields["eta_range"] = str(p.eta_range.value)
        try:
            design = Design(**fields)
        except ParameterError as exc:
            ctx.design_error = f"{exc.field} = {exc.value:g} is invalid; valid range {exc.valid}" \
                if isinstance(exc.value, float) else str(exc)
            kept = ctx.state.design
            was = f"{exc.field} = {getattr(kept, exc.field):g}" if exc.field in DESIGN_KEYS else "the last valid design"
            p.design_message.content = (f"**Not applied:** {md_text(ctx.design_error)}. "
                                        f"The design keeps {md_text(was)}.")
            p.design_message.visible = True
            self.numbers.render()
            return
        ctx.design_error = None
        p.design_message.visible = False
        self.apply_design(design)

    def apply_design(self, design: Design) -> None:
        """Make ``design`` current: carriages, mechanism, workspace job, URL."""
        ctx = self.ctx
        with ctx.lock:
            s = ctx.state
            if design == s.design:
                return
            d, eta = list(s.d), list(s.eta)
            notes = []
            lo, hi = design.eta_limits
            for i in range(3):
                if d[i] > design.d_s:
                    notes.append(f"{D_KEYS[i]} {d[i]:g} -> {design.d_s:g}")
                    d[i] = design.d_s
                e = min(max(eta[i], lo), hi)
                if e != eta[i]:
                    notes.append(f"{ETA_KEYS[i]} {eta[i]:g} -> {e:g}")
                    eta[i] = e
            ctx.state = s.replace(design=design, d=tuple(d), eta=tuple(eta))
        self._set_carriage_slider_ranges(design, d, eta)
        if notes and ctx.state.carriages == "manual":
            ctx.notify("Carriages moved into the new strokes", ", ".join(notes), color="orange")
        self.update_mechanism()
        self.submit_workspace()
        self.on_state_change()

    def show_design(self, design: Design) -> None:
        """Put ``design`` into the design sliders (each widened to hold its value); the caller
        suppresses the callbacks."""
        p = self.ctx.panels
        for key in DESIGN_KEYS:
            h, v = p.design[key], float(getattr(design, key))
            h.min, h.max = slider_span(DESIGN_SLIDERS[key].lo, DESIGN_SLIDERS[key].hi, v)
            h.value = v
        p.eta_range.value = design.eta_range

    def load_design(self, design: Design) -> None:
        """Put ``design`` into the design sliders and apply it (as if typed)."""
        ctx = self.ctx
        with ctx.input_lock:
            with ctx.programmatic():
                self.show_design(design)
            ctx.design_error = None
            ctx.panels.design_message.visible = False
            self.apply_design(design)

    def reset_design(self) -> None:
        """Reset the design sliders to the paper's defaults (Fig. 3 design)."""
        self.load_design(Design())

    def show_result(self, r: WorkspaceResult) -> None:
        """Put the design, voxel edge, orientation and joints of ``r`` into the controls (Stop: the
        state already is ``r``'s); the callbacks are suppressed."""
        ctx = self.ctx
        p = ctx.panels
        psi, theta, phi = r.settings.orientation
        with ctx.programmatic():
            if r.design is not None:  # None: a mechanism of the selector (app/mechanism_panel.py)
                self.show_design(r.design)
            p.voxel.value = float(r.settings.voxel)
            for k, v in (("psi", psi), ("theta", theta), ("phi", phi)):
                p.pose[k].value = v
            p.joints.show(r.settings.joints)
        s = ctx.state
        self._set_carriage_slider_ranges(s.design, list(s.d), list(s.eta))

    def _set_carriage_slider_ranges(self, design: Design, d: list[float], eta: list[float]) -> None:
        p = self.ctx.panels
        lo, hi = design.eta_limits
        with self.ctx.programmatic():
            for i in range(3):
                p.d[i].max = max(design.d_s, 1e-6)
                p.d[i].value = d[i]
                p.eta[i].min = lo
                p.eta[i].max = max(hi, lo + 1e-6)
                p.eta[i].value = eta[i]
            z = p.pose["z"]
            z.min, z.max = pose_slider_span("z", design, float(self.ctx.state.pose.z))

    # ----- joints and voxel ---------------------------------------------------------------------
    def on_joints_input(self) -> None:
        """A Joints control changed: the core validates the values; a valid set recomputes the
        workspace, the orientation maps and the pose's IK with the new limits."""
        ctx = self.ctx
        with ctx.input_lock:
            joints, error = ctx.panels.joints.read()
            msg = ctx.panels.joints.message
            if error:
                msg.content = f"**Not applied:** {md_text(error)}. The last valid joints stay."
                msg.visible = True
                return
            msg.visible = False
            with ctx.lock:
                if joints == ctx.state.joints:
                    return
                ctx.state = ctx.state.replace(joints=joints)
        self.update_mechanism()
        self.submit_workspace()
        self.on_state_change()

    def on_voxel(self) -> None:
        """The voxel slider moved: recompute the workspace at the new resolution."""
        self.ctx.update_state(voxel=float(self.ctx.panels.voxel.value))
        self.submit_workspace()
        self.on_state_change()
