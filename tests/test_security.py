"""Security of the explorer link: values are text, never markup; the page never talks to another server.

* :func:`paraspace.app.textsafe.md_text` is checked with an independent CommonMark renderer
  (markdown-it-py, HTML enabled like viser's markdown panel): no payload becomes an element.
* :func:`paraspace.app.explorer.pagehook.page_refusal` and the gate on the real explorer's HTTP port:
  only the explorer's own keys reach the page, plain-text refusals, CSP on the page.
* In a real Chromium: links carrying HTML/script payloads in every field run no script, open no
  dialog and add no element of theirs; a ``websocket=`` link never connects to a stand-in server
  on another loopback port, and the served page cannot open one either (CSP).
* The explorer obeys the API's grid limit whatever a link asks for.
"""

from __future__ import annotations

import os
import socket
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Iterator

import pytest
from markdown_it import MarkdownIt

from paraspace.app.explorer import Explorer
from paraspace.app.explorer.pagehook import CONTENT_SECURITY_POLICY, MAX_QUERY_CHARS, page_refusal
from paraspace.app.textsafe import md_text, plain_text
from paraspace.app.urlstate import known_keys

PAYLOADS = [
    '<iframe srcdoc="<script>parent.__pwned=1</script>">',
    "<img src=x onerror=window.__pwned=1>",
    "<script>window.__pwned=1</script>",
    "[click](javascript:window.__pwned=1)",
    "![x](javascript:window.__pwned=1)",
    "<svg/onload=window.__pwned=1>",
    "&lt;script&gt;window.__pwned=1&lt;/script&gt;",
    "**bold** _it_ `code` # head\n- list\n> quote",
    "http://evil.example/x",
    "<a href='javascript:window.__pwned=1'>x</a>",
]


# ----- escaping ---------------------------------------------------------------------------------

@pytest.mark.parametrize("payload", PAYLOADS)
def test_md_text_renders_as_exactly_its_text(payload: str) -> None:
    html = MarkdownIt("commonmark", {"html": True}).enable("table").render(md_text(payload))
    inner = html.strip()
    assert inner.startswith("<p>") and inner.endswith("</p>") and inner.count("<") == 2, inner
    # the paragraph's text, unescaped, is the payload's text (whitespace folded)
    import html as html_mod

    assert html_mod.unescape(inner[3:-4]) == plain_text(payload)


def test_plain_text_bounds_length_and_folds_control_characters() -> None:
    out = plain_text("a\nb\r\nc\x00d\u2028e" + "x" * 1000, max_chars=50)
    assert len(out) == 50 and out.endswith("…") and out.startswith("a b c d e")


# ----- the HTTP gate ----------------------------------------------------------------------------

def test_page_refusal_allows_only_explorer_keys() -> None:
    assert page_refusal("/", "") is None
    assert page_refusal("/", "a=60&d_s=40&view=top&voxel=2") is None
    assert page_refusal("/", "view=%3Cscript%3E") is None  # bad values are the explorer's to report
    for query in ("websocket=ws://127.0.0.1:9", "web%73ocket=ws://x", "a=60&playbackPath=/x.viser",
                  "darkMode=1", "a=1&A=2"):
        status, text = page_refusal("/", query)  # type: ignore[misc]
        assert status == 400 and "does not accept" in text
    status, text = page_refusal("/", "a=60&websocket=ws://x&view=top")  # type: ignore[misc]
    assert "'websocket'" in text and "/?a=60&view=top" in text and "ws://x" not in text
    status, _ = page_refusal("/", "a=" + "1" * (MAX_QUERY_CHARS + 1))  # type: ignore[misc]
    assert status == 414


@pytest.fixture(scope="module")
def explorer() -> Iterator[Explorer]:
    exp = Explorer("127.0.0.1", 0).start()
    exp.warm.wait(120)
    yield exp
    exp.stop()


def _get(url: str) -> tuple[int, dict[str, str], bytes]:
    try:
        with urllib.request.urlopen(url, timeout=10) as r:
            return r.status, dict(r.headers), r.read()
    except urllib.error.HTTPError as err:
        return err.code, dict(err.headers), err.read()


def test_explorer_port_refuses_foreign_keys_and_sends_csp(explorer: Explorer) -> None:
    status, headers, body = _get(explorer.url + "?a=60&websocket=ws://127.0.0.1:9/")
    assert status == 400
    assert headers["Content-Type"].startswith("text/plain") and headers["X-Content-Type-Options"] == "nosniff"
    assert b"websocket" in body and b"<" not in body
    status, headers, body = _get(explorer.url + "?" + urllib.parse.urlencode({"view": PAYLOADS[0]}))
    assert status == 200
    assert headers["Content-Security-Policy"] == CONTENT_SECURITY_POLICY
    assert b"<title>paraspace</title>" in body
    status, headers, body = _get(explorer.url + "?a=" + "9" * 20000)  # over websockets' default 8 KiB line
    assert status == 414 and headers["Content-Type"].startswith("text/plain") and b"4,096" in body


