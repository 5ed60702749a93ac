"""The Share tab and the address bar: the link to the current state, and the current result as files.

Beside the data path slider -> state -> job -> engine -> mesh -> scene, reading only: after any
change the controllers call :meth:`ShareController.schedule_url`, which rewrites the address bar
(debounced, ``history.replaceState``; :mod:`app.jsbridge`) from the state (:func:`app.urlstate.encode_query`)
so it always holds a link to what is on screen; the Share tab shows the same link, copies it, and
downloads the full-resolution shell (STL, PLY, GLB), the measures (JSON) and the design report
(HTML, :mod:`app.report`: the design on screen and the pinned ones, computed in a background job
that reuses what is already on screen). The problems of the
link the page was opened with are shown here too (:meth:`ShareController.show_link_messages`).
"""

from __future__ import annotations

import dataclasses
import json
import threading
import urllib.parse
from typing import Any

import numpy as np

from ..textsafe import md_text
from ..urlstate import encode_query
from . import jsbridge
from .optimize_panel import DEFAULTS as _OPT_DEFAULTS
from .optimize_panel import URL_KEYS as _OPT_URL_KEYS
from .optimize_panel import OptimizePanel
from .session import SessionContext

#: Debounce of the address-bar update, seconds.
URL_DEBOUNCE = 0.25
#: The Optimize panel's settings as the link writes them, at their defaults (left out of links).
_OPT_DEFAULT_QUERY = {k: (f"{_OPT_DEFAULTS[v]:g}" if isinstance(_OPT_DEFAULTS[v], float) else str(_OPT_DEFAULTS[v]))
                      for k, v in _OPT_URL_KEYS.items()}


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    return str(obj)


