"""Explorer latency in a real browser (Playwright + Chromium, SwiftShader on this machine).

Starts an :class:`app.explorer.Explorer` in-process, opens it in headless Chromium and measures,
with timestamps taken *in the page* (``performance.now()``, sampled once per animation frame):

* **mechanism**: key press on the ``x`` slider thumb (an IK-only update) -> the platform node has
  moved in the browser's scene -> the next animation frame after that (drawn);
* **preview / full shell**: key press on the ``a`` slider thumb (a design change; every press is a
  new, uncached value; the press is the slider stop) -> the preview shell (h = 6) / the full shell
  (h = 2) has its GLB parsed and attached -> the next frame (drawn). The full shell is recognised by
  its face count (the one the server sent), so a preview that the full shell replaced before it was
  ever drawn does not stall the run (it is counted as "preview never drawn");
* the press split into its legs on one clock (the server's events aligned to the page's clock by
  wall time): key -> the server starts the job; server: job start -> full shell sent; browser: full
  shell sent -> drawn;
* connect: page load -> first full shell on screen, with its legs (page load event, the server's
  first job and first full shell), when plotly.js was evaluated in the page (the page's plot gate
  sends it after the first shell is drawn: ``app/explorer/lazy_plot.py``; the run waits for it
  before the presses) and the websocket bytes.

``--display`` selects the shell sent (issue 24 target 10): ``light`` (default) is what the explorer
sends, ``kinematics.display_mesh.display_shell`` (a re-mesh of at most 36 000 faces, smoothed,
decimated to 12 000); ``decimated`` the path before it (the 50 000-face block re-mesh of at most
60 000, smoothed, then decimated to 12 000 by ``display_mesh``); ``full`` the path before that (the
50 000-face re-mesh, not decimated). The load average is printed before and after: the machine
is shared, so compare runs taken side by side.

``--glb`` selects how the shell goes on the wire: ``quantised`` (default) is what the explorer
sends (:func:`app.explorer.wire_glb.quantised_glb`: int16 positions, uint8 colours, uint16
indices, normals declared without data); ``float`` the GLB before it (trimesh's float32 export with
float normals and uint32 indices, the material patched in); ``ab`` alternates the two in one run
(connects, mechanism presses and design presses in the order ABBA ABBA ..., after one connect that
is not counted: the first page compiles the shaders and evaluates plotly.js) and prints both tables
side by side with their ratio (quantised / float), so that the load of the shared machine falls on
both alike. The forced redraws are then timed after each design press, with that press's shell on
screen.

``--trace DIR`` also records a Chrome trace and a JS CPU profile of the connect and of one more
press, and prints where the renderer's main thread and the GPU process spend that time.
``--no-plots`` is a what-if: the explorer's plotly plots are replaced by stand-ins (plotly.js is
then never sent), to measure what lazily created plots would save. Numbers only, no assertions.

Usage::

    python benchmarks/explorer_latency.py [--reps 5] [--connects 3] [--voxel 2] [--trace DIR] [--no-plots]
                                          [--display light|decimated|full] [--glb quantised|float|ab]
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from playwright.sync_api import sync_playwright  # noqa: E402

from paraspace.app.explorer import Explorer  # noqa: E402

TRACE_CATEGORIES = ["devtools.timeline", "blink.user_timing", "v8", "gpu", "disabled-by-default-devtools.timeline"]
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
        "--no-first-run", "--disable-sync"]

#: Before the page's own scripts: when ``window.Plotly`` gets its value (viser sends plotly.min.js
#: in the first message batch and evaluates it with ``new Function``).
CONNECT_PROBE = """
(() => {
  const C = window.__connect = {plotly: null};
  let plotly;
  Object.defineProperty(window, 'Plotly', {configurable: true, enumerable: true, get() { return plotly; },
    set(v) { plotly = v; if (C.plotly === null) { C.plotly = performance.now(); performance.mark('probe:plotly'); } }});
})();
"""

#: In-page probe, sampled once per animation frame: records when the platform moves and when a new
#: shell node is loaded (with its face count), and the frame after each (drawn).
PROBE = """
() => {
  const M = window.__viserMutable;
  const P = window.__probe = {key: 0, platform: [], shell: [], lastPlat: ''};
  const seen = new WeakSet();
  window.addEventListener('keydown', () => { P.key = performance.now(); performance.mark('probe:key'); }, true);
  const faces = (node) => {
    let n = 0;
    node.traverse(o => { const g = o.isMesh ? o.geometry : null;
                         if (g) n += (g.index ? g.index.count : g.attributes.position.count) / 3; });
    return n;
  };
  const record = (arr, t, extra, mark) => {
    const rec = [t, 0, extra];
    arr.push(rec);
    requestAnimationFrame(() => { rec[1] = performance.now(); performance.mark(mark); });
  };
  const tick = () => {
    const t = performance.now();
    const pl = M.nodeRefFromName['/platform'];
    if (pl) { const s = pl.position.toArray().join(','); if (s !== P.lastPlat) { P.lastPlat = s; record(P.platform, t, 0, 'probe:platform-drawn'); } }
    const sh = M.nodeRefFromName['/workspace/shell'];
    if (sh && sh.children.length > 0 && !seen.has(sh)) { seen.add(sh); const f = faces(sh); record(P.shell, t, f, 'probe:shell-drawn:' + f); }
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
}
"""


#: Time of one forced redraw (requestRender, then the frame after the next one has started).
REDRAW = """
async () => {
  const M = window.__viserMutable;
  await new Promise(r => requestAnimationFrame(r));
  const t0 = performance.now();
  M.requestRender();
  await new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)));
  return performance.now() - t0;
}
"""


def _wait(cond: Callable[[], bool], timeout: float, what: str) -> None:
    """Poll ``cond`` until it holds; raise (never hang) after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            raise TimeoutError(f"waited {timeout:g} s for {what}")
        time.sleep(0.01)


