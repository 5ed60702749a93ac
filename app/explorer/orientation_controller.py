"""The Plots tab's orientation maps (Fig. 3 e-g) and the indices TI_1 / TI_2 of the numbers panel.

On the data path slider -> state -> job -> engine -> mesh -> scene this is a side branch after the
workspace job: once a workspace is finished (``app/workspace_controller.py``), or when z0 moves,
:meth:`OrientationController.submit` runs ``kinematics.orientation.orientation_workspace`` for the
current design, z0 and joints (for a mechanism of the selector,
``kinematics.mechanism_orientation.mechanism_orientation_workspace``: the scan lines along its
symmetry axis) as an ``"orientation"`` job and draws its figure (``app/figures.py``). Maps of a
design that is no longer current are cancelled at once and never shown
(:meth:`OrientationController.forget_stale`). Results are cached per (design or mechanism, z0,
joints).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from paraspace.kinematics.design import ParameterError
from paraspace.kinematics.mechanism_orientation import mechanism_orientation_workspace
from paraspace.kinematics.orientation import OrientationResult, orientation_workspace

from .. import figures
from ..jobs import Job, LimitExceeded
from ..textsafe import md_text
from ..urlstate import ExplorerState
from .numbers_panel import NumbersPanel, fmt, ori_current
from .plot_exports import PlotExports
from .session import PROGRESS_INTERVAL, SessionContext


class OrientationController:
    """The orientation maps of one session (module docstring).

    Args:
        ctx: the session's shared state (the maps on screen go to ``ctx.orientation``).
        numbers: the numbers panel (``render``), which shows TI_1 / TI_2.
        exports: the plots' PNG/SVG downloads (:class:`~app.plot_exports.PlotExports`).
        on_state_change: called after z0 changed the state (the link follows).
    """

    def __init__(self, ctx: SessionContext, *, numbers: NumbersPanel, exports: PlotExports,
                 on_state_change: Callable[[], None]) -> None:
        self.ctx = ctx
        self.numbers = numbers
        self.exports = exports
        self.on_state_change = on_state_change
        self.gen = 0
        self.job: Job | None = None
        self._submit_lock = threading.Lock()  # orders submit() and forget_stale(); taken before ``ctx.lock``
        self.key: tuple | None = None  # (design key, z0, joints key) of the maps being computed/shown
        self.on_shown: Callable[[], None] | None = None  # e.g. the Compare table's TI column
        # the refusal of the value on screen ("" once a valid one is applied): it heads every status
        # until then, so that maps or progress of the state kept never hide why the input was refused
        self.refusal = ""

    def wire(self) -> None:
        """Attach z0 and the maps' download buttons."""
        p, cb = self.ctx.panels, self.ctx.callback
        p.z0.on_update(cb(self.on_z0))
        p.scan_range.on_update(cb(self.on_z0))
        p.scan_step.on_update(cb(self.on_z0))
        p.orientation_png.on_click(cb(lambda: self.exports.download("orientation", "png")))
        p.orientation_svg.on_click(cb(lambda: self.exports.download("orientation", "svg")))

    def on_z0(self) -> None:
        """The height of the orientation-map lines or the scan's range or step changed: recompute the
        maps (a value outside its table range is refused with the table's message)."""
        p = self.ctx.panels
        try:
            s = self.ctx.state.replace(z0=float(p.z0.value), angle_range=float(p.scan_range.value),
                                       angle_step=float(p.scan_step.value))
            s.orientation_settings()
        except ParameterError as exc:
            with self.ctx.lock:
                self.refusal = f"**Not applied:** {md_text(str(exc))}"
                p.orientation_status.content = self.refusal
            return
        with self.ctx.lock:
            self.refusal = ""  # the submit below writes the status
        self.ctx.update_state(z0=s.z0, angle_range=s.angle_range, angle_step=s.angle_step)
        self.submit()
        self.on_state_change()

    @staticmethod
    def _key(s: ExplorerState) -> tuple:
        what = s.design.key() if s.mechanism is None else ("mechanism", s.mechanism.key())
        return (what, s.orientation_settings().key())

    def forget_stale(self, s: ExplorerState) -> None:
        """Maps of another design than ``s``'s are stale: never show them, and free the worker at once."""
        ctx = self.ctx
        with self._submit_lock, ctx.lock:
            if self.key is None or self.key == self._key(s):
                return
            self.gen += 1
            self.key = None
            stale_job, self.job = self.job, None
        ctx.cancel_job(stale_job)
        with ctx.lock:
            if not ctx.closed:
                ctx.panels.orientation_status.content = self._headed("waiting for the new design's workspace...")

    def submit(self) -> None:
        """Recompute the orientation maps and TI_1/TI_2 for the current design and z0 (the generation
        and its job are taken under one lock, as in ``WorkspaceController.submit``: the job submitted
        last is the newest generation's)."""
        with self._submit_lock:
            self._submit()

    def _submit(self) -> None:
        ctx = self.ctx
        with ctx.lock:
            self.gen += 1
            gen = self.gen
            s = ctx.state
            key = self._key(s)
            self.key = key
            # the maps on screen (``ctx.orientation``, their figure in the exports: both set by
            # _publish) are already the state's (the same design or mechanism and settings, by value:
            # a state rebuilt with an equal mechanism may make another key): no job, no
            # "computing..." over the maps they are
            on_screen, spec = ctx.orientation, self.exports.specs.get("orientation")
            shown = (on_screen, spec) if spec is not None and ori_current(s, on_screen) else None
        cache = ctx.explorer.orientation_cache
        hit = shown if shown is not None else cache.get(key)
        if hit is not None:
            ctx.cancel_job(self.job)
            self._publish(gen, *hit)
            return

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            scale = lambda f, m: progress(0.85 * f, m)  # noqa: E731
            if s.mechanism is None:
                res = orientation_workspace(s.design, s.orientation_settings(), progress=scale, cancel=cancel)
            else:  # scan lines along the mechanism's symmetry axis (kinematics/mechanism_orientation.py)
                res = mechanism_orientation_workspace(s.mechanism.mechanism(), s.orientation_settings(),
                                                      progress=scale, cancel=cancel)
            progress(0.9, "drawing...")
            spec = figures.orientation_spec(res, s.z0)
            cache.put(key, (res, spec))
            return res, spec

        def done(job: Job) -> None:
            if job.status == "done":
                self._publish(gen, *job.result)
            elif job.status == "failed":
                self._set_status(gen, f"**failed:** {md_text(job.error)}")

        try:
            job = ctx.jobs.submit(
                fn, kind="orientation", client=ctx.job_client, supersede=True, on_done=done,
                on_progress=lambda j: None if ctx.throttled("or-progress", 4 * PROGRESS_INTERVAL) else
                self._set_status(gen, f"computing... {100 * j.progress:.0f} %"))
        except (LimitExceeded, RuntimeError) as exc:
            self._set_status(gen, f"not started: {md_text(exc)}")
            return
        with ctx.lock:
            if gen == self.gen:
                self.job = job
        self._set_status(gen, "computing...")

    def _set_status(self, gen: int, text: str) -> None:
        with self.ctx.lock:
            if gen != self.gen or self.ctx.closed:
                return
            self.ctx.panels.orientation_status.content = self._headed(text)

    def _headed(self, text: str) -> str:
        """``text`` under the refusal of the values on screen while they still differ from the state's
        (a link or a reset may have put valid ones there since); call with ``ctx.lock`` held."""
        p, s = self.ctx.panels, self.ctx.state
        on_screen = (float(p.z0.value), float(p.scan_range.value), float(p.scan_step.value))
        if self.refusal and on_screen != (s.z0, s.angle_range, s.angle_step):
            return f"{self.refusal}  \n{text}"
        return text

    def _publish(self, gen: int, res: OrientationResult, spec: figures.FigureSpec) -> None:
        fig = figures.to_plotly(spec)
        warning = figures.saturation_warning(res)
        ctx = self.ctx
        with ctx.lock:
            if gen != self.gen or ctx.closed:
                return
            ctx.orientation = res
            self.exports.set("orientation", spec)
            p = ctx.panels
            p.orientation_plot.aspect = spec.aspect
            p.orientation_plot.figure = fig
            p.orientation_status.content = self._headed(
                f"TI₁ = {fmt(res.ti1, 4)}, TI₂ = {fmt(res.ti2, 4)} deg·units (z0 = {res.settings.z0:g}; "
                f"{res.compute_seconds:.2f} s). Dashed boxes: the Δ extents of eq. (28)."
                + (f"  \n⚠ {md_text(warning, 600)}" if warning else ""))
        self.numbers.render()
        if self.on_shown is not None:
            self.on_shown()
        ctx.event("orientation-shown")

