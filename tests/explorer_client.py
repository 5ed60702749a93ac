"""A protocol-level viser client for tests: :class:`FakeBrowser` and polling helpers.

:class:`FakeBrowser` is a websocket client that speaks viser 1.1.1's wire format (notes §5),
answers localStorage requests as a browser that has run the JS bridge (app/jsbridge.py) would,
plays ``history.replaceState`` on a fake ``location.search``, and records what the server sends
(scripts, file downloads). Inputs are sent as ``GuiUpdateMessage`` exactly like the web client
does, so they go through viser's callback thread pool.

Shared by tests/test_explorer.py and tests/test_load_explorer.py (pytest's default "prepend"
import mode puts tests/ on ``sys.path``, so ``from explorer_client import ...`` works).
"""

from __future__ import annotations

import json
import re
import sys
import threading
import time
import traceback
import warnings
from collections.abc import Callable
from typing import Any

import msgspec
import viser
import zstandard
from websockets.sync.client import connect

from paraspace.app.explorer import ClientSession, Explorer

__all__ = ["DEADLINE_SCALE", "FakeBrowser", "wait_for", "wait_idle"]

#: Every deadline of :func:`wait_for` and :func:`wait_idle` is multiplied by this. The deadlines bound
#: liveness only (a test fails instead of hanging); speed is never asserted in tests, it is measured
#: by the benchmarks. The suite runs two worker processes on two cores (scripts/test.sh), where a
#: callback can wait seconds for a core while another worker compiles or meshes.
DEADLINE_SCALE = 4.0


class FakeBrowser:
    """A viser client over the websocket protocol, with a fake ``location`` and localStorage."""

    def __init__(self, explorer: Explorer, search: str = "", *, location_delay: float = 0.0,
                 answers_location: bool = True, build_timeout: float = 20.0) -> None:
        """``location_delay``: seconds this "browser" takes to tell its link (a busy browser);
        ``answers_location=False``: it never does."""
        self.location_delay = location_delay
        self.answers_location = answers_location
        self.explorer = explorer
        self.search = search if not search or search.startswith("?") else "?" + search
        self.base = explorer.url
        self.storage: dict[str, str] = {}
        self.scripts: list[str] = []
        #: every address-bar rewrite the server sent (app/jsbridge.replace_query), in order
        self.rewrites: list[str] = []
        self.downloads: dict[str, dict[str, Any]] = {}
        self.lock = threading.Lock()
        self.closed = False
        #: this page's viser client id, read from the key of the server's location request (the
        #: server names it ``paraspace_location_<client id>``): pages opened at once each wait for
        #: their own session, never for whichever new session is ready first.
        self.client_id: int | None = None
        self.ws = connect(explorer.url.replace("http", "ws").rstrip("/"),
                          subprotocols=[f"viser-v{viser.__version__}"], max_size=None)
        self._send({"type": "ViewerCameraMessage", "wxyz": (1.0, 0.0, 0.0, 0.0), "position": (0.0, 0.0, 500.0),
                    "fov": 1.0, "near": 0.01, "far": 1000.0, "image_height": 720, "image_width": 1280,
                    "look_at": (0.0, 0.0, 0.0), "up_direction": (0.0, 0.0, 1.0)})
        self.thread = threading.Thread(target=self._recv_loop, daemon=True)
        self.thread.start()
        self.session: ClientSession = wait_for(self._own_ready_session, build_timeout, "the session was not built")

    def _own_ready_session(self) -> ClientSession | None:
        if self.client_id is None:
            return None
        s = self.explorer.session(self.client_id)
        return s if s is not None and s.ready.is_set() else None

    # ----- wire ---------------------------------------------------------------------------------
    def _send(self, msg: dict) -> None:
        self.ws.send(msgspec.msgpack.encode(msg))

    def _recv_loop(self) -> None:
        dctx = zstandard.ZstdDecompressor()
        while not self.closed:
            try:
                raw = self.ws.recv()
            except Exception:  # noqa: BLE001 - closed
                return
            if not isinstance(raw, bytes):
                continue
            inner = int.from_bytes(raw[0:8], "little")
            comp = int.from_bytes(raw[8:16], "little")
            payload = msgspec.msgpack.decode(dctx.decompress(raw[16:16 + comp], max_output_size=inner))
            for m in payload["messages"]:
                self._handle(m)

    def _handle(self, m: dict) -> None:
        kind = m.get("type")
        if kind == "RunJavascriptMessage":
            src = m["source"]
            with self.lock:
                self.scripts.append(src)
            # Play the browser: the scripts of app/explorer/jsbridge.py that matter here.
            var_k = re.search(r"var k = (\"[^\"]+\");", src)
            if var_k and "location.search" in src:
                own = re.fullmatch(r"viser-user:paraspace_location_(\d+)", json.loads(var_k.group(1)))
                if own:
                    self.client_id = int(own.group(1))
                self.storage[json.loads(var_k.group(1))] = json.dumps({"search": self.search, "base": self.base})
            if var_k and "navigator.clipboard" in src:  # a page without clipboard access
                self.storage[json.loads(var_k.group(1))] = "refused"
            if var_k and "paraspace_drawn_" in src:  # jsbridge.wait_drawn: a page that draws at once
                self.storage[json.loads(var_k.group(1))] = "1"
            q = re.search(r"var q = (\"(?:[^\"\\]|\\.)*\");", src)
            if q and "replaceState" in src:  # app/jsbridge.replace_query (plotly.js mentions replaceState too)
                self.search = json.loads(q.group(1))
                with self.lock:
                    self.rewrites.append(self.search)
        elif kind == "LocalStorageGetItemRequestMessage":
            value = self.storage.get("viser-user:" + m["key"])
            answer = {"type": "LocalStorageGetItemResponseMessage", "value": value, "error": None,
                      "request_uuid": m["request_uuid"]}
            if "paraspace_location" in m["key"]:  # the page's link: a busy browser answers late, or never
                if not self.answers_location:
                    return
                if self.location_delay > 0:
                    threading.Timer(self.location_delay, self._send, (answer,)).start()
                    return
            self._send(answer)
        elif kind == "LocalStorageRemoveItemMessage":
            self.storage.pop("viser-user:" + m["key"], None)
        elif kind == "FileTransferStartDownload":
            with self.lock:
                self.downloads[m["transfer_uuid"]] = {"filename": m["filename"], "parts": {},
                                                      "count": m["part_count"]}
        elif kind == "FileTransferPart":
            with self.lock:
                d = self.downloads.get(m["transfer_uuid"])
                if d is not None:
                    d["parts"][m["part_index"]] = bytes(m["content"])

    # ----- actions -------------------------------------------------------------------------------
    def set(self, handle: Any, value: Any) -> None:
        """Change a GUI input the way the web client does."""
        self._send({"type": "GuiUpdateMessage", "uuid": handle._impl.uuid, "updates": {"value": value}})

    def click(self, handle: Any) -> None:
        self.set(handle, True)

    def download(self, filename: str, timeout: float = 20.0) -> bytes:
        def done() -> bytes | None:
            with self.lock:
                for d in self.downloads.values():
                    if d["filename"] == filename and len(d["parts"]) == d["count"]:
                        return b"".join(d["parts"][i] for i in range(d["count"]))
            return None
        return wait_for(done, timeout, f"download {filename}")

    def close(self) -> None:
        self.closed = True
        self.ws.close()


