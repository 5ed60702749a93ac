"""Load on the explorer: several concurrent browser sessions on loopback, bounded in count and time.

Two tests, both on a private server:

* ``test_concurrent_sessions_protocol_level``: one :class:`~app.explorer.Explorer`, ``N`` protocol-level
  fake browsers (tests/explorer_client.py), each opened with its own link (its own design ``a``,
  pose ``x`` and ``z``). Every browser moves its pose slider ``z`` (and every few steps its design
  slider ``a``) from its own thread, for at most :data:`DURATION` seconds and :data:`MAX_POSE_MOVES`
  moves. Every browser draws from its own, disjoint, set of values, so a value seen anywhere
  identifies the browser it came from. Measured (printed, never asserted): the latency from sending
  a pose slider update until the server session's state holds it, and until the gizmo's new position
  comes back over the websocket. Asserted: no session's state, result, address bar or scene ever
  held another browser's value (a monitor thread samples every session during the load; each fake
  browser records every gizmo position and address bar it received), and at the end every session
  holds exactly its own last values and shows the workspace of its own last design (volume equal to
  ``compute_workspace`` for that design at the same voxel size).
* ``test_concurrent_real_browsers``: three pages of one headless Chromium (separate contexts), all
  connected at once, each moving a different slider through the GUI (keyboard on the Mantine
  thumb); each page's address bar and each server session reflects only its own change, while the
  REST API (same :class:`~app.jobs.JobManager`) answers ``/health`` (latencies printed).
"""

from __future__ import annotations

import dataclasses
import os
import re
import statistics
import threading
import time
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from explorer_client import FakeBrowser, wait_for, wait_idle  # tests/ (pytest's prepend import mode)

from paraspace.app.api import API_PREFIX, create_api
from paraspace.app.explorer import ClientSession, Explorer
from paraspace.app.jobs import JobManager
from paraspace.app.numfmt import significant
from paraspace.app.serve import start_api
from paraspace.app.urlstate import parse_query
from paraspace.kinematics.design import Design
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
        "--no-first-run", "--disable-sync"]

#: Protocol-level load: browsers, seconds, pose moves per browser, a design move every k pose moves.
N_SESSIONS = 6
DURATION = 8.0
MAX_POSE_MOVES = 150
DESIGN_EVERY = 4
#: Voxel size of every session (>= the preview size: one full computation per design, no preview).
VOXEL = 6.0
#: Longest wait for one echo before the browser gives up (a liveness bound, not a timing check).
ECHO_TIMEOUT = 15.0


def _pct(xs: list[float], p: float) -> float:
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(p / 100 * (len(xs) - 1))))]


def _ms(xs: list[float]) -> str:
    if not xs:
        return "n=0"
    return f"n={len(xs)} p50 {1e3 * statistics.median(xs):.1f} ms, p95 {1e3 * _pct(xs, 95):.1f} ms, " \
           f"max {1e3 * max(xs):.1f} ms"


# ------------------------------------------------------------------------------------------------
# protocol level


class RecordingBrowser(FakeBrowser):
    """A :class:`FakeBrowser` that also records every gizmo position and address bar it receives."""

    def __init__(self, explorer: Explorer, search: str = "") -> None:
        # set before FakeBrowser.__init__: its receive thread starts there
        self.cond = threading.Condition()
        self.gizmo_positions: list[tuple[float, float, float]] = []
        super().__init__(explorer, search)

    def _handle(self, m: dict) -> None:
        super()._handle(m)
        kind = m.get("type")
        if kind == "SetPositionMessage" and m.get("name") == "/gizmo":
            with self.cond:
                self.gizmo_positions.append(tuple(float(v) for v in m["position"]))
                self.cond.notify_all()

    def wait_gizmo(self, pred: Any, start: int, timeout: float) -> bool:
        """Wait until a gizmo position received after index ``start`` satisfies ``pred``."""
        deadline = time.monotonic() + timeout
        with self.cond:
            while True:
                if any(pred(p) for p in self.gizmo_positions[start:]):
                    return True
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self.cond.wait(left)


