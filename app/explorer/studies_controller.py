"""The Plots tab's parameter studies: a measure against one design parameter (Fig. 4) and the volume
over the (a, d_s) grid (Fig. 5), with progress, Stop, CSV and PNG/SVG downloads.

A side branch of the data path slider -> state -> job -> engine -> mesh -> scene, run on request:
a button turns the current state into one ``"sweep"`` or ``"surface"`` job
(``kinematics.sweep.sweep_1d`` / ``sweep_2d``, sharing the explorer's study cache) whose result
is drawn as an interactive plot (``app/figures.py``) with the current design marked.
"""

from __future__ import annotations

import csv
import io
import threading
from collections.abc import Callable
from typing import Any

from .. import figures
from ..jobs import Job, LimitExceeded
from ..textsafe import md_text
from .plot_exports import PlotExports
from .session import PROGRESS_INTERVAL, SessionContext
from .workspace_job import ws_settings


class StudiesController:
    """The sweep and the (a, d_s) study of one session (module docstring).

    Args:
        ctx: the session's shared state.
        exports: the plots' PNG/SVG downloads (:class:`~app.plot_exports.PlotExports`).
    """

    def __init__(self, ctx: SessionContext, *, exports: PlotExports) -> None:
        self.ctx = ctx
        self.exports = exports
        self.sweep_job: Job | None = None
        self.sweep: dict | None = None  # the last sweep on screen
        self.surface_job: Job | None = None
        self.surface: dict | None = None  # the last (a, d_s) study on screen

    def wire(self) -> None:
        """Attach the two studies' buttons and the sweep's measure menu."""
        p, cb, ex = self.ctx.panels, self.ctx.callback, self.exports
        p.sweep_measure.on_update(cb(self.on_sweep_measure))
        p.sweep_run.on_click(cb(self.run_sweep))
        p.sweep_stop.on_click(cb(lambda: self.ctx.cancel_job(self.sweep_job)))
        p.sweep_csv.on_click(cb(self.download_sweep_csv))
        p.sweep_png.on_click(cb(lambda: ex.download("sweep", "png")))
        p.sweep_svg.on_click(cb(lambda: ex.download("sweep", "svg")))
        p.surface_run.on_click(cb(self.run_surface))
        p.surface_stop.on_click(cb(lambda: self.ctx.cancel_job(self.surface_job)))
        p.surface_csv.on_click(cb(self.download_surface_csv))
        p.surface_png.on_click(cb(lambda: ex.download("surface", "png")))
        p.surface_svg.on_click(cb(lambda: ex.download("surface", "svg")))

    # ----- Fig. 4 ---------------------------------------------------------------------------------
    def run_sweep(self) -> None:
        """Volume against one design parameter (Fig. 4) on request, with progress and Stop."""
        from paraspace.kinematics.sweep import study_values, sweep_1d

        ctx = self.ctx
        p = ctx.panels
        param = str(p.sweep_param.value)
        measure = str(p.sweep_measure.value)
        n = int(p.sweep_points.value)
        voxel = float(p.study_voxel.value)
        s = ctx.state
        values = study_values(param, n)
        settings = ws_settings(s, voxel)
        cache = ctx.explorer.study_cache

        # TI_1/TI_2 need the orientation maps of every point (at the current z0)
        ori = s.orientation_settings() if measure in ("TI_1", "TI_2") else None

        done_rows: list[dict] = []  # the points done, in order (read by done() after a Stop)
        n_points = len(values)

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> dict:
            # point by point, so that a Stop keeps (and draws) the points done
            for i, v in enumerate(values):
                progress(0.95 * i / n_points, f"{param} = {v:g} ({i + 1} of {n_points} points)")
                done_rows.extend(sweep_1d(s.design, param, [v], settings, orientation=ori, cancel=cancel,
                                          cache=cache))
            current = float(getattr(s.design, param))
            progress(0.95, f"the current design ({param} = {current:g})")
            cur_row = sweep_1d(s.design, param, [current], settings, orientation=ori, cancel=cancel, cache=cache)[0]
            out = {"param": param, "rows": list(done_rows), "current": current, "current_row": cur_row,
                   "current_volume": cur_row["volume"], "voxel": voxel, "design": s.design,
                   "orientation": settings.orientation}
            out["spec"] = self._sweep_spec(out, measure)
            out["figure"] = figures.to_plotly(out["spec"])
            return out

        def done(job: Job) -> None:
            p.sweep_stop.visible = False
            p.sweep_run.disabled = False
            p.sweep_progress.visible = False
            if job.status == "done":
                self._show_sweep(job.result)
                p.sweep_csv.disabled = False
                p.sweep_status.content = f"{n_points} points at h = {voxel:g} ({job.elapsed or 0.0:.0f} s)"
                return
            k = len(done_rows)
            why = "Stop pressed" if job.status == "cancelled" else f"failed: {md_text(str(job.error), 200)}"
            if k and job.status == "cancelled":
                rows = list(done_rows)
                current = float(getattr(s.design, param))
                part: dict[str, Any] = {
                    "param": param, "rows": rows, "current": current, "current_row": {}, "voxel": voxel,
                    "design": s.design, "orientation": settings.orientation,
                    "note": f"stopped after {k} of {n_points} points (Stop pressed)"}
                spec = self._sweep_spec(part, measure)
                part.update(spec=spec, figure=figures.to_plotly(spec))
                self._show_sweep(part)
                p.sweep_csv.disabled = False
            p.sweep_status.content = (
                f"**Stopped** after {k} of {n_points} points ({why}, {job.elapsed or 0.0:.0f} s): "
                + (f"the {k} points done are drawn, from {param} = {done_rows[0]['value']:g} to "
                   f"{done_rows[-1]['value']:g}; they are kept, so Run sweep computes only the other "
                   f"{n_points - k}." if k and job.status == "cancelled" else "nothing drawn."))
            if job.status == "failed":
                ctx.notify("Sweep failed", str(job.error))

        self.sweep_job = self._start(fn, "sweep", p.sweep_progress, p.sweep_stop, p.sweep_run, done, p.sweep_status)

    @staticmethod
    def _sweep_spec(data: dict, measure: str) -> figures.FigureSpec:
        cur = data["current_row"].get(measure)
        spec = figures.sweep_spec(data["rows"], data["param"], measure, current=data["current"],
                                  current_value=None if cur is None else float(cur), voxel=data["voxel"])
        if data.get("note"):  # a sweep stopped part-way says so on the figure and its downloads
            spec.warnings.append(data["note"])
        return spec

    def _show_sweep(self, data: dict) -> None:
        p = self.ctx.panels
        if self.ctx.closed:  # the browser left while the figure was being built
            return
        with self.ctx.lock:
            self.sweep = data
            self.exports.set("sweep", data["spec"])
        p.sweep_plot.aspect = data["spec"].aspect
        p.sweep_plot.figure = data["figure"]
        p.sweep_plot.visible = True
        p.sweep_png.disabled = False
        p.sweep_svg.disabled = False

    def on_sweep_measure(self) -> None:
        """The sweep's measure menu changed: redraw the last sweep when its rows carry that measure."""
        measure = str(self.ctx.panels.sweep_measure.value)
        data = self.sweep
        if data is None:
            return
        if not any(measure in r for r in data["rows"]):
            self.ctx.notify("Run the sweep again", f"the last sweep did not compute {measure}; press Run sweep",
                            color="orange")
            return
        spec = self._sweep_spec(data, measure)
        self._show_sweep({**data, "spec": spec, "figure": figures.to_plotly(spec)})

    # ----- Fig. 5 ---------------------------------------------------------------------------------
    def run_surface(self) -> None:
        """Volume over the (a, d_s) grid (Fig. 5) on request, with progress and Stop."""
        from paraspace.kinematics.sweep import study_values, sweep_1d, sweep_2d

        ctx = self.ctx
        p = ctx.panels
        n = int(p.surface_points.value)
        voxel = float(p.study_voxel.value)
        s = ctx.state
        xs = study_values("a", n)
        ys = [v for v in study_values("d_s", n) if v <= s.design.r]
        settings = ws_settings(s, voxel)
        cache = ctx.explorer.study_cache

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> dict:
            out = sweep_2d(s.design, "a", xs, "d_s", ys, settings, progress=lambda f, m: progress(0.97 * f, m),
                           cancel=cancel, cache=cache)
            cur = sweep_1d(s.design, "a", [s.design.a], settings, cancel=cancel, cache=cache)[0]
            spec = figures.study_spec(out["values_x"], out["values_y"], out["volume"], param_x="a", param_y="d_s",
                                      current=(s.design.a, s.design.d_s), current_value=cur["volume"], voxel=voxel)
            return {**out, "spec": spec, "figure": figures.to_plotly(spec), "voxel": voxel, "design": s.design,
                    "orientation": settings.orientation}

        def done(job: Job) -> None:
            p.surface_stop.visible = False
            p.surface_run.disabled = False
            p.surface_progress.visible = False
            if job.status == "done":
                with ctx.lock:
                    self.surface = job.result
                    self.exports.set("surface", job.result["spec"])
                p.surface_plot.aspect = job.result["spec"].aspect
                p.surface_plot.figure = job.result["figure"]
                p.surface_plot.visible = True
                p.surface_csv.disabled = False
                p.surface_png.disabled = False
                p.surface_svg.disabled = False
                p.surface_status.content = f"{len(xs)} x {len(ys)} points at h = {voxel:g} ({job.elapsed or 0.0:.0f} s)"
                return
            why = "Stop pressed" if job.status == "cancelled" else f"failed: {md_text(str(job.error), 200)}"
            p.surface_status.content = (f"**Stopped** at {md_text(job.progress_message, 120)} ({why}, "
                                        f"{job.elapsed or 0.0:.0f} s): nothing drawn (the surface needs every point)"
                                        + ("; the points done are kept, so Run computes only the others."
                                           if job.status == "cancelled" else "."))
            if job.status == "failed":
                ctx.notify("Study failed", str(job.error))

        self.surface_job = self._start(fn, "surface", p.surface_progress, p.surface_stop, p.surface_run, done,
                                       p.surface_status)

    def _start(self, fn: Any, kind: str, bar: Any, stop: Any, run: Any, done: Callable[[Job], None],
               status: Any) -> Job | None:
        ctx = self.ctx

        def on_progress(job: Job) -> None:
            if not ctx.throttled(kind + "-progress", PROGRESS_INTERVAL):
                bar.value = 100.0 * job.progress
                status.content = f"computing {md_text(job.message, 120)} ({job.elapsed or 0.0:.0f} s)"
        try:
            job = ctx.jobs.submit(fn, kind=kind, client=ctx.job_client, supersede=True,
                                  on_done=done, on_progress=on_progress)
        except (LimitExceeded, RuntimeError) as exc:
            ctx.notify("Not started", str(exc), color="orange")
            return None
        bar.value = 0.0
        bar.visible = True
        bar.animated = True
        stop.visible = True
        run.disabled = True
        status.content = "starting..."
        return job

    # ----- CSV ------------------------------------------------------------------------------------
    def download_sweep_csv(self) -> None:
        """Send the last volume-vs-parameter sweep as CSV (one row per value)."""
        data = self.sweep
        if data is None:
            return
        cols = ["value", "volume", "voids", "void_ratio", "hollowness", "components", "genus",
                "boundary_closed", "boundary_complete"]
        buf = io.StringIO()
        w = csv.writer(buf)
        w.writerow([data["param"]] + cols[1:])
        for r in data["rows"]:
            w.writerow([r.get(c) for c in cols])
        self.ctx.client.send_file_download(f"paraspace_sweep_{data['param']}.csv", buf.getvalue().encode(),
                                           save_immediately=True)

    def download_surface_csv(self) -> None:
        """Send the last (a, d_s) study as CSV (one row per grid point)."""
        data = self.surface
        if data is None:
            return
        buf = io.StringIO()
        w = csv.writer(buf)
        w.writerow(["a", "d_s", "volume", "voids", "hollowness", "components", "genus", "boundary_closed"])
        for pt in data["points"]:
            w.writerow([pt["x"], pt["y"], pt.get("volume"), pt.get("voids"), pt.get("hollowness"),
                        pt.get("components"), pt.get("genus"), pt.get("boundary_closed")])
        self.ctx.client.send_file_download("paraspace_volume_a_d_s.csv", buf.getvalue().encode(),
                                           save_immediately=True)
