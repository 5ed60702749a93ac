"""The explorer page's HTTP gate: what a link may carry, and what the page may connect to.

viser's web client acts on some query keys of its own page URL before our server sees anything:
``?websocket=ws://elsewhere`` connects the page to another server (which can then draw any GUI and
run script in the explorer's origin), ``?playbackPath=`` loads a foreign recording. viser 1.1.1
serves its page from a ``process_request`` hook of its websocket server and offers no public way to
filter requests, so this module wraps that hook (the second and last place, with
:mod:`paraspace.app.jsbridge`, that touches viser's private API; viser is pinned to 1.1.1 and
``tests/test_security.py`` covers the wrapper). For every plain HTTP request (the websocket upgrade
passes untouched):

1. a query longer than :data:`MAX_QUERY_CHARS` is refused with 414 (the websockets server's own
   limit on a request line is raised from 8 KiB to :data:`MAX_REQUEST_LINE` so that such a link
   gets this answer instead of a dropped connection; a request beyond even that is dropped by
   websockets, and its "opening handshake failed" traceback is kept out of the log by
   :class:`_QuietHandshakeFailures`);
2. a query carrying any key that is not one of the explorer's own keys
   (:func:`paraspace.app.urlstate.link_keys`) is refused with 400: the page is never served with
   a key that viser's client could act on. The answer is plain text (never HTML), names the
   refused keys (cut and quoted) and gives the same link without them;
3. the page itself is served with a ``Content-Security-Policy`` whose ``connect-src 'self'`` keeps
   the page from opening a websocket (or fetch) to any other server, even if a future client
   learned another way to be pointed elsewhere; its ``<title>`` says paraspace, and it hides
   viser's own control panel until the explorer's GUI has arrived (:data:`PANEL_WAIT`), and its
   number boxes apply a typed value only on Enter, leaving the box or a pause (:data:`TYPING_GATE`).

Before all of this, every request (page or websocket upgrade) must pass the host and origin rules
of :mod:`paraspace.app.hostcheck` (DNS rebinding, cross-site websockets): a refused one gets a
plain-text 403. The rules are set per listening port by the explorer (:func:`set_policy`); a port
without one gets the loopback-only default.

The refusal is decided by :func:`page_refusal`, a pure function of the request's path and query.
"""

from __future__ import annotations

import gzip
import logging
import threading
import urllib.parse
from collections.abc import Callable
from typing import Any

from websockets.datastructures import Headers
from websockets.http11 import Response

from ..hostcheck import HostPolicy
from ..urlstate import link_keys
from .jsbridge import PANEL_WAIT_CLASS

__all__ = ["MAX_QUERY_CHARS", "MAX_REQUEST_LINE", "CONTENT_SECURITY_POLICY", "page_refusal", "install",
           "set_policy", "clear_policy"]

#: Longest query string of a page request (a full explorer link is about 300 characters).
MAX_QUERY_CHARS = 4096
#: Longest request line the explorer's server reads (websockets' default is 8 KiB).
MAX_REQUEST_LINE = 262144
#: Sent with the page: the page may connect (websocket, fetch) only to the server it came from.
CONTENT_SECURITY_POLICY = ("connect-src 'self' blob: data:; object-src 'none'; base-uri 'none'; "
                           "frame-ancestors 'self'; form-action 'none'")
#: Longest time the page hides its control panel while waiting for the explorer's GUI, milliseconds.
PANEL_WAIT_MS = 20_000
#: Put into the page's head: until the explorer's GUI has arrived (the server then runs
#: :func:`paraspace.app.jsbridge.show_panel`), viser's floating panel is hidden, so its own
#: panel (connection, "Save Canvas", scene tree) does not flash before the explorer's; after
#: :data:`PANEL_WAIT_MS` it is shown whatever happened.
PANEL_WAIT = (
    f'<style>html.{PANEL_WAIT_CLASS} [data-testid="floating-panel"]{{visibility:hidden}}</style>'
    f'<script>document.documentElement.classList.add("{PANEL_WAIT_CLASS}");setTimeout(function(){{'
    f'document.documentElement.classList.remove("{PANEL_WAIT_CLASS}");}}, {PANEL_WAIT_MS});</script>').encode()