class Plan:
    """One browser's own, disjoint values: ``a`` and ``z`` on the 0.5 slider grid, a fixed ``x``."""

    def __init__(self, i: int) -> None:
        self.i = i
        self.a_values = [20.0 + 12.0 * i + 0.5 * k for k in range(13)]  # 20 + 12 i ... 26 + 12 i
        self.z_values = [100.0 + 8.0 * i + 0.5 * k for k in range(16)]  # 100 + 8 i ... 107.5 + 8 i
        self.x = -25.0 + 10.0 * i
        self.a0, self.z0 = self.a_values[-1], self.z_values[-1]  # the link's values
        self.link = f"voxel={VOXEL:g}&a={self.a0:g}&x={self.x:g}&z={self.z0:g}"
        self.last_a, self.last_z = self.a0, self.z0
        self.a_set, self.z_set = set(self.a_values), set(self.z_values)

    def owns(self, design: Design, pose: Pose) -> bool:
        """Whether a (design, pose) could only have come from this browser."""
        return (design.a in self.a_set and pose.z in self.z_set and pose.x == self.x
                and design == Design(a=design.a))

    def expected(self) -> tuple[Design, Pose]:
        return Design(a=self.last_a), Pose(x=self.x, z=self.last_z)


@pytest.fixture(scope="module")
def explorer() -> Iterator[Explorer]:
    exp = Explorer("127.0.0.1", 0).start()
    exp.warm.wait(120)
    yield exp
    exp.stop()


