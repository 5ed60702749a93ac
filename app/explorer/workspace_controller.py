"""The "Workspace" status panel and the workspace job's life: submit, progress, publish, Stop.

On the data path slider -> state -> job -> engine -> mesh -> scene this module is "state -> job"
and "mesh -> scene": :meth:`WorkspaceController.submit` turns the current state into a
``"workspace"`` job (``supersede=True``: the last slider value wins; the job itself is
:func:`app.workspace_job.workspace_job`), and :meth:`WorkspaceController.publish` puts each shell
it produces into the scene (:class:`~app.scene.ShellScene`). A generation counter makes sure a
stale job can never overwrite a newer result, whatever the thread timing; while a new shell
computes, the one on screen is marked stale. A finished workspace starts the orientation maps.
"""

from __future__ import annotations

import dataclasses
import functools
import threading
from collections.abc import Callable

from paraspace.kinematics.design import ParameterError
from paraspace.kinematics.workspace import WorkspaceResult

from ..jobs import Job, LimitExceeded
from ..limits import check_mechanism_grid, check_workspace_grid
from ..textsafe import md_text
from .legend import colorbar_image
from .numbers_panel import NumbersPanel
from .orientation_controller import OrientationController
from .session import PROGRESS_INTERVAL, SessionContext, ShellInfo
from .view_controller import ViewController
from .workspace_job import ShellBundle, bracket, bracket_unavailable, workspace_job, ws_key, ws_settings