#: Longest pause between keystrokes in a number box before its value is applied, milliseconds.
TYPING_PAUSE_MS = 800
#: Put into the page's head: a number box (Mantine's NumberInput, inside every slider) applies what
#: is typed only on Enter, on leaving the box, or after a pause of :data:`TYPING_PAUSE_MS` - never
#: a keystroke's prefix ("120" typed key by key never applies 12). The keystrokes' ``input`` events
#: are held at the document (capture phase, before React's root listener sees them); on Enter, on
#: the ``change`` event the browser sends when Tab moves the focus on (before ``blur``: React took it
#: as the box's value and put the held text back to the last applied one, so "a = 120" then Tab
#: left a = 50), on ``blur`` or after the pause the box's whole text goes to React in two ``input``
#: events: an empty box (not a number: nothing is applied), then the text, which it applies. The
#: number box diffs each text against the one it last saw, and a single event from "0" to a text
#: two or more characters longer that ends the same ("0" -> "100", "-10", "101") was undone and
#: never sent (found typing a pose on 2026-12-05; "0" -> "50" and "20" -> "200" went through); from
#: an empty box every text is new. The box's ``focusout`` never reaches React: on it Mantine clamps
#: the value to the track's ends and sends that end, before the server's wider track (which a value
#: beyond it gets, :func:`paraspace.app.explorer.typed_values.hold_typed_values`) has arrived: "a =
#: 120" typed and then a click elsewhere applied a = 100, and an angle step of 2 typed below the
#: track's 2.5 applied 2.5 (2026-12-05, typing key by key in headless Chromium).
TYPING_GATE = (
    "<script>(function(){var P=" + str(TYPING_PAUSE_MS) + ",q=new Map();"
    "var S=Object.getOwnPropertyDescriptor(HTMLInputElement.prototype,'value').set;"
    "function own(e){return e&&e.classList&&e.classList.contains('mantine-NumberInput-input');}"
    "function fire(e){e.dispatchEvent(new Event('input',{bubbles:true}));}"
    "function go(e){var t=q.get(e);if(t===undefined)return;clearTimeout(t);q.delete(e);e.__psGo=true;"
    "try{var v=e.value;S.call(e,'');fire(e);S.call(e,v);fire(e);}finally{e.__psGo=false;}}"
    "document.addEventListener('input',function(v){var e=v.target;if(!own(e)||e.__psGo)return;"
    "v.stopImmediatePropagation();var t=q.get(e);if(t!==undefined)clearTimeout(t);"
    "q.set(e,setTimeout(function(){go(e);},P));},true);"
    "document.addEventListener('keydown',function(v){if(v.key==='Enter'&&q.has(v.target))go(v.target);},true);"
    "document.addEventListener('change',function(v){if(q.has(v.target))go(v.target);},true);"
    "document.addEventListener('blur',function(v){if(q.has(v.target))go(v.target);},true);"
    "document.addEventListener('focusout',function(v){var e=v.target;if(!own(e))return;if(q.has(e))go(e);"
    "v.stopImmediatePropagation();},true);"
    "})();</script>").encode()
#: How long viser's "Software WebGL rendering detected" notice stays the first time, milliseconds.
WEBGL_NOTICE_MS = 8000
#: The browser's localStorage key saying that it was shown viser's software-WebGL notice ("1").
WEBGL_NOTICE_KEY = "paraspace.webglNoticeShown"
#: Put into the page's head: viser's software-WebGL notice (it covers the scene's top left corner)
#: is shown once per browser for :data:`WEBGL_NOTICE_MS`, then closed; on later loads it is closed
#: as soon as it appears (the browser remembers in its localStorage that it was told).
WEBGL_NOTICE = (
    "<script>(function(){var K='" + WEBGL_NOTICE_KEY + "',seen=false;"
    "try{seen=localStorage.getItem(K)==='1';}catch(e){}"
    "function close(n){var b=n.querySelector('.mantine-Notification-closeButton');if(b)b.click();}"
    "new MutationObserver(function(){document.querySelectorAll('.mantine-Notification-root').forEach("
    "function(n){if(n.__ps||n.textContent.indexOf('Software WebGL')<0)return;n.__ps=true;"
    "if(seen){close(n);return;}seen=true;try{localStorage.setItem(K,'1');}catch(e){}"
    "setTimeout(function(){close(n);}," + str(WEBGL_NOTICE_MS) + ");});})"
    ".observe(document.documentElement,{childList:true,subtree:true});})();</script>").encode()