def test_concurrent_sessions_protocol_level(explorer: Explorer) -> None:
    plans = [Plan(i) for i in range(N_SESSIONS)]
    browsers: list[RecordingBrowser] = []
    try:
        # opened one after another: a FakeBrowser finds its session as "the new one"
        for plan in plans:
            browsers.append(RecordingBrowser(explorer, plan.link))
        sessions = [b.session for b in browsers]
        assert len({id(s) for s in sessions}) == N_SESSIONS
        assert len({s.client.client_id for s in sessions}) == N_SESSIONS
        for plan, s in zip(plans, sessions):
            assert (s.state.design, s.state.pose) == plan.expected(), "a session did not start from its link"

        violations: list[str] = []
        stop_monitor = threading.Event()
        samples = [0]

        def monitor() -> None:
            """Sample every session's state and result while the load runs."""
            while not stop_monitor.is_set():
                for plan, s in zip(plans, sessions):
                    st = s.state
                    if not plan.owns(st.design, st.pose):
                        violations.append(f"session {plan.i}: state {st.design} {st.pose}")
                    b = s.bundle
                    if b is not None and b.result.design.a not in plan.a_set:
                        violations.append(f"session {plan.i}: result of a = {b.result.design.a}")
                samples[0] += 1
                time.sleep(0.02)

        lat_state: list[list[float]] = [[] for _ in plans]
        lat_echo: list[list[float]] = [[] for _ in plans]
        lost: list[str] = []
        counts = [[0, 0] for _ in plans]  # pose moves, design moves
        t_start = time.monotonic()
        stop_at = t_start + DURATION

        def drive(plan: Plan, b: RecordingBrowser) -> None:
            s = b.session
            z_handle, a_handle = s.panels.pose["z"], s.panels.design["a"]
            k = 0
            while time.monotonic() < stop_at and k < MAX_POSE_MOVES:
                z = plan.z_values[k % len(plan.z_values)]  # cycles; never equal to the previous value
                start = len(b.gizmo_positions)
                t0 = time.perf_counter()
                b.set(z_handle, z)
                plan.last_z = z
                counts[plan.i][0] += 1
                ok = False
                deadline = time.monotonic() + ECHO_TIMEOUT
                while time.monotonic() < deadline:
                    if s.state.pose.z == z:
                        ok = True
                        break
                    time.sleep(0.002)
                if not ok:
                    lost.append(f"session {plan.i}: state never reached z = {z}")
                    return
                lat_state[plan.i].append(time.perf_counter() - t0)
                if not b.wait_gizmo(lambda p, z=z: p[2] == z, start, ECHO_TIMEOUT):
                    lost.append(f"session {plan.i}: no gizmo echo for z = {z}")
                    return
                lat_echo[plan.i].append(time.perf_counter() - t0)
                if k % DESIGN_EVERY == DESIGN_EVERY - 1:  # a design move, not waited for
                    # cycles over all but the link's value: never equal to the previous value
                    a = plan.a_values[(k // DESIGN_EVERY) % (len(plan.a_values) - 1)]
                    b.set(a_handle, a)
                    plan.last_a = a
                    counts[plan.i][1] += 1
                k += 1

        mon = threading.Thread(target=monitor, daemon=True)
        mon.start()
        threads = [threading.Thread(target=drive, args=(p, b), daemon=True) for p, b in zip(plans, browsers)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(DURATION + 3 * ECHO_TIMEOUT)
        load_seconds = time.monotonic() - t_start
        assert not any(t.is_alive() for t in threads), "a driver thread did not finish"

        # every session settles on exactly its own last values and its own workspace
        t_settle = time.monotonic()
        for plan, s in zip(plans, sessions):
            design, pose = plan.expected()
            wait_for(lambda: s.state.design == design and s.state.pose == pose, 30.0,
                     f"session {plan.i} to hold its last values")
        # after the load: when each session shows the full workspace of its last design, and when it
        # has no unfinished job left (its orientation maps included)
        settle_ws = [float("nan")] * len(sessions)
        settle_idle = [float("nan")] * len(sessions)
        settle_errors: list[str] = []

        def settle_one(i: int) -> None:
            s, design = sessions[i], plans[i].expected()[0]
            try:
                wait_for(lambda: s.bundle is not None and s.bundle.result.design == design
                         and (info := s.ctx.ws_info) is not None and info.preview is False
                         and info.measures is not None,
                         90.0, f"session {i}'s last workspace")
                settle_ws[i] = time.monotonic() - t_settle
                wait_idle(explorer, s, timeout=90.0)
                settle_idle[i] = time.monotonic() - t_settle
            except AssertionError as exc:
                settle_errors.append(f"session {i}: {exc}")

        waiters = [threading.Thread(target=settle_one, args=(i,), daemon=True) for i in range(len(sessions))]
        for t in waiters:
            t.start()
        for t in waiters:
            t.join(100.0)
        assert not settle_errors, settle_errors
        time.sleep(0.5)  # a stale job that would still publish has had every chance to
        stop_monitor.set()
        mon.join(5.0)

        total = sum(c[0] for c in counts)
        all_state = [x for v in lat_state for x in v]
        all_echo = [x for v in lat_echo for x in v]
        print(f"\nexplorer load: {N_SESSIONS} fake browsers, {total} pose moves + {sum(c[1] for c in counts)} "
              f"design moves in {load_seconds:.1f} s ({total / load_seconds:.0f} pose moves/s); "
              f"{samples[0]} monitor samples")
        print("  after the load, per session: last design's full workspace on screen in "
              + ", ".join(f"{x:.1f}" for x in settle_ws) + " s; no job left in "
              + ", ".join(f"{x:.1f}" for x in settle_idle) + " s")
        mine = {s.job_client for s in sessions}
        history = [j for j in explorer.jobs.jobs() if j.client in mine]  # the manager keeps the last 256
        for kind in ("workspace", "orientation"):
            js = [j for j in history if j.kind == kind]
            by_status = {st: sum(1 for j in js if j.status == st) for st in ("done", "cancelled", "failed")}
            ran = [j for j in js if j.started is not None and j.finished is not None]
            print(f"  {kind} jobs in the history: {len(js)} {by_status}, {len(ran)} started; of those, queue "
                  f"wait {_ms([j.started - j.created for j in ran])}; run {_ms([j.finished - j.started for j in ran])}")
        print(f"  pose slider -> session state: {_ms(all_state)}")
        print(f"  pose slider -> gizmo echo:    {_ms(all_echo)}")
        for plan in plans:
            print(f"  session {plan.i}: {counts[plan.i][0]:3d} pose / {counts[plan.i][1]:2d} design moves; "
                  f"echo {_ms(lat_echo[plan.i])}")

        assert not lost, lost
        assert not violations, violations[:5]
        cache: dict[float, float] = {}
        for plan, b, s in zip(plans, browsers, sessions):
            design, pose = plan.expected()
            assert s.state.design == design and s.state.pose == pose
            assert s.panels.design["a"].value == design.a and s.panels.pose["z"].value == pose.z
            assert s.panels.pose["x"].value == plan.x
            # the workspace on screen is the one of its own last design
            assert s.bundle.result.design == design
            assert s.bundle.result.settings.voxel == VOXEL
            assert s.bundle.result.settings.orientation == (0.0, 0.0, 0.0)
            if design.a not in cache:
                cache[design.a] = compute_workspace(design, WorkspaceSettings(voxel=VOXEL)).volume
            assert s.bundle.result.volume == cache[design.a]
            shown = re.sub(r"<[^>]+>", "", s.panels.numbers.content)  # without the names' hover-text markup
            assert f"**Volume** {significant(cache[design.a])} " in shown  # its own volume
            assert s.shell.source is s.bundle.mesh
            # the address bar holds its own last state
            wait_for(lambda: parse_query(b.search) == (s.state, []), 10.0, f"session {plan.i}'s address bar")
            # nothing another browser did ever reached this browser's scene or address bar
            foreign = [p for p in b.gizmo_positions if p[0] != plan.x or p[2] not in plan.z_set]
            assert not foreign, f"browser {plan.i} received foreign gizmo positions {foreign[:3]}"
            for q in b.rewrites:  # every address bar the server sent it
                st, msgs = parse_query(q)
                assert msgs == [] and plan.owns(st.design, st.pose), f"browser {plan.i} got address bar {q}"
            assert len(b.gizmo_positions) >= counts[plan.i][0]
        # volumes differ between designs, so the check above would catch a swapped result
        assert len(set(cache.values())) == len(cache)
        assert set(explorer.sessions.values()) >= set(sessions)
    finally:
        for b in browsers:
            b.close()


# ------------------------------------------------------------------------------------------------
# real browsers


def _open_page(browser: Any, explorer: Explorer, query: str) -> tuple[Any, ClientSession]:
    """A fresh browser context (own localStorage) on ``?query``; returns the page and its session."""
    before = set(explorer.sessions)
    ctx = browser.new_context(viewport={"width": 1280, "height": 800})
    page = ctx.new_page()
    page.goto(explorer.url + "?" + query)
    page.wait_for_function("() => !document.body.innerText.includes('Connecting...')", timeout=30000)
    session = wait_for(lambda: next((s for cid, s in list(explorer.sessions.items())
                                     if cid not in before and s.ready.is_set()), None), 30, "session")
    return page, session


def _thumb(page: Any, handle: Any) -> Any:
    return page.locator(f'[id="{handle._impl.uuid}"] [role=slider]')


def _search(page: Any) -> str:
    return page.evaluate("() => location.search")


@pytest.mark.browser
@pytest.mark.slow
@pytest.mark.skipif(not os.path.exists(CHROMIUM),
                    reason=f"{CHROMIUM} is missing (install Debian's chromium package to run the browser tests)")
def test_concurrent_real_browsers() -> None:
    from playwright.sync_api import sync_playwright

    jobs = JobManager(max_workers=2, max_jobs_total=16, max_jobs_per_client=8, max_seconds=120)
    exp = Explorer("127.0.0.1", 0, jobs=jobs).start()
    api = start_api(create_api(jobs, explorer_url=exp.url), "127.0.0.1", 0)
    health_lat: list[float] = []
    health_bad: list[str] = []
    stop_health = threading.Event()

    def poll_health() -> None:
        with httpx.Client(base_url=api.url, timeout=30) as c:
            while not stop_health.is_set():
                t0 = time.perf_counter()
                try:
                    r = c.get(f"{API_PREFIX}/health")
                    dt = time.perf_counter() - t0
                    if r.status_code != 200 or r.json().get("status") != "ok":
                        health_bad.append(f"{r.status_code} {r.text[:200]}")
                except httpx.HTTPError as exc:
                    dt = time.perf_counter() - t0
                    health_bad.append(repr(exc))
                health_lat.append(dt)
                stop_health.wait(0.05)

    poller = threading.Thread(target=poll_health, daemon=True)
    t_begin = time.monotonic()
    try:
        exp.warm.wait(120)
        poller.start()
        links = ["voxel=6&a=30&z=120", "voxel=6&a=60&z=135", "voxel=6&a=80&z=150"]
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
            try:
                opened = [_open_page(browser, exp, q) for q in links]  # one after another: session = "the new one"
                t_open = time.monotonic() - t_begin
                pages = [pg for pg, _ in opened]
                sessions = [s for _, s in opened]
                assert len({id(s) for s in sessions}) == 3
                assert all(exp.sessions.get(s.client.client_id) is s for s in sessions)  # all connected at once
                initial = [s.state for s in sessions]
                for q, st in zip(links, initial):
                    assert parse_query(q)[0] == st
                # each page moves a different slider, one right after the other (no waiting in between)
                # page 0: design eta_s -> End (100); page 1: pose z +1 (two steps of 0.5); page 2: d_s -> Home (10)
                t_moves = time.monotonic()
                pages[0].bring_to_front()
                _thumb(pages[0], sessions[0].panels.design["eta_s"]).press("End")
                pages[1].bring_to_front()
                pages[1].get_by_role("tab", name="Pose").click()
                z_thumb = _thumb(pages[1], sessions[1].panels.pose["z"])
                z_thumb.press("ArrowRight")
                z_thumb.press("ArrowRight")
                pages[2].bring_to_front()
                _thumb(pages[2], sessions[2].panels.design["d_s"]).press("Home")
                expected = [
                    initial[0].replace(design=initial[0].design.replace(eta_s=100.0)),
                    initial[1].replace(pose=dataclasses.replace(initial[1].pose, z=136.0)),
                    initial[2].replace(design=initial[2].design.replace(d_s=10.0)),
                ]
                for i, (s, exp_state) in enumerate(zip(sessions, expected)):
                    wait_for(lambda: s.state == exp_state, 30, f"session {i} to hold its own change only")
                # each page's address bar reflects its own change only (a hidden page processes
                # messages once in front)
                for i, (page, s, exp_state) in enumerate(zip(pages, sessions, expected)):
                    page.bring_to_front()
                    wait_for(lambda: parse_query(_search(page)) == (exp_state, []), 30, f"page {i}'s address bar")
                t_moves = time.monotonic() - t_moves
                # the server sessions still hold their own states (nobody moved anybody else's)
                for s, exp_state in zip(sessions, expected):
                    assert s.state == exp_state
                for s in sessions:
                    wait_idle(exp, s, timeout=90)
                for s, exp_state in zip(sessions, expected):
                    assert s.bundle.result.design == exp_state.design
                assert "eta_s=100" in _search(pages[0]) and "a=30" in _search(pages[0])
                assert "z=136" in _search(pages[1]) and "eta_s=30" in _search(pages[1])
                assert "d_s=10" in _search(pages[2]) and "z=150" in _search(pages[2])
                # the sliders on screen: each page's moved slider moved, the same slider elsewhere did not
                pages[1].bring_to_front()
                pages[1].get_by_role("tab", name="Design").click()
                assert float(_thumb(pages[1], sessions[1].panels.design["eta_s"]).get_attribute(
                    "aria-valuenow")) == 30.0
                assert float(_thumb(pages[1], sessions[1].panels.design["d_s"]).get_attribute(
                    "aria-valuenow")) == 50.0
                pages[0].bring_to_front()
                assert float(_thumb(pages[0], sessions[0].panels.design["eta_s"]).get_attribute(
                    "aria-valuenow")) == 100.0
                assert float(_thumb(pages[0], sessions[0].panels.design["d_s"]).get_attribute(
                    "aria-valuenow")) == 50.0
                for page in pages:
                    page.context.close()
            finally:
                browser.close()
        stop_health.set()
        poller.join(10)
        print(f"\nbrowser load: 3 Chromium pages opened in {t_open:.1f} s, moves applied and address bars "
              f"updated in {t_moves:.1f} s, total {time.monotonic() - t_begin:.1f} s")
        print(f"  API /health during the browser load: {_ms(health_lat)}")
        assert not health_bad, health_bad[:5]
        assert len(health_lat) > 0
    finally:
        stop_health.set()
        exp.stop()
        api.stop()
        jobs.shutdown(wait=False)