class SlowWait(UserWarning):
    """A wait that succeeded but took longer than :data:`SLOW_WAIT` seconds: not a failure (speed is
    never asserted in tests), a line in the run's warnings summary that names the test and the wait,
    so that a slow run of the suite says where its time went."""


#: Seconds after which a successful wait is reported as :class:`SlowWait`.
SLOW_WAIT = 15.0


def note_slow_wait(what: str, t0: float) -> None:
    """Report the wait for ``what`` begun at ``t0`` (``time.monotonic()``) if it took over :data:`SLOW_WAIT`."""
    took = time.monotonic() - t0
    if took > SLOW_WAIT:
        warnings.warn(SlowWait(f"waiting for {what} took {took:.1f} s"), stacklevel=3)


def wait_for(fn: Callable[[], Any], timeout: float, what: str) -> Any:
    """Poll ``fn`` until it returns a truthy value (returned) or fail after ``timeout`` seconds (times
    :data:`DEADLINE_SCALE`); a wait over :data:`SLOW_WAIT` seconds is reported (:class:`SlowWait`)."""
    t0 = time.monotonic()
    deadline = t0 + timeout * DEADLINE_SCALE
    while time.monotonic() < deadline:
        v = fn()
        if v:
            note_slow_wait(what, t0)
            return v
        time.sleep(0.02)
    raise AssertionError(f"timed out after {timeout * DEADLINE_SCALE:g} s waiting for: {what}\n"
                         f"the other threads (the explorer's callbacks and jobs run in this process):\n"
                         f"{thread_stacks()}")


def thread_stacks(depth: int = 14) -> str:
    """The innermost ``depth`` frames of every thread but the caller's, by name: what a time-out waited
    on (a callback blocked on a lock, a job that does not end). A wait that failed once in CI and never
    here then says where it stood."""
    names = {t.ident: t.name for t in threading.enumerate()}
    me = threading.get_ident()
    parts = []
    for ident, frame in sys._current_frames().items():
        if ident != me:
            parts.append(f"--- {names.get(ident, ident)}\n" + "".join(traceback.format_stack(frame, limit=depth)))
    return "\n".join(parts)


def wait_idle(exp: Explorer, session: ClientSession, timeout: float = 60.0) -> None:
    """Wait until the session has no unfinished jobs and a full, measured and bracketed result for its
    current state; on a time-out the message says which of these is still missing."""
    def missing() -> str:
        active = exp.jobs.active(session.job_client)
        if active:
            return "unfinished jobs: " + ", ".join(f"{j.kind} ({j.status}: {j.message})" for j in active)
        b = session.bundle
        s = session.state
        if b is None:
            return "no result yet"
        if b.measures is None:
            return "the result has no measures"
        if b.result.design != s.design:
            return f"the result is for another design ({b.result.design} against {s.design})"
        if b.result.settings.orientation != (s.pose.psi, s.pose.theta, s.pose.phi):
            return "the result is for another orientation"
        if b.result.settings.voxel != s.voxel:
            return f"the result is for voxel {b.result.settings.voxel}, not {s.voxel}"
        info = session.ctx.ws_info
        if info is None or info.preview is not False or info.measures is None:
            return "the numbers shown are a preview or have no measures"
        if b.bracket is None and b.result.settings.joints.min_distance <= 0.0:
            return "no certified bracket yet"
        return ""

    deadline = time.monotonic() + timeout * DEADLINE_SCALE
    while (why := missing()) and time.monotonic() < deadline:
        time.sleep(0.02)
    if why:
        raise AssertionError(f"timed out after {timeout * DEADLINE_SCALE:g} s waiting for the session to become idle: "
                             f"{why}")