#: Put into the page's head: viser's modal windows (the plots' "Open large") as wide as the window
#: allows instead of Mantine's 440 px.
WIDE_MODALS = b"<style>.mantine-Modal-content{flex:0 0 min(92vw,1400px)!important;max-width:92vw!important}</style>"
#: Replacements applied to viser's page (its HTML is otherwise served as is).
PAGE_EDITS: tuple[tuple[bytes, bytes], ...] = (
    (b"<title>Viser</title>", b"<title>paraspace</title>" + PANEL_WAIT + TYPING_GATE + WEBGL_NOTICE + WIDE_MODALS),)

_KNOWN = frozenset(link_keys())


def _quote(key: str) -> str:
    return repr(key if len(key) <= 40 else key[:39] + "…")


def page_refusal(path: str, query: str) -> tuple[int, str] | None:
    """``None`` if a page request for ``path?query`` may be served, else ``(status, text)``.

    The rule: the query is at most :data:`MAX_QUERY_CHARS` characters and every key (decoded the
    way the browser's ``URLSearchParams`` decodes it) is one of the explorer's own keys.
    """
    if len(query) > MAX_QUERY_CHARS:
        return 414, (f"paraspace explorer: this link's query has {len(query):,} characters; links are "
                     f"limited to {MAX_QUERY_CHARS:,}. An explorer link holds about 300: check the link.")
    try:
        pairs = urllib.parse.parse_qsl(query, keep_blank_values=True)
    except ValueError:
        return 400, "paraspace explorer: this link's query could not be read."
    bad: list[str] = []
    for key, _ in pairs:
        if key not in _KNOWN and key not in bad:
            bad.append(key)
    if not bad:
        return None
    kept = urllib.parse.urlencode([(k, v) for k, v in pairs if k in _KNOWN], safe=",")
    clean = (path or "/") + (f"?{kept}" if kept else "")
    named = ", ".join(_quote(k) for k in bad[:8]) + (f" and {len(bad) - 8} more" if len(bad) > 8 else "")
    return 400, (f"paraspace explorer: this link carries parameters the explorer does not accept: {named}. "
                 "Only the explorer's own parameters are allowed (" + ", ".join(link_keys()) + ").\n"
                 f"The same link without them (on this server): {clean}\n")


_policies: dict[int, HostPolicy] = {}
_DEFAULT_POLICY = HostPolicy()


def set_policy(port: int, policy: HostPolicy) -> None:
    """The host and origin rules of the explorer listening on ``port``."""
    _policies[int(port)] = policy


def clear_policy(port: int) -> None:
    """Forget the rules of ``port`` (its explorer stopped)."""
    _policies.pop(int(port), None)


def _policy_of(connection: Any) -> HostPolicy:
    try:
        port = int(connection.local_address[1])
    except (AttributeError, IndexError, TypeError, ValueError):
        return _DEFAULT_POLICY
    return _policies.get(port, _DEFAULT_POLICY)


def _text_response(status: int, text: str) -> Response:
    reason = {400: "Bad Request", 403: "Forbidden", 414: "URI Too Long"}.get(status, "Error")
    body = text.encode("utf-8")
    return Response(status, reason, Headers({
        "Content-Type": "text/plain; charset=utf-8", "Content-Length": str(len(body)),
        "X-Content-Type-Options": "nosniff", "Content-Security-Policy": "default-src 'none'",
        "Cache-Control": "no-store", "Connection": "close"}), body)