def _idle(exp: Explorer, session: Any, quiet: float = 1.5, timeout: float = 60.0) -> None:
    """Wait until the session has no unfinished job, then ``quiet`` more seconds (the page redraws)."""
    deadline = time.monotonic() + timeout
    while exp.jobs.active(session.job_client) and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(quiet)


def _stats(values: list[float]) -> str:
    if not values:
        return "n/a"
    return f"{statistics.median(values):8.3f} {min(values):8.3f} {max(values):8.3f}"


class _PlotStandIn:
    """What ``--no-plots`` puts where a plotly plot was: takes every attribute the explorer sets."""

    def __setattr__(self, name: str, value: Any) -> None:
        object.__setattr__(self, name, value)

    def __getattr__(self, name: str) -> Any:
        return None


def _no_plots() -> None:
    """The what-if of ``--no-plots``: every ``gui.add_plotly`` returns a stand-in, so neither
    plotly.js nor any figure is sent to the page."""
    from viser._gui_api import GuiApi

    GuiApi.add_plotly = lambda self, *a, **k: _PlotStandIn()  # type: ignore[method-assign]


#: (what, start, end) on the server's perf_counter clock, from :func:`_time_server_steps`.
STEPS: list[tuple[str, float, float]] = []


def _before_display(decimate: bool) -> None:
    """The explorer's shells as before issue 24 target 10: the block re-mesh to the job's budget
    (60 000 faces for the full shell), smoothed, then decimated to the display budget by
    ``display_mesh`` (``decimate``) or not at all."""
    from paraspace.app.explorer import workspace_job
    from paraspace.kinematics.display_mesh import DISPLAY_FACES, display_mesh

    make_shell = workspace_job.make_shell

    def before(result: Any, max_faces: int, display_faces: int | None = DISPLAY_FACES) -> Any:
        remesh = make_shell(result, max_faces, display_faces=None)
        return display_mesh(remesh, display_faces) if decimate and display_faces is not None else remesh

    workspace_job.make_shell = before  # type: ignore[assignment]


#: The wire encoding in use (``--glb``): read by the patched encoder of :func:`_wire_encodings` at each send.
WIRE = {"glb": "quantised"}