class ShareController:
    """The link and the downloads of one session (module docstring). ``optimize`` is the Optimize
    panel once built (its non-default settings travel in the link)."""

    def __init__(self, ctx: SessionContext) -> None:
        self.ctx = ctx
        self.optimize: OptimizePanel | None = None  # set when the Optimize tab is built
        self.last_query: str | None = None
        self._timer: threading.Timer | None = None

    def wire(self) -> None:
        """Attach the Share tab's buttons."""
        p, cb = self.ctx.panels, self.ctx.callback
        p.copy_link.on_click(cb(self.copy_link))
        p.download_stl.on_click(cb(lambda: self.download_shell("stl")))
        p.download_ply.on_click(cb(lambda: self.download_shell("ply")))
        p.download_glb.on_click(cb(lambda: self.download_shell("glb")))
        p.download_json.on_click(cb(self.download_measures))
        p.download_report.on_click(cb(self.download_report))

    def close(self) -> None:
        """The browser left: no address-bar update is pending."""
        with self.ctx.lock:
            if self._timer is not None:
                self._timer.cancel()

    def show_link_messages(self) -> None:
        """Show the opened link's problems (fields that keep their defaults), if any."""
        ctx = self.ctx
        msgs = ctx.url_messages
        if not msgs:
            ctx.panels.url_messages.visible = False
            return
        body = "\n".join(f"- {md_text(m)}" for m in msgs)
        ctx.panels.url_messages.content = (
            "**The link had problems; these fields keep their defaults, everything else applies** "
            "(this note closes at your first change):\n\n" + body)
        ctx.panels.url_messages.visible = True
        ctx.notify("Link problems", "; ".join(msgs), color="orange")

    # ----- the link -------------------------------------------------------------------------------
    def query(self) -> str:
        """The query string of the current state (only the explorer's own keys), plus the Optimize
        panel's settings that differ from its defaults."""
        with self.ctx.lock:
            q = encode_query(self.ctx.state)
        if self.optimize is not None:
            extra = [(k, v) for k, v in self.optimize.query().items() if v != _OPT_DEFAULT_QUERY.get(k)]
            if extra:
                q += "&" + urllib.parse.urlencode(extra, safe=",")
        return q

    def link(self) -> str:
        """The shareable link of the current state."""
        return f"{self.ctx.base_url}?{self.query()}"

    def schedule_url(self) -> None:
        """Rewrite the address bar after :data:`URL_DEBOUNCE` seconds without further changes."""
        with self.ctx.lock:
            if self._timer is not None:
                self._timer.cancel()
            t = threading.Timer(URL_DEBOUNCE, self.sync_url_now)
            t.daemon = True
            self._timer = t
        t.start()

    def sync_url_now(self) -> None:
        """Rewrite the address bar and the Share tab's link now (if the state's query changed)."""
        ctx = self.ctx
        if ctx.closed:
            return
        q = self.query()
        if q == self.last_query:
            return
        self.last_query = q
        if not ctx.link_unread:  # a page whose link was never read keeps it in its address bar
            jsbridge.replace_query(ctx.client, q)
        ctx.panels.link.value = f"{ctx.base_url}?{q}"
        ctx.event("url")

    def copy_link(self) -> None:
        """Bring the address bar up to date and try to copy the link to the clipboard."""
        self.sync_url_now()
        ok = jsbridge.copy_to_clipboard(self.ctx.client, self.link())
        if ok:
            self.ctx.notify("Link copied", "the link to this design, pose and view is on the clipboard",
                            color="green")
        else:
            why = ("the browser did not allow the clipboard here" if ok is False
                   else f"the browser did not say within {jsbridge.CLIPBOARD_SECONDS:g} s whether it copied it")
            self.ctx.notify("Link not copied", f"{why}; select the link in the text field above and copy it "
                                               "(Ctrl+C)", color="orange")

    # ----- downloads ------------------------------------------------------------------------------
    def download_shell(self, fmt: str) -> None:
        """Send the full-resolution (uncut, not re-meshed) shell as STL, PLY or GLB: the marching-
        cubes surface of the voxel grid, watertight, as ``paraspace workspace --export`` writes it
        (the view shows a lighter re-mesh of it)."""
        from paraspace.kinematics.shell import export_shell, workspace_shell

        ctx = self.ctx
        b = ctx.bundle
        if b is None:
            ctx.notify("Not ready", "the full workspace is still being computed", color="orange")
            return
        try:
            mesh = workspace_shell(b.result)
            data = export_shell(mesh, fmt)
        except ValueError as exc:  # e.g. an empty workspace has no shell
            ctx.notify("No shell to download", str(exc), color="orange")
            return
        ctx.client.send_file_download(f"paraspace_workspace.{fmt}", data, save_immediately=True)
        ctx.notify("Shell downloaded", f"full-resolution shell at h = {b.result.grid.h:g}: "
                   f"{len(mesh.faces):,} faces, watertight, volume {mesh.volume:.4g} units³ "
                   f"(the view shows a {len(b.mesh.faces):,}-face re-mesh of it)", color="blue")

    def measures_document(self) -> dict:
        """JSON document of the current design, pose, settings, measures and indices."""
        ctx = self.ctx
        with ctx.lock:
            s = ctx.state
            b = ctx.bundle
            ori = ctx.orientation
            res = ctx.resolution
        doc: dict[str, Any] = {
            "link": self.link(),
            "design": s.design.to_dict() if s.mechanism is None else None,
            "mechanism": None if s.mechanism is None else s.mechanism.mechanism().to_dict(),
            "pose": s.pose.to_dict(),
            "workspace_settings": None if b is None else dataclasses.asdict(b.result.settings),
            "grid": None if b is None else b.result.grid.to_dict(),
            "compute_seconds": None if b is None else b.result.compute_seconds,
            "measures": None if b is None or b.measures is None else b.measures.to_dict(),
            "orientation": None if ori is None or s.mechanism is not None else ori.to_dict(),
            "pose_resolution": None if res is None else res.to_dict(),
        }
        return doc

    def download_measures(self) -> None:
        """Send :meth:`measures_document` as JSON."""
        data = json.dumps(self.measures_document(), indent=2, default=_json_default).encode()
        self.ctx.client.send_file_download("paraspace_measures.json", data, save_immediately=True)

    def download_report(self) -> None:
        """Write the design report of the design on screen and the pinned designs in a background
        job, then send it as ``paraspace_report.html``. The current design's workspace, measures,
        bracket and orientation maps are the ones on screen; only the pinned designs (and what is
        not on screen yet) are computed."""
        import paraspace
        from paraspace.kinematics.orientation import OrientationResult
        from paraspace.kinematics.workspace import WorkspaceSettings

        from ..report import ReportEntry, compute_entry, report_html

        ctx = self.ctx
        with ctx.lock:
            s = ctx.state
            b = ctx.bundle
            ori = ctx.orientation
        if s.mechanism is not None:  # the report is the paper design's (parameters, TI, pins)
            ctx.panels.report_status.content = f"*Design report: {md_text(s.mechanism.not_yet())}.*"
            return
        if b is None or b.measures is None or b.result.design != s.design:
            ctx.notify("Report not started", "the full workspace is still being computed; try again when the "
                       "numbers show the full result", color="orange")
            return
        link = self.link()
        osettings = s.orientation_settings()
        ori_now: OrientationResult | None = (ori if ori is not None and ori.settings == osettings
                                             and ori.design == s.design else None)
        p = ctx.panels
        p.download_report.disabled = True
        p.report_status.content = "writing the report..."
        pins = s.pins

        def fn(progress: Any, cancel: threading.Event) -> bytes:
            from paraspace.kinematics.bracket import bracket_of
            from paraspace.kinematics.orientation import orientation_workspace

            progress(0.05, "the design on screen")
            bracket = b.bracket if b.bracket is not None or s.joints.min_distance > 0 else bracket_of(b.result,
                                                                                                    cancel=cancel)
            o = ori_now if ori_now is not None else orientation_workspace(s.design, osettings, cancel=cancel)
            measures = b.measures
            assert measures is not None  # checked before the job was submitted
            entries = [ReportEntry("the design on screen", s.design, b.result, measures, bracket, o, link)]
            settings = WorkspaceSettings(voxel=b.result.grid.h, joints=s.joints)
            for k, pin in enumerate(pins):
                progress(0.3 + 0.5 * k / len(pins), f"pinned design {k + 1}")
                pin_link = link.split("?")[0] + "?" + encode_query(dataclasses.replace(s, design=pin, pins=()))
                entries.append(compute_entry(f"pinned design {k + 1}", pin, settings, osettings, link=pin_link,
                                             cancel=cancel))
            progress(0.8, "drawing the pictures")
            return report_html(entries, version=paraspace.__version__).encode("utf-8")

        def done(job: Any) -> None:
            p.download_report.disabled = False
            if job.status == "done":
                ctx.client.send_file_download("paraspace_report.html", job.result, save_immediately=True)
                p.report_status.content = (f"report sent ({len(job.result) / 1e6:.1f} MB): open it in the browser; "
                                           "print it to PDF from there")
            elif job.status == "failed":
                p.report_status.content = f"**report failed:** {md_text(job.error)}"
            else:
                p.report_status.content = "report stopped"

        def on_progress(job: Any) -> None:
            p.report_status.content = f"writing the report: {md_text(job.message or '')}, {100 * job.progress:.0f} %"

        try:
            ctx.jobs.submit(fn, kind="report", client=ctx.job_client, supersede=True, on_done=done,
                            on_progress=on_progress)
        except Exception as exc:  # noqa: BLE001 - e.g. the job limits: said, not raised into viser
            p.download_report.disabled = False
            p.report_status.content = f"report not started: {md_text(str(exc))}"