class _PageEditor:
    """Applies :data:`PAGE_EDITS` to viser's (cached, possibly gzipped) page bytes, once each."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._done: dict[int, tuple[bytes | bytearray, bytes]] = {}  # id(original) -> (original, edited)

    def edited(self, body: bytes | bytearray, gzipped: bool) -> bytes:
        with self._lock:
            hit = self._done.get(id(body))
            if hit is not None and hit[0] is body:
                return hit[1]
        html = gzip.decompress(body) if gzipped else bytes(body)
        for old, new in PAGE_EDITS:
            html = html.replace(old, new, 1)
        out = gzip.compress(html) if gzipped else html
        with self._lock:
            if len(self._done) > 8:
                self._done.clear()
            self._done[id(body)] = (body, out)
        return out


_EDITOR = _PageEditor()


def _guarded(inner: Callable[[Any, Any], Response | None]) -> Callable[[Any, Any], Response | None]:
    def process_request(connection: Any, request: Any) -> Response | None:
        why = _policy_of(connection).refusal(request.headers.get("Host"), request.headers.get("Origin"))
        if why is not None:
            return _text_response(403, f"paraspace explorer: {why}\n")
        if str(request.headers.get("Upgrade", "")).lower() == "websocket":
            return inner(connection, request)
        path, _, query = request.path.partition("?")
        refusal = page_refusal(path, query)
        if refusal is not None:
            return _text_response(*refusal)
        resp = inner(connection, request)
        if resp is None or resp.status_code != 200:
            return resp
        if str(resp.headers.get("Content-Type", "")).startswith("text/html"):
            gz = resp.headers.get("Content-Encoding") == "gzip"
            body = _EDITOR.edited(resp.body, gz)
            headers = Headers(resp.headers)  # a multidict: assignment appends, so delete first
            # websockets closes the connection after any plain HTTP answer: say so (keep-alive clients)
            for name, value in (("Content-Length", str(len(body))),
                                ("Content-Security-Policy", CONTENT_SECURITY_POLICY),
                                ("X-Content-Type-Options", "nosniff"), ("Referrer-Policy", "no-referrer"),
                                ("Connection", "close")):
                if name in headers:
                    del headers[name]
                headers[name] = value
            resp = Response(resp.status_code, resp.reason_phrase, headers, body)
        return resp

    process_request.__wrapped__ = inner  # type: ignore[attr-defined]
    return process_request


class _Delegate:
    """Attribute access to ``target`` with some attributes replaced."""

    def __init__(self, target: Any, **overrides: Any) -> None:
        self._target = target
        self._overrides = overrides

    def __getattr__(self, name: str) -> Any:
        if name in self._overrides:
            return self._overrides[name]
        return getattr(self._target, name)


class _QuietHandshakeFailures(logging.Filter):
    """Drops websockets' "opening handshake failed" records (a malformed or oversized HTTP request
    from a client: not a server error, and its traceback floods the log)."""

    def filter(self, record: logging.LogRecord) -> bool:
        return record.getMessage() not in ("opening handshake failed", "connection rejected (200 OK)")


_install_lock = threading.Lock()


def install() -> None:
    """Wrap the ``process_request`` hook of every viser server started from now on (idempotent).

    viser's server module calls ``websockets.asyncio.server.serve(..., process_request=...)``
    through its own module-global name ``websockets``; that name (only in viser's module) is
    replaced by a delegate whose ``serve`` wraps the hook with the gate above.
    """
    import websockets.http11
    from viser.infra import _infra  # private: viser is pinned to 1.1.1

    with _install_lock:
        if isinstance(_infra.websockets, _Delegate):
            return
        websockets.http11.MAX_LINE_LENGTH = max(websockets.http11.MAX_LINE_LENGTH, MAX_REQUEST_LINE)
        for name in ("websockets.server", "websockets"):
            logging.getLogger(name).addFilter(_QuietHandshakeFailures())
        real = websockets
        import websockets.asyncio.server as real_server

        def serve(*args: Any, **kwargs: Any) -> Any:
            inner = kwargs.get("process_request")
            if inner is not None:
                kwargs["process_request"] = _guarded(inner)
            return real_server.serve(*args, **kwargs)

        _infra.websockets = _Delegate(  # type: ignore[assignment]  # the module, wrapped
            real, asyncio=_Delegate(real.asyncio, server=_Delegate(real_server, serve=serve)))
