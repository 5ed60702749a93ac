"""The Share tab and the address bar: the link to the current state, and the current result as files.

Beside the data path slider -> state -> job -> engine -> mesh -> scene, reading only: after any
change the controllers call :meth:`ShareController.schedule_url`, which rewrites the address bar
(debounced, ``history.replaceState``; :mod:`app.jsbridge`) from the state (:func:`app.urlstate.encode_query`)
so it always holds a link to what is on screen; the Share tab shows the same link, copies it, and
downloads the full-resolution shell (STL, PLY, GLB) and the measures (JSON). The problems of the
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
            self.ctx.notify("Link not copied", "the browser did not allow the clipboard here; select the link "
                                               "in the text field above and copy it (Ctrl+C)", color="orange")

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
            "design": s.design.to_dict(),
            "pose": s.pose.to_dict(),
            "workspace_settings": None if b is None else dataclasses.asdict(b.result.settings),
            "grid": None if b is None else b.result.grid.to_dict(),
            "compute_seconds": None if b is None else b.result.compute_seconds,
            "measures": None if b is None or b.measures is None else b.measures.to_dict(),
            "orientation": None if ori is None else ori.to_dict(),
            "pose_resolution": None if res is None else res.to_dict(),
        }
        return doc

    def download_measures(self) -> None:
        """Send :meth:`measures_document` as JSON."""
        data = json.dumps(self.measures_document(), indent=2, default=_json_default).encode()
        self.ctx.client.send_file_download("paraspace_measures.json", data, save_immediately=True)