def test_explorer_obeys_the_grid_limit(explorer: Explorer) -> None:
    from explorer_client import FakeBrowser, wait_for  # tests/ (pytest's prepend import mode)

    old = explorer.max_voxels
    explorer.max_voxels = 200_000
    try:
        b = FakeBrowser(explorer, "voxel=1")
        try:
            s = b.session
            wait_for(lambda: "not started" in s.panels.status.content, 10.0, "the refusal")
            text = s.panels.status.content.replace("\\", "")
            assert "voxel" in text and "200,000" in text
            assert s.workspace_controller.job is None  # nothing was queued
        finally:
            b.close()
    finally:
        explorer.max_voxels = old


# ----- a real browser -----------------------------------------------------------------------------

CHROMIUM = "/usr/bin/chromium"
browser_only = pytest.mark.skipif(not os.path.exists(CHROMIUM), reason=f"{CHROMIUM} is missing")


class StandIn:
    """A TCP server on another loopback port that records every connection (a stand-in for an
    attacker's websocket server)."""

    def __init__(self) -> None:
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(16)
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.connections = 0
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while not self.stop.is_set():
            try:
                conn, _ = self.sock.accept()
            except OSError:
                continue
            self.connections += 1
            conn.close()

    def close(self) -> None:
        self.stop.set()
        self.thread.join(2)
        self.sock.close()


@browser_only
@pytest.mark.browser
@pytest.mark.slow
def test_links_with_payloads_run_no_script_and_never_leave_the_server(explorer: Explorer) -> None:
    from explorer_client import wait_for
    from playwright.sync_api import sync_playwright

    stand_in = StandIn()
    args = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
            "--no-first-run", "--disable-sync"]
    try:
        with sync_playwright() as p:
            b = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=args)
            ctx = b.new_context(viewport={"width": 1200, "height": 800})
            dialogs: list[str] = []
            page = ctx.new_page()
            page.on("dialog", lambda d: (dialogs.append(d.message), d.dismiss()))
            # 1. every explorer field carries a payload; the page loads, shows the messages as text
            keys = [k for k in known_keys()]
            for i in range(0, len(keys), 16):  # three pages (key k carries payload k mod 10 whatever the page)
                chunk = keys[i:i + 16]
                query = urllib.parse.urlencode({k: PAYLOADS[(i + j) % len(PAYLOADS)] for j, k in enumerate(chunk)})
                before = set(explorer.sessions)
                page.goto(explorer.url + "?" + query)
                page.wait_for_function("() => !document.body.innerText.includes('Connecting...')", timeout=30000)
                session = wait_for(lambda: next((s for cid, s in list(explorer.sessions.items())
                                                 if cid not in before and s.ready.is_set()), None), 30, "session")
                wait_for(lambda: session.panels.url_messages.visible, 10, "the link's messages")
                page.wait_for_function("() => document.body.innerText.includes('The link had problems')",
                                       timeout=15000)
                time.sleep(0.5)
                assert page.evaluate("() => window.__pwned === undefined")
                found = page.evaluate("""() => ({
                    iframes: document.querySelectorAll('iframe').length,
                    imgs: [...document.querySelectorAll('img')].filter(e => e.getAttribute('src') === 'x').length,
                    svgOnload: document.querySelectorAll('svg[onload]').length,
                    jsLinks: [...document.querySelectorAll('a')].filter(a => (a.getAttribute('href') || '').startsWith('javascript')).length,
                    scripts: [...document.querySelectorAll('script')].filter(s => s.textContent.includes('__pwned')).length,
                })""")
                assert found == {"iframes": 0, "imgs": 0, "svgOnload": 0, "jsLinks": 0, "scripts": 0}, (chunk, found)
            # the payload itself is on screen as literal text (viser's client rewrites the address
            # bar with decoded values on connect, which cuts values at '#' or '&'; this one has neither)
            page.goto(explorer.url + "?" + urllib.parse.urlencode({"view": "<script>window.__pwned=1</script>"}))
            page.wait_for_function("() => document.body.innerText.includes('The link had problems')", timeout=30000)
            assert "view = '<script>window.__pwned=1</script>' is invalid" in page.evaluate("() => document.body.innerText")
            assert page.evaluate("() => window.__pwned === undefined")
            assert dialogs == []
            assert page.title() == "paraspace"
            # 2. a websocket= link is refused before the page loads: nothing connects elsewhere
            resp = page.goto(explorer.url + f"?a=60&websocket=ws://127.0.0.1:{stand_in.port}")
            assert resp is not None and resp.status == 400
            assert "does not accept" in page.evaluate("() => document.body.innerText")
            # 3. the served page itself may not open a connection to another server (CSP)
            page.goto(explorer.url + "?a=60")
            page.wait_for_function("() => !document.body.innerText.includes('Connecting...')", timeout=30000)
            blocked = page.evaluate(f"""() => new Promise(res => {{
                try {{ const ws = new WebSocket('ws://127.0.0.1:{stand_in.port}/');
                       ws.onerror = () => res('error'); ws.onopen = () => res('open'); }}
                catch (e) {{ res('blocked: ' + e.name); }}
                setTimeout(() => res('timeout'), 3000); }})""")
            time.sleep(0.5)
            assert blocked != "open"
            assert stand_in.connections == 0
            # the page's own connection works (same origin) and the explorer is usable
            assert "Connecting..." not in page.evaluate("() => document.body.innerText")
            b.close()
    finally:
        stand_in.close()


