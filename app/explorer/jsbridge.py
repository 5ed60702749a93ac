"""The only place that touches viser's private API: running JavaScript in one browser.

viser 1.1.1 offers no public way to read or write the page URL (notes §4). Its web client runs any
``RunJavascriptMessage`` it receives with ``new Function(source)()`` (that is how Plotly is set
up), and the public ``client.local_storage`` reads a value back. Together they form a small bridge:

* :func:`read_location` makes the page store ``location.search`` and the page's base URL in
  localStorage and reads them back (one round trip, about 0.1 s on localhost);
* :func:`wait_drawn` waits until the page has drawn a scene node (the first shell, before the plots'
  plotly.js is sent: :mod:`paraspace.app.explorer.lazy_plot`);
* :func:`replace_query` rewrites the address bar with ``history.replaceState`` (no reload);
* :func:`copy_to_clipboard` tries ``navigator.clipboard`` (may be refused outside a secure context;
  the explorer always shows the link in a text field as well);
* :func:`show_panel` lets the page show its control panel once the explorer's GUI is there (the
  page keeps it hidden until then: :data:`paraspace.app.pagehook.PANEL_WAIT`).

The message is queued on the **client's** connection only, never on the server-wide buffer (that
one is persistent and would replay the script to every future browser). Pinned to viser 1.1.1;
``tests/test_explorer.py`` and ``tests/test_browser.py`` cover these functions. (The other use of
viser internals is :mod:`paraspace.app.pagehook`, the gate on the page request.)
"""

from __future__ import annotations

import json
import time

import viser
from viser import _messages

#: localStorage namespace prefix that viser's ``LocalStorageHandle`` adds in the browser.
VISER_STORAGE_PREFIX = "viser-user:"


def run_js(client: viser.ClientHandle, source: str) -> None:
    """Run ``source`` in this client's page (errors are caught and logged in the browser console)."""
    wrapped = f"try {{ {source} }} catch (e) {{ console.error('paraspace bridge:', e); }}"
    client._websock_connection.queue_message(_messages.RunJavascriptMessage(source=wrapped))  # noqa: SLF001


def _round_trip(client: viser.ClientHandle, key: str, source: str, timeout: float,
                poll: float | None = None) -> str | None:
    """Run ``source`` (which stores its answer under the JS variable ``k``'s localStorage key) and
    read the answer back; ``None`` if the browser did not answer within ``timeout`` seconds.
    ``poll``: the script answers later (after frames, a promise), so the key is read again every
    ``poll`` seconds until it is there; without it, the first read is the answer (a script that
    answers at once: the read queued after it sees the key)."""
    run_js(client, f"var k = {json.dumps(VISER_STORAGE_PREFIX + key)};" + source)
    deadline = time.monotonic() + timeout
    try:
        raw = client.local_storage.get_item(key, timeout=timeout)
        while raw is None and poll is not None and time.monotonic() + poll < deadline:
            time.sleep(poll)
            raw = client.local_storage.get_item(key, timeout=max(deadline - time.monotonic(), 0.01))
    except (TimeoutError, RuntimeError):
        return None
    try:
        client.local_storage.remove_item(key)
    except Exception:  # noqa: BLE001 - the client may be gone already
        pass
    return raw


def read_location(client: viser.ClientHandle, timeout: float = 5.0) -> tuple[str, str] | None:
    """The page's ``(location.search, origin + pathname)``, or ``None`` if the browser did not answer.

    Blocks for one round trip: call it from a thread-pool callback (a ``def`` callback), never from
    an ``async def`` one.
    """
    raw = _round_trip(client, f"paraspace_location_{client.client_id}", (
        "localStorage.setItem(k, JSON.stringify({search: window.location.search, "
        "base: window.location.origin + window.location.pathname}));"), timeout)
    if raw is None:
        return None
    try:
        data = json.loads(raw)
        return str(data.get("search", "")), str(data.get("base", ""))
    except (ValueError, AttributeError):
        return None