class WorkspaceController:
    """Submit, progress, publish and Stop of one session's workspace job (module docstring).

    Args:
        ctx: the session's shared state.
        orientation: starts the orientation maps once a workspace is finished (``submit``) and
            forgets maps of another design (``forget_stale``).
        numbers: the numbers panel (``render``).
        view: frames the first shell (``set_camera``) and reports its size (``show_payload``).
        on_measures: called after the full result's measures are shown (the Compare tab's table).
        show_controls: puts a result's design, voxel, orientation and joints back into the controls
            (Stop goes back to the shell on screen).
        on_state_change: called after Stop changed the state (the mechanism and the link follow).
    """

    def __init__(self, ctx: SessionContext, *, orientation: OrientationController, numbers: NumbersPanel,
                 view: ViewController,
                 on_measures: Callable[[], None], show_controls: Callable[[WorkspaceResult], None],
                 on_state_change: Callable[[], None]) -> None:
        self.ctx = ctx
        self.orientation = orientation
        self.numbers = numbers
        self.view = view
        self.on_measures = on_measures
        self.show_controls = show_controls
        self.on_state_change = on_state_change
        self.gen = 0
        self.job: Job | None = None
        self.bracket_job: Job | None = None  # the certified bracket of the full result on screen
        # orders submit() and Stop: taken after ``ctx.input_lock`` and before ``view_lock``/``lock``
        self._submit_lock = threading.Lock()
        self._framed = False  # the camera has framed a shell once

    def wire(self) -> None:
        """Attach the Stop button."""
        self.ctx.panels.stop.on_click(self.ctx.callback(self.stop))

    # ----- submit ---------------------------------------------------------------------------------
    def submit(self) -> None:
        """(Re)compute the workspace for the current design/orientation/voxel; the last call wins.

        viser runs a session's callbacks on several threads at once. The generation number and the
        job it names are taken under one lock (``_submit_lock``), so the job submitted last is always
        the one of the newest generation: without it, a thread holding an older state could submit
        after a newer one and supersede it (the newer job cancelled, the older one's result dropped
        as stale, and the session left idle on a shell of an older state)."""
        with self._submit_lock:
            self._submit()

    def _submit(self) -> None:
        ctx = self.ctx
        with ctx.lock:
            self.gen += 1
            gen = self.gen
            s = ctx.state
            ctx.ws_refused = None
        self.orientation.forget_stale(s)
        try:  # the same grid limit as the API, before any work is queued
            if s.mechanism is None:
                check_workspace_grid(s.design, ws_settings(s, s.voxel), ctx.explorer.max_voxels)
            else:
                check_mechanism_grid(s.mechanism.mechanism(), ws_settings(s, s.voxel), ctx.explorer.max_voxels)
        except ParameterError as exc:
            ctx.cancel_job(self.job)
            with ctx.lock:
                if gen == self.gen:
                    ctx.ws_refused = str(exc)
            self._mark_stale("this design is not computed")
            self.set_status(gen, f"**not started:** {md_text(exc)}", 0.0, running=False)
            ctx.notify("Grid too large", str(exc), color="orange")
            self.numbers.render()
            self.orientation.submit()  # TI_1, TI_2 do not depend on the voxel grid
            return
        ctx.cancel_job(self.bracket_job)
        cache = ctx.explorer.shell_cache
        hit = cache.get(ws_key(s, s.voxel))
        if hit is not None and hit.measures is not None:
            ctx.cancel_job(self.job)
            self.publish(gen, hit, preview=False, seconds=hit.result.compute_seconds, from_cache=True)
            self.publish_measures(gen, hit)
            self.set_status(gen, f"full workspace h = {s.voxel:g} (cached)", 100.0, running=False)
            self.orientation.submit()
            if hit.bracket is None:
                self._submit_bracket(gen, hit)
            return
        ctx.event("workspace-submit")
        fn = workspace_job(s, cache, show=lambda b, preview, seconds: self.publish(gen, b, preview, seconds),
                           show_measures=lambda b, preview: self.publish_measures(gen, b, preview))
        try:
            job = ctx.jobs.submit(fn, kind="workspace", client=ctx.job_client, supersede=True,
                                  on_progress=functools.partial(self._on_progress, gen),
                                  on_done=functools.partial(self._on_done, gen))
        except LimitExceeded as exc:
            self.set_status(gen, f"not started: {md_text(exc)}", 0.0, running=False)
            return
        except RuntimeError as exc:  # shut down
            self.set_status(gen, f"not started: {md_text(exc)}", 0.0, running=False)
            return
        with ctx.lock:
            if gen == self.gen:
                self.job = job
        self._mark_stale()
        self.set_status(gen, "queued...", 0.0, running=True)

    def _submit_bracket(self, gen: int, bundle: ShellBundle) -> None:
        """Certify the volume of the full result on screen in a job of its own, off the shell's
        critical path (cancelled by the next submit); the numbers panel shows it when it arrives."""
        ctx = self.ctx

        def done(job: Job) -> None:
            if job.status == "done" and job.result is not None:
                bundle.bracket = job.result
                self.publish_measures(gen, bundle)
            elif job.status == "failed":  # the panel says so, instead of leaving the line out
                self._note_bracket(gen, f"failed: {job.error}")

        why = bracket_unavailable(bundle.result)
        if why is not None:  # leg interference, or a mechanism's cones: the Numbers say why
            self._note_bracket(gen, why)
            return
        try:
            job = ctx.jobs.submit(lambda progress, cancel: bracket(bundle.result, cancel, progress), kind="bracket",
                                  client=ctx.job_client, supersede=True, on_done=done)
        except (LimitExceeded, RuntimeError) as exc:  # the server's total limit, or shut down: say so
            self._note_bracket(gen, f"not started: {exc}")
            return
        with ctx.lock:
            if gen == self.gen:
                self.bracket_job = job

    def _note_bracket(self, gen: int, note: str) -> None:
        """Why the certified bracket of generation ``gen``'s result is not coming, in the Numbers."""
        ctx = self.ctx
        with ctx.lock:
            if gen != self.gen or ctx.closed or ctx.ws_info is None:
                return
            ctx.ws_info = dataclasses.replace(ctx.ws_info, bracket_note=note)
        self.numbers.render()

    def _mark_stale(self, why: str = "recomputing") -> None:
        """The shell on screen belongs to an older state while a new one computes (or is not
        computed, ``why``): say so on it and in the legend; cleared when the new shell is shown."""
        ctx = self.ctx
        shell = ctx.shell
        assert shell is not None  # built before the controllers are wired
        with ctx.view_lock:
            if ctx.closed or shell.source is None:
                return
            with ctx.client.atomic():
                shell.set_stale(f"previous result - {why}")
                zr = shell.z_range()
                if zr is not None:
                    ctx.panels.legend.show_z_range(*zr, stale=f"previous design, {why}")

    # ----- progress and status -------------------------------------------------------------------
    def _on_progress(self, gen: int, job: Job) -> None:
        if self.ctx.throttled("ws-progress", PROGRESS_INTERVAL):
            return
        self.set_status(gen, md_text(job.message), 100.0 * job.progress, running=True)

    def _on_done(self, gen: int, job: Job) -> None:
        ctx = self.ctx
        if ctx.closed:
            return
        if job.status == "done":
            b: ShellBundle = job.result
            self.set_status(gen, f"full workspace h = {b.result.grid.h:g}: {b.result.compute_seconds:.2f} s "
                                 f"+ shell {b.shell_seconds:.2f} s", 100.0, running=False)
            with ctx.lock:
                latest = gen == self.gen
            if latest:
                self.orientation.submit()
                self._submit_bracket(gen, b)
        elif job.status == "failed":
            self.set_status(gen, f"**failed:** {md_text(job.error)}", 0.0, running=False)
        else:
            with ctx.lock:
                latest = gen == self.gen
            if latest:  # stopped by the user (a superseded job is followed by a newer one)
                self.set_status(gen, "stopped; the shell shows the last finished result", 0.0, running=False)

    def set_status(self, gen: int, text: str, percent: float, running: bool) -> None:
        """Status line, progress bar and Stop button, if ``gen`` is still the latest request."""
        with self.ctx.lock:
            if gen != self.gen or self.ctx.closed:
                return
            p = self.ctx.panels
            p.status.content = text
            p.progress.value = float(min(100.0, max(0.0, percent)))
            p.progress.animated = running
            p.stop.visible = running

    # ----- publish --------------------------------------------------------------------------------
    def publish(self, gen: int, bundle: ShellBundle, preview: bool, seconds: float,
                from_cache: bool = False) -> bool:
        """Show a shell if ``gen`` is still the latest request; returns whether it was shown."""
        ctx = self.ctx
        with ctx.view_lock:
            with ctx.lock:
                if gen != self.gen or ctx.closed:
                    return False
                s = ctx.state
            shell = ctx.shell
            assert shell is not None  # built before the controllers are wired
            with ctx.client.atomic():
                size = shell.show(bundle.mesh, s.opacity, s.cut, s.cut_z, s.cut_keep)
                zr = shell.z_range()
                if zr is not None:
                    colorbar_image(*zr)  # drawn now (cached), so the writes below follow the check at once
                if ctx.closed:  # the browser left while the shell was being encoded and sent
                    return False
                shell.set_stale(None)
                if zr is not None:
                    ctx.panels.legend.show_z_range(*zr)
            with ctx.lock:
                if preview:
                    ctx.preview = bundle
                else:
                    ctx.bundle = bundle
                ctx.ws_info = ShellInfo(volume=bundle.result.volume, h=bundle.result.grid.h, preview=preview,
                                        seconds=bundle.result.compute_seconds, shell_seconds=bundle.shell_seconds,
                                        gen=gen, cached=from_cache)
                first = not self._framed
                self._framed = True
            if first:  # the first shell: frame it (later shells keep the user's camera)
                self.view.set_camera(s.view)
            self.view.show_payload(size)
            ctx.payloads["preview" if preview else "full"] = size
        ctx.client.flush()
        ctx.event("preview-shown" if preview else "full-shown")
        self.numbers.render()
        return True

    def publish_measures(self, gen: int, bundle: ShellBundle, preview: bool = False) -> None:
        """Show the measures of the shell on screen (if it is still ``bundle``'s kind and ``gen``)."""
        ctx = self.ctx
        with ctx.lock:
            if gen != self.gen or ctx.closed:
                return
            if ctx.ws_info is None or ctx.ws_info.preview != preview:
                return
            ctx.ws_info = dataclasses.replace(ctx.ws_info, measures=bundle.measures, bracket=bundle.bracket)
        self.numbers.render()
        if not preview:
            self.on_measures()
        ctx.event("measures-preview" if preview else "measures-full")

    # ----- Stop -----------------------------------------------------------------------------------
    def stop(self) -> None:
        """The Stop button: cancel the running workspace job and go back to the state of the shell on
        screen (design, orientation, voxel, joints), so the controls, the numbers and the link all
        describe a result that exists (issue 8 defect 10)."""
        ctx = self.ctx
        with ctx.input_lock, self._submit_lock:  # no submit() between the cancel and the new generation
            ctx.cancel_job(self.job)
            ctx.cancel_job(self.bracket_job)
            shown = ctx.bundle
            if shown is None:
                return
            r = shown.result
            psi, theta, phi = r.settings.orientation
            with ctx.lock:
                s = ctx.state
                back = s.replace(design=r.design or s.design, voxel=float(r.settings.voxel),
                                 joints=r.settings.joints if r.design is not None else s.joints,
                                 mechanism=shown.mechanism,
                                 pose=dataclasses.replace(s.pose, psi=psi, theta=theta, phi=phi))
                self.gen += 1  # late progress of the cancelled job must not touch the status
                info = ctx.ws_info
                if info is not None and info.measures is None and info.volume > 0:
                    # the shell on screen stays; its measures were being computed: say they are not coming
                    ctx.ws_info = dataclasses.replace(info, stopped=True)
                same = back == s
                ctx.state = back
            if not same:
                self.show_controls(r)
        if same:
            if not ctx.closed:
                self.numbers.render()
                self.set_status(self.gen, "stopped: the shell on screen is kept, its measures were not computed"
                                if ctx.ws_info is not None and ctx.ws_info.stopped else "stopped", 100.0,
                                running=False)
            return
        if ctx.closed:
            return
        assert ctx.shell is not None  # built before the controllers are wired
        ctx.shell.set_stale(None)
        zr = ctx.shell.z_range()
        if zr is not None:
            ctx.panels.legend.show_z_range(*zr)
        self.set_status(self.gen, "stopped: back to the design on screen", 100.0, running=False)
        self.on_state_change()