# ----- short links (REST API over real HTTP) ------------------------------------------------------

@pytest.fixture(scope="module")
def api_url() -> Iterator[str]:
    from paraspace.app.api import create_api
    from paraspace.app.jobs import JobManager
    from paraspace.app.serve import start_api

    jobs = JobManager(max_workers=1)
    srv = start_api(create_api(jobs, explorer_url="http://127.0.0.1:9999"), "127.0.0.1", 0)
    yield srv.url
    jobs.shutdown(wait=False)
    srv.stop()


@pytest.mark.parametrize("extra", ["websocket=ws://127.0.0.1:9/", "playbackPath=/x.viser", "darkMode=1"])
def test_short_links_accept_only_explorer_keys(api_url: str, extra: str) -> None:
    import httpx

    with httpx.Client(base_url=api_url, timeout=30.0, follow_redirects=False) as http:
        key = extra.split("=")[0]
        r = http.get(f"/s?a=60&{extra}")
        assert r.status_code == 422 and "location" not in r.headers
        assert any(key in item["message"] for item in r.json()["detail"])
        r = http.post("/api/v1/links", json={"query": f"a=60&{extra}"})
        assert r.status_code == 422
        ok = http.post("/api/v1/links", json={"query": "a=60&view=top"})
        assert ok.status_code == 200
        r = http.get(ok.json()["path"])
        assert r.status_code == 307 and r.headers["location"] == "http://127.0.0.1:9999/?a=60&view=top"


# ----- a bounded fuzz of explorer links over real HTTP ---------------------------------------------

VISER_KEYS = ["websocket", "playbackPath", "darkMode", "hideViserLogo", "initialCameraPosition",
              "initialCameraLookAt", "initialCameraUp", "initialCameraFov", "initialCameraNear",
              "initialCameraFar", "showStats", "fixedDpr", "logCamera", "dummyWindowDimensions"]


def test_fuzzed_links_are_answered_safely(explorer: Explorer) -> None:
    """300 generated links (explorer keys, every viser key, junk keys; HTML/script/markdown payloads,
    numbers, long and odd values) against the explorer's port: each gets 200 (the page) or a
    plain-text 400/414 that never echoes markup, and for each page the messages the explorer would
    show render as text (markdown-it, HTML enabled) with no element from the link."""
    import random

    import httpx

    rng = random.Random(20261123)
    keys = list(known_keys()) + VISER_KEYS + ["bogus", "A", "a ", "<b>", "x[]"]
    values = PAYLOADS + ["60", "-0", "1e309", "nan", "", "%zz", "ws://127.0.0.1:9", "9" * 300,
                         "centered", "top", "<b>bold</b>", "\u202e\u0000x"]
    md = MarkdownIt("commonmark", {"html": True})
    from paraspace.app.urlstate import parse_query

    statuses: dict[int, int] = {}
    with httpx.Client(base_url=explorer.url, timeout=20) as http:
        for _ in range(300):
            pairs = [(rng.choice(keys), rng.choice(values)) for _ in range(rng.randint(0, 6))]
            query = urllib.parse.urlencode(pairs)
            r = http.get("/?" + query)
            statuses[r.status_code] = statuses.get(r.status_code, 0) + 1
            if r.status_code == 200:
                assert r.headers["content-security-policy"] == CONTENT_SECURITY_POLICY
                assert all(k in known_keys() for k, _ in pairs)
                _, messages = parse_query(query)
                for m in messages:
                    html = md.render(md_text(m)).strip()
                    assert html.count("<") == 2, (m, html)
            else:
                assert r.status_code in (400, 414), r.status_code
                assert r.headers["content-type"].startswith("text/plain")
                assert "<" not in r.text.split("Only the explorer's own parameters")[0].replace("'<b>'", "")
    print(f"\nlink fuzz: 300 links, status codes {dict(sorted(statuses.items()))}")
    assert statuses.get(200, 0) > 20 and statuses.get(400, 0) > 20