def _wire_encodings() -> None:
    """Make the shell's GLB encoder follow ``WIRE["glb"]``: ``float`` is the encoding before the
    quantised one (trimesh's float32 GLB with normals, the material patched in)."""
    from typing import cast

    from paraspace.app.explorer import scene

    quantised = scene.quantised_glb

    def encode(mesh: Any, opacity: float) -> bytes:
        if WIRE["glb"] == "float":
            return scene.glb_with_material(cast(bytes, mesh.export(file_type="glb", include_normals=True)), opacity)
        return quantised(mesh, opacity)

    scene.quantised_glb = encode  # type: ignore[assignment]


def _time_server_steps() -> None:
    """Time the explorer's server-side steps that its events do not split (measurement only: the
    same functions run, wrapped): measures + bracket of a result, and a shell's GLB export + send."""
    from paraspace.app.explorer import jsbridge, scene, workspace_controller, workspace_job
    from paraspace.app.explorer import server as explorer

    def timed(what: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def run(*a: Any, **k: Any) -> Any:
            t = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                STEPS.append((what, t, time.perf_counter()))
        return run

    workspace_job.measure = timed("measures", workspace_job.measure)  # type: ignore[assignment]
    # the bracket is a job of its own after the full shell (the controller imported the function by name)
    workspace_controller.bracket = timed("bracket", workspace_controller.bracket)  # type: ignore[assignment]
    scene.ShellScene.show = timed("shell GLB export + send", scene.ShellScene.show)  # type: ignore[method-assign]
    jsbridge.read_location = timed("read the page's location", jsbridge.read_location)  # type: ignore[assignment]
    explorer.ClientSession.build = timed("build the GUI", explorer.ClientSession.build)  # type: ignore[method-assign]


# ----- trace analysis (--trace) ---------------------------------------------------------------


def _self_times(events: list[dict], lo: float, hi: float) -> tuple[float, collections.Counter]:
    """Busy time and self time per event name of one thread's complete ('X') events in [lo, hi] (µs)."""
    xs = sorted((e for e in events if e.get("ph") == "X" and "dur" in e and lo <= e["ts"] <= hi),
                key=lambda e: (e["ts"], -e["dur"]))
    self_t: collections.Counter = collections.Counter()
    stack: list[dict] = []
    busy = 0.0
    for e in xs:
        while stack and e["ts"] >= stack[-1]["ts"] + stack[-1]["dur"]:
            stack.pop()
        name = e["name"]
        data = (e.get("args") or {}).get("data") or {}
        if name in ("FunctionCall", "EvaluateScript", "v8.compile", "v8.run") and data.get("url"):
            name = f"{name} {data['url'].rsplit('/', 1)[-1][:40]}"
        if stack:
            parent = stack[-1]
            self_t[parent["_key"]] -= e["dur"]
        else:
            busy += e["dur"]
        e["_key"] = name
        self_t[name] += e["dur"]
        stack.append(e)
    return busy, self_t


def _summarise_trace(path: Path, marks: tuple[str, str], splits: dict[str, float], title: str) -> None:
    """Print the renderer main thread's and the GPU process's busy time between two user-timing marks
    (``splits``: extra boundaries, in ms after the first mark), and the largest self times."""
    data = json.loads(path.read_text())
    events = data["traceEvents"] if isinstance(data, dict) else data
    names: dict[tuple[int, int], str] = {}
    for e in events:
        if e.get("ph") == "M" and e.get("name") == "thread_name":
            names[(e["pid"], e["tid"])] = e["args"]["name"]
    mark_ts = collections.defaultdict(list)
    for e in events:
        if e.get("name") in marks or e.get("name") == "probe:plotly":
            mark_ts[e["name"]].append(e["ts"])
    if not mark_ts.get(marks[0]) or not mark_ts.get(marks[1]):
        print(f"  {title}: marks {marks} not found in the trace")
        return
    t0 = min(mark_ts[marks[0]])
    t1 = min(t for t in mark_ts[marks[1]] if t >= t0) if any(t >= t0 for t in mark_ts[marks[1]]) else None
    if t1 is None:
        print(f"  {title}: no {marks[1]} after {marks[0]}")
        return
    by_thread = collections.defaultdict(list)
    for e in events:
        by_thread[(e.get("pid"), e.get("tid"))].append(e)
    mains = [k for k, n in names.items() if n == "CrRendererMain"]
    main = max(mains, key=lambda k: sum(1 for e in by_thread[k] if t0 <= e.get("ts", 0) <= t1))
    gpus = [k for k, n in names.items() if n in ("CrGpuMain", "VizCompositorThread")]
    bounds = sorted([("start", t0)] + [(k, t0 + v * 1e3) for k, v in splits.items() if 0 < v * 1e3 < t1 - t0]
                    + [("end", t1)], key=lambda kv: kv[1])
    print(f"\n  {title}: {(t1 - t0) / 1e3:.0f} ms from {marks[0]} to {marks[1]}")
    for (a, ta), (b, tb) in zip(bounds, bounds[1:]):
        busy, _ = _self_times(by_thread[main], ta, tb)
        line = f"    {a} -> {b}: {(tb - ta) / 1e3:7.0f} ms; renderer main thread busy {busy / 1e3:7.0f} ms"
        for g in gpus:
            gb, _ = _self_times(by_thread[g], ta, tb)
            line += f"; {names[g]} busy {gb / 1e3:.0f} ms"
        print(line)
    for mark in ("probe:plotly",):  # the task that evaluated plotly.js (the mark is set at its end)
        for ts in mark_ts.get(mark, []):
            tasks = [e for e in by_thread[main] if e.get("ph") == "X" and e["ts"] <= ts <= e["ts"] + e.get("dur", 0)]
            if tasks:
                task = max(tasks, key=lambda e: e["dur"])
                print(f"    the main-thread task that evaluated plotly.js: {task['dur'] / 1e3:.0f} ms, "
                      f"{(task['ts'] - t0) / 1e3:.0f} ms after {marks[0]}")
    busy, self_t = _self_times(by_thread[main], t0, t1)
    print(f"    renderer main thread, largest self times (of {busy / 1e3:.0f} ms busy):")
    for name, us in self_t.most_common(12):
        print(f"      {us / 1e3:8.1f} ms  {name}")
    for g in gpus:
        gb, gself = _self_times(by_thread[g], t0, t1)
        if gb > 0:
            print(f"    {names[g]}, largest self times (of {gb / 1e3:.0f} ms busy):")
            for name, us in gself.most_common(5):
                print(f"      {us / 1e3:8.1f} ms  {name}")


def _summarise_profile(profile: dict, title: str, top: int = 15) -> None:
    """Print the JS functions with the largest self time of a CDP CPU profile."""
    nodes = {n["id"]: n for n in profile["nodes"]}
    counts: collections.Counter = collections.Counter()
    for sample, dt in zip(profile.get("samples", []), profile.get("timeDeltas", [])):
        f = nodes[sample]["callFrame"]
        url = f.get("url", "").rsplit("/", 1)[-1][:30]
        counts[f"{f.get('functionName') or '(anonymous)'} [{url}:{f.get('lineNumber', 0)}]"] += dt
    total = sum(counts.values())
    print(f"\n  {title}: JS CPU profile, {total / 1e3:.0f} ms sampled; largest self times:")
    for name, us in counts.most_common(top):
        print(f"      {us / 1e3:8.1f} ms  {name}")


def _start_profiling(browser: Any, page: Any, trace_path: Path) -> Any:
    """Start a Chrome trace of ``page`` (to ``trace_path``) and a JS CPU profile; returns the CDP session."""
    cdp = page.context.new_cdp_session(page)
    browser.start_tracing(page=page, path=str(trace_path), screenshots=False, categories=TRACE_CATEGORIES)
    cdp.send("Profiler.enable")
    cdp.send("Profiler.setSamplingInterval", {"interval": 500})
    cdp.send("Profiler.start")
    return cdp


# ----- the benchmark -----------------------------------------------------------------------------


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--voxel", type=float, default=2.0)
    ap.add_argument("--width", type=int, default=1400, help="browser viewport width")
    ap.add_argument("--height", type=int, default=900, help="browser viewport height")
    ap.add_argument("--trace", type=Path, default=None, help="write Chrome traces and CPU profiles here")
    ap.add_argument("--connects", type=int, default=3, help="page loads timed (each a new design)")
    ap.add_argument("--no-plots", action="store_true", help="what-if: no plotly plots (stand-ins)")
    ap.add_argument("--display", choices=("light", "decimated", "full"), default="light",
                    help="decimated / full: the shell on screen as before issue 24 target 10 (module docstring)")
    ap.add_argument("--glb", choices=("quantised", "float", "ab"), default="quantised",
                    help="the shell's GLB on the wire; ab: float and quantised in turn (module docstring)")
    args = ap.parse_args()
    variants = ["float", "quantised"] if args.glb == "ab" else [args.glb]
    _wire_encodings()
    if args.no_plots:
        _no_plots()
    if args.display != "light":
        _before_display(decimate=args.display == "decimated")
    load_before = os.getloadavg()
    _time_server_steps()
    if args.trace is not None:
        args.trace.mkdir(parents=True, exist_ok=True)

    exp = Explorer("127.0.0.1", 0).start()
    exp.warm.wait(120)
    row_names = (
        "connect -> first full shell drawn (s)", "  connect: page load event (s)", "  connect: plotly.js evaluated (s)",
        "  connect: plotly.js evaluated - first shell drawn (s)",
        "  connect: server: read the page's location (s)", "  connect: server: build the GUI (s)",
        "  connect: server submits the first job (s)", "  connect: server sends the first full shell (s)",
        "  connect: browser: first full shell sent -> drawn (s)",
        "mechanism: key -> moved (s)", "mechanism: key -> drawn (s)",
        "preview shell: key -> drawn (s)", "full shell: key -> drawn (s)",
        "  key -> server starts the job (s)", "  server: job start -> full shell sent (s)",
        "    server: job start -> preview sent (s)", "    server: preview sent -> full shell sent (s)",
        "    server: measures + bracket in it (s)", "    server: GLB export + send in it (s)",
        "  browser: full shell sent -> drawn (s)",
        "server: preview compute+mesh (s)", "server: full compute (s)", "server: full mesh (s)",
        "browser: forced redraw -> 2nd frame (s)")
    size_names = ("connect: websocket bytes received (MB)", "preview GLB (MB)", "full GLB (MB)", "full faces")
    tables = {v: ({k: [] for k in row_names}, {k: [] for k in size_names}) for v in variants}
    skipped_by = dict.fromkeys(variants, 0)

    def turn(i: int) -> str:
        """The variant of the ``i``-th run of a loop: ABBA ABBA ... (no order favours either)."""
        return variants[(i + i // 2) % len(variants)] if len(variants) == 2 else variants[0]

    def use(variant: str) -> None:
        """Send the shells with ``variant``'s GLB from now on and record into its table."""
        nonlocal rows, sizes, skipped_previews
        if rows is not None:
            skipped_by[WIRE["glb"]] = skipped_previews
        WIRE["glb"] = variant
        rows, sizes = tables[variant]
        skipped_previews = skipped_by[variant]

    rows: dict[str, list[float]] = None  # type: ignore[assignment]
    sizes: dict[str, list[float]] = None  # type: ignore[assignment]
    skipped_previews = 0
    wall_minus_perf = time.time() - time.perf_counter()  # server perf_counter -> epoch seconds
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium", headless=True, args=ARGS)
            def connect(i: int) -> tuple[Any, Any]:
                """Open a new page on a new design (uncached: a = 50 + i/2) and time its first full shell."""
                page = browser.new_page(viewport={"width": args.width, "height": args.height})
                page.add_init_script(CONNECT_PROBE)
                ws_bytes = [0]

                def on_ws(ws: Any) -> None:
                    ws.on("framereceived", lambda payload: ws_bytes.__setitem__(0, ws_bytes[0] + len(payload)))

                page.on("websocket", on_ws)
                traced = args.trace is not None and i == 0
                if traced:
                    cdp = _start_profiling(browser, page, args.trace / "connect.json")
                before = set(exp.sessions)
                t0 = time.perf_counter()
                page.goto(exp.url + f"?voxel={args.voxel:g}&a={50 + 0.5 * i:g}")
                rows["  connect: page load event (s)"].append(time.perf_counter() - t0)
                page.wait_for_function("() => window.__viserMutable?.nodeRefFromName['/workspace/shell']?.children"
                                       "?.length > 0 && document.body.innerText.includes('(full, h =')", timeout=90000)
                page.evaluate("() => new Promise(r => requestAnimationFrame(() => {"
                              " performance.mark('probe:connected'); r(); }))")
                t_drawn = time.perf_counter()
                rows["connect -> first full shell drawn (s)"].append(t_drawn - t0)
                session = next(s for cid, s in list(exp.sessions.items()) if cid not in before)
                _wait(lambda: session.bundle is not None, 60, "the first full shell")
                drawn_at = page.evaluate("() => performance.now()")  # ms after the page's time origin
                for what, a, b in list(STEPS):
                    if a >= t0 and what in ("read the page's location", "build the GUI"):
                        rows[f"  connect: server: {what} (s)"].append(b - a)
                first = {what: t for t, what in reversed(list(session.events))}
                if "workspace-submit" in first:
                    rows["  connect: server submits the first job (s)"].append(first["workspace-submit"] - t0)
                if "full-shown" in first:
                    rows["  connect: server sends the first full shell (s)"].append(first["full-shown"] - t0)
                    rows["  connect: browser: first full shell sent -> drawn (s)"].append(t_drawn - first["full-shown"])
                _idle(exp, session)  # first frames (shader compilation), measures and orientation maps done
                # the plots' plotly.js follows the first shell drawn (app/explorer/lazy_plot.py, the gate): wait
                # for it, so that it is not evaluated during the presses below
                gate = getattr(session, "plot_gate", None)
                if gate is not None and not args.no_plots:
                    _wait(gate.opened.is_set, 30, "the plot gate")
                    page.wait_for_function("() => window.__connect.plotly !== null", timeout=30000)
                plotly_at = page.evaluate("() => window.__connect.plotly")
                if plotly_at is not None:
                    rows["  connect: plotly.js evaluated (s)"].append(plotly_at / 1e3)
                    rows["  connect: plotly.js evaluated - first shell drawn (s)"].append((plotly_at - drawn_at) / 1e3)
                sizes["connect: websocket bytes received (MB)"].append(ws_bytes[0] / 1e6)
                if traced:
                    _summarise_profile(cdp.send("Profiler.stop")["profile"], "connect")
                    browser.stop_tracing()
                    _summarise_trace(args.trace / "connect.json", ("navigationStart", "probe:connected"), {},
                                     "connect (navigation -> first full shell drawn)")
                return page, session

            page = None
            if len(variants) == 2:  # one page not counted: the first compiles the shaders, evaluates plotly.js
                use(variants[0])
                kept_rows = {k: list(v) for k, v in (*rows.items(), *sizes.items())}
                page, session = connect(-1)
                for k, v in (*rows.items(), *sizes.items()):
                    v[:] = kept_rows[k]
            for i in range(max(1, args.connects) * len(variants)):
                use(turn(i))
                if page is not None:
                    page.close()
                    _wait(lambda: len(exp.sessions) == 0, 30, "the closed page's session to end")
                page, session = connect(i)
            # cost of one frame: software WebGL redraws are the floor of every latency (with two
            # variants: timed after each design press instead, with that variant's shell on screen)
            for _ in range(8 if len(variants) == 1 else 0):
                rows["browser: forced redraw -> 2nd frame (s)"].append(page.evaluate(REDRAW) / 1e3)
            page.evaluate(PROBE)
            time_origin = page.evaluate("() => performance.timeOrigin") / 1e3  # epoch seconds of page t = 0

            def page_ms(server_perf: float) -> float:
                """A server perf_counter time on the page's performance.now() clock (ms)."""
                return (server_perf + wall_minus_perf - time_origin) * 1e3

            uuid_x = session.panels.pose["x"]._impl.uuid
            uuid_a = session.panels.design["a"]._impl.uuid
            thumb_x = page.locator(f'[id="{uuid_x}"] [role=slider]')
            thumb_a = page.locator(f'[id="{uuid_a}"] [role=slider]')

            page.get_by_role("tab", name="Pose").click()
            for i in range(args.reps * len(variants)):
                use(turn(i))
                n = page.evaluate("() => window.__probe.platform.length")
                thumb_x.press("ArrowRight")
                page.wait_for_function(f"() => window.__probe.platform.length > {n} && "
                                       f"window.__probe.platform[{n}][1] > 0", timeout=20000)
                key, (moved, drawn, _f) = page.evaluate(f"() => [window.__probe.key, window.__probe.platform[{n}]]")
                rows["mechanism: key -> moved (s)"].append((moved - key) / 1e3)
                rows["mechanism: key -> drawn (s)"].append((drawn - key) / 1e3)
                _idle(exp, session, quiet=0.5)

            page.get_by_role("tab", name="Design").click()

            def press_a(trace_to: Path | None = None) -> None:
                nonlocal skipped_previews
                n = page.evaluate("() => window.__probe.shell.length")
                t_press = time.perf_counter()
                old = session.state.design
                thumb_a.press("ArrowRight")
                _wait(lambda: session.state.design != old, 20, "the server to take the new design")
                _wait(lambda: session.bundle is not None and session.bundle.result.design == session.state.design,
                      90, "the full shell of the new design to be sent")
                faces = session.shell.last_faces
                try:
                    page.wait_for_function(
                        f"() => window.__probe.shell.slice({n}).some(r => r[2] === {faces} && r[1] > 0)", timeout=60000)
                except Exception:
                    print("DEBUG", page.evaluate("() => JSON.stringify(window.__probe.shell)")[-600:], faces,
                          session.panels.status.content, file=sys.stderr)
                    raise
                key, shells = page.evaluate(f"() => [window.__probe.key, window.__probe.shell.slice({n})]")
                i_full = next(i for i, r in enumerate(shells) if r[2] == faces and r[1] > 0)
                full = shells[i_full]
                pre = shells[0] if i_full > 0 else None
                if pre is None:
                    skipped_previews += 1
                else:
                    rows["preview shell: key -> drawn (s)"].append((pre[1] - key) / 1e3)
                rows["full shell: key -> drawn (s)"].append((full[1] - key) / 1e3)
                events = [(t, what) for t, what in list(session.events) if t >= t_press]
                submit = [t for t, what in events if what == "workspace-submit"]
                sent = [t for t, what in events if what == "full-shown"]
                pre_sent = [t for t, what in events if what == "preview-shown"]
                if submit and sent and pre_sent:
                    rows["    server: job start -> preview sent (s)"].append(pre_sent[-1] - submit[-1])
                    rows["    server: preview sent -> full shell sent (s)"].append(sent[-1] - pre_sent[-1])
                if submit and sent:
                    inside = [(w, a, b) for w, a, b in list(STEPS) if submit[-1] <= a and b <= sent[-1]]
                    rows["    server: measures + bracket in it (s)"].append(
                        sum(b - a for w, a, b in inside if w in ("measures", "bracket")))
                    rows["    server: GLB export + send in it (s)"].append(
                        sum(b - a for w, a, b in inside if w == "shell GLB export + send"))
                    rows["  key -> server starts the job (s)"].append((page_ms(submit[-1]) - key) / 1e3)
                    rows["  server: job start -> full shell sent (s)"].append(sent[-1] - submit[-1])
                    rows["  browser: full shell sent -> drawn (s)"].append((full[1] - page_ms(sent[-1])) / 1e3)
                b, pv = session.bundle, session.preview
                if pv is not None:
                    rows["server: preview compute+mesh (s)"].append(pv.result.compute_seconds + pv.shell_seconds)
                rows["server: full compute (s)"].append(b.result.compute_seconds)
                rows["server: full mesh (s)"].append(b.shell_seconds)
                sizes["preview GLB (MB)"].append(session.payloads.get("preview", 0) / 1e6)
                sizes["full GLB (MB)"].append(session.payloads.get("full", 0) / 1e6)
                sizes["full faces"].append(float(faces))
                if trace_to is not None and submit and sent:
                    splits = {"server starts the job": page_ms(submit[-1]) - key,
                              "full shell sent": page_ms(sent[-1]) - key}
                    if pre_sent:
                        splits["preview sent"] = page_ms(pre_sent[-1]) - key
                    press_splits.update(splits)
                    press_splits["_faces"] = faces

            press_splits: dict[str, float] = {}
            for i in range(args.reps * len(variants)):
                use(turn(i))
                press_a()
                _idle(exp, session)  # measures + orientation maps of this design finish before the next press
                for _ in range(3 if len(variants) == 2 else 0):
                    rows["browser: forced redraw -> 2nd frame (s)"].append(page.evaluate(REDRAW) / 1e3)
            if args.trace:  # one more press, traced and profiled (not in the table)
                kept = {id(v): len(v) for v in (*rows.values(), *sizes.values())}
                kept_skipped = skipped_previews
                cdp = _start_profiling(browser, page, args.trace / "press.json")
                press_a(args.trace / "press.json")
                page.evaluate("() => new Promise(r => setTimeout(r, 300))")
                profile = cdp.send("Profiler.stop")["profile"]
                browser.stop_tracing()
                for vals in (*rows.values(), *sizes.values()):  # keep the traced press out of the table
                    del vals[kept[id(vals)]:]
                skipped_previews = kept_skipped
                faces = int(press_splits.pop("_faces", 0))
                _summarise_profile(profile, "one design press (key -> full shell drawn, +0.3 s)")
                _summarise_trace(args.trace / "press.json", ("probe:key", f"probe:shell-drawn:{faces}"),
                                 press_splits, "one design press (key -> full shell drawn)")
                _idle(exp, session)
            browser.close()
    finally:
        exp.stop()
    use(variants[-1])

    print(f"\nexplorer latency, headless Chromium (SwiftShader), viewport {args.width}x{args.height}, "
          f"voxel h = {args.voxel:g}, reps = {args.reps}{', NO PLOTS (what-if)' if args.no_plots else ''}, "
          f"display shell {args.display}, GLB {args.glb}; "
          f"load average {load_before[0]:.2f} before, {os.getloadavg()[0]:.2f} after "
          f"({os.cpu_count()} CPUs)")
    for variant in variants:
        rows, sizes = tables[variant]
        mesh, comp = rows["server: full mesh (s)"], rows["server: full compute (s)"]
        rows["server: full mesh / full compute (ratio)"] = [m / c for m, c in zip(mesh, comp)]
        sizes["presses whose preview was never drawn"] = [float(skipped_by[variant])]
    if len(variants) == 1:
        rows, sizes = tables[variants[0]]
        print(f"{'':44s} {'median':>8s} {'min':>8s} {'max':>8s}")
        for name, vals in (*rows.items(), *sizes.items()):
            print(f"{name:44s} {_stats(vals)}")
        return
    print(f"medians (n per variant: connects {args.connects}, presses {args.reps}); ratio = quantised / float")
    print(f"{'':44s} {'float':>9s} {'quantised':>9s} {'ratio':>7s}")
    for name in (*tables["float"][0], *tables["float"][1]):
        a_vals = tables["float"][0].get(name, tables["float"][1].get(name, []))
        b_vals = tables["quantised"][0].get(name, tables["quantised"][1].get(name, []))
        ma = statistics.median(a_vals) if a_vals else float("nan")
        mb = statistics.median(b_vals) if b_vals else float("nan")
        ratio = f"{mb / ma:7.2f}" if a_vals and b_vals and ma else "    n/a"
        print(f"{name:44s} {ma:9.3f} {mb:9.3f} {ratio}")


if __name__ == "__main__":
    main()