def wait_drawn(client: viser.ClientHandle, node: str, timeout: float = 8.0, give_up: float = 5.0) -> bool | None:
    """Wait until the page has drawn the scene node ``node``: the node has loaded children (a GLB is
    parsed asynchronously after its message) and the next animation frame has started. ``True``:
    drawn; ``False``: the page gave up after ``give_up`` seconds (no such node with children, or a
    viser client without ``window.__viserMutable``, the scene internals viser 1.1.1 exposes for
    end-to-end tests); ``None``: no answer within ``timeout`` seconds (a hidden tab draws no frames).
    Blocks, polling the answer every 50 ms (a ``def`` callback or a thread of its own)."""
    raw = _round_trip(client, f"paraspace_drawn_{client.client_id}", (
        f"var n = {json.dumps(node)}; var t0 = performance.now();"
        "function go() { var M = window.__viserMutable; var o = M && M.nodeRefFromName && M.nodeRefFromName[n];"
        " if (o && o.children && o.children.length > 0) {"
        "  requestAnimationFrame(function () { localStorage.setItem(k, '1'); }); return; }"
        f" if (performance.now() - t0 > {1000.0 * give_up:.0f}) {{ localStorage.setItem(k, '0'); return; }}"
        " requestAnimationFrame(go); }"
        "requestAnimationFrame(go);"), timeout, poll=0.05)
    return None if raw is None else raw == "1"


def replace_query(client: viser.ClientHandle, query: str) -> None:
    """Set the address bar to ``?query`` (same path, no reload, no history entry)."""
    q = ("?" + query) if query else ""
    run_js(client, (
        f"var q = {json.dumps(q)};"
        "if (window.location.search !== q) {"
        " window.history.replaceState(window.history.state, '', window.location.pathname + q + window.location.hash); }"
    ))


#: Seconds the page gets to say whether it copied to the clipboard (:func:`copy_to_clipboard`).
CLIPBOARD_SECONDS = 3.0


def copy_to_clipboard(client: viser.ClientHandle, text: str, timeout: float = CLIPBOARD_SECONDS) -> bool | None:
    """Try to put ``text`` on the clipboard of this client's browser and report what happened:
    ``True`` copied, ``False`` refused by the browser (e.g. not a secure context, no permission),
    ``None`` no answer within ``timeout`` seconds. The page answers when the clipboard's promise
    settles, after the first read of the answer has usually arrived, so the answer is polled (until
    2026-12-05 it was read once, and a link the browser had copied was reported as refused). Blocks
    (a ``def`` callback)."""
    raw = _round_trip(client, f"paraspace_clip_{client.client_id}", (
        f"var t = {json.dumps(text)};"
        "function put(v) { localStorage.setItem(k, v); }"
        "if (navigator.clipboard && navigator.clipboard.writeText) {"
        " navigator.clipboard.writeText(t).then(function () { put('ok'); },"
        " function (e) { console.warn('clipboard:', e); put('refused'); }); }"
        " else { put('refused'); }"), timeout, poll=0.05)
    return None if raw is None else raw == "ok"


#: The class on the page's ``<html>`` element that hides viser's panel while the explorer's GUI is
#: being built (set by the page itself: :data:`paraspace.app.pagehook.PANEL_WAIT`).
PANEL_WAIT_CLASS = "paraspace-wait"


def show_panel(client: viser.ClientHandle, marker: str = "Numbers") -> None:
    """Show the page's control panel (hidden until the explorer's GUI has arrived, so that viser's
    own panel -- connection, "Save Canvas", scene tree -- never flashes before it). The script
    arrives after the GUI messages queued before it, but the browser may run it before it has
    drawn them: it waits, 16 ms at a time (at most 5 s), until the panel shows ``marker`` (a
    label of the explorer's GUI)."""
    run_js(client, "(function(){var t0=Date.now();function go(){"
                   "var p=document.querySelector('[data-testid=\"floating-panel\"]');"
                   f"if((p&&p.textContent.indexOf({json.dumps(marker)})>=0)||Date.now()-t0>5000)"
                   f"{{document.documentElement.classList.remove({json.dumps(PANEL_WAIT_CLASS)});return;}}"
                   "setTimeout(go,16);}go();})();")
