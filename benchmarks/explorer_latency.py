"""Explorer latency in a real browser (Playwright + Chromium, SwiftShader on this machine).

Starts an :class:`app.explorer.Explorer` in-process, opens it in headless Chromium and measures,
with timestamps taken *in the page* (``performance.now()``):

* **mechanism**: key press on the ``x`` slider thumb (an IK-only update) -> the platform node has
  moved in the browser's scene -> the next animation frame after that (drawn);
* **preview / full shell**: key press on the ``a`` slider thumb (a design change; every press is a
  new, uncached value) -> the first / second replacement of the ``/workspace/shell`` node has its
  GLB parsed and attached (the preview at h = 6, then the full shell at h = 2) -> next frame;
* server-side: workspace compute and shell meshing times, GLB payload sizes;
* connect: page load -> first full shell on screen.

Prints a table (median, min, max over the repetitions). No assertions: numbers only.

Usage::

    python benchmarks/explorer_latency.py [--reps 5] [--voxel 2]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from playwright.sync_api import sync_playwright  # noqa: E402

from paraspace.app.explorer import Explorer  # noqa: E402

ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
        "--no-first-run", "--disable-sync"]

#: In-page probe: records when the platform moves and when the shell node is replaced and loaded.
PROBE = """
() => {
  const M = window.__viserMutable;
  const P = window.__probe = {key: 0, platform: [], shell: [], lastShell: '', lastPlat: ''};
  window.addEventListener('keydown', () => { P.key = performance.now(); }, true);
  const frame = (arr) => { const t = performance.now(); requestAnimationFrame(() => arr.push([t, performance.now()])); };
  setInterval(() => {
    const pl = M.nodeRefFromName['/platform'];
    if (pl) { const s = pl.position.toArray().join(','); if (s !== P.lastPlat) { P.lastPlat = s; frame(P.platform); } }
    const sh = M.nodeRefFromName['/workspace/shell'];
    if (sh && sh.children.length > 0 && sh.uuid !== P.lastShell) { P.lastShell = sh.uuid; frame(P.shell); }
  }, 2);
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


def _idle(exp: Explorer, session, quiet: float = 1.5, timeout: float = 60.0) -> None:
    """Wait until the session has no unfinished job, then ``quiet`` more seconds (the page redraws)."""
    deadline = time.monotonic() + timeout
    while exp.jobs.active(session.job_client) and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(quiet)


def _stats(values: list[float]) -> str:
    if not values:
        return "n/a"
    return f"{statistics.median(values):8.3f} {min(values):8.3f} {max(values):8.3f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--voxel", type=float, default=2.0)
    ap.add_argument("--width", type=int, default=1400, help="browser viewport width")
    ap.add_argument("--height", type=int, default=900, help="browser viewport height")
    args = ap.parse_args()

    exp = Explorer("127.0.0.1", 0).start()
    exp.warm.wait(120)
    rows: dict[str, list[float]] = {k: [] for k in (
        "connect -> first full shell drawn (s)", "mechanism: key -> moved (s)", "mechanism: key -> drawn (s)",
        "preview shell: key -> drawn (s)", "full shell: key -> drawn (s)", "server: preview compute+mesh (s)",
        "server: full compute (s)", "server: full mesh (s)", "browser: forced redraw -> 2nd frame (s)")}
    sizes: dict[str, list[int]] = {"preview GLB (MB)": [], "full GLB (MB)": [], "full faces": []}
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium", headless=True, args=ARGS)
            page = browser.new_page(viewport={"width": args.width, "height": args.height})
            before = set(exp.sessions)
            t0 = time.perf_counter()
            page.goto(exp.url + f"?voxel={args.voxel:g}")
            page.wait_for_function("() => !!window.__viserMutable?.nodeRefFromName['/workspace/shell']"
                                   "?.children?.length", timeout=60000)
            session = next(s for cid, s in list(exp.sessions.items()) if cid not in before)
            while session.bundle is None:
                time.sleep(0.01)
            page.wait_for_function("() => window.__viserMutable.nodeRefFromName['/workspace/shell']?.children?.length"
                                   " > 0 && document.body.innerText.includes('(full, h =')", timeout=60000)
            page.evaluate("() => new Promise(r => requestAnimationFrame(() => r()))")
            rows["connect -> first full shell drawn (s)"].append(time.perf_counter() - t0)
            _idle(exp, session)  # first frames (shader compilation), measures and orientation maps done
            for _ in range(8):  # cost of one frame: software WebGL redraws are the floor of every latency
                rows["browser: forced redraw -> 2nd frame (s)"].append(page.evaluate(REDRAW) / 1e3)
            page.evaluate(PROBE)
            uuid_x = session.panels.pose["x"]._impl.uuid
            uuid_a = session.panels.design["a"]._impl.uuid
            thumb_x = page.locator(f'[id="{uuid_x}"] [role=slider]')
            thumb_a = page.locator(f'[id="{uuid_a}"] [role=slider]')

            page.get_by_role("tab", name="Pose").click()
            for _ in range(args.reps):
                n = page.evaluate("() => window.__probe.platform.length")
                thumb_x.press("ArrowRight")
                page.wait_for_function(f"() => window.__probe.platform.length > {n}", timeout=20000)
                key, (moved, drawn) = page.evaluate(f"() => [window.__probe.key, window.__probe.platform[{n}]]")
                rows["mechanism: key -> moved (s)"].append((moved - key) / 1e3)
                rows["mechanism: key -> drawn (s)"].append((drawn - key) / 1e3)
                _idle(exp, session, quiet=0.5)

            page.get_by_role("tab", name="Design").click()
            for _ in range(args.reps):
                n = page.evaluate("() => window.__probe.shell.length")
                thumb_a.press("ArrowRight")
                try:
                    page.wait_for_function(f"() => window.__probe.shell.length >= {n + 2}", timeout=60000)
                except Exception:
                    print("DEBUG", page.evaluate("() => JSON.stringify(window.__probe)")[:500], session.state.design,
                          session.panels.status.content, file=sys.stderr)
                    raise
                key, pre, full = page.evaluate(
                    f"() => [window.__probe.key, window.__probe.shell[{n}], window.__probe.shell[{n + 1}]]")
                rows["preview shell: key -> drawn (s)"].append((pre[1] - key) / 1e3)
                rows["full shell: key -> drawn (s)"].append((full[1] - key) / 1e3)
                while session.bundle is None or session.bundle.result.design != session.state.design:
                    time.sleep(0.01)
                b, pv = session.bundle, session.preview
                if pv is not None:
                    rows["server: preview compute+mesh (s)"].append(pv.result.compute_seconds + pv.shell_seconds)
                rows["server: full compute (s)"].append(b.result.compute_seconds)
                rows["server: full mesh (s)"].append(b.shell_seconds)
                sizes["preview GLB (MB)"].append(session.payloads.get("preview", 0) / 1e6)
                sizes["full GLB (MB)"].append(session.payloads.get("full", 0) / 1e6)
                sizes["full faces"].append(len(b.mesh.faces))
                _idle(exp, session)  # measures + orientation maps of this design finish before the next press
            browser.close()
    finally:
        exp.stop()

    print(f"\nexplorer latency, headless Chromium (SwiftShader), viewport {args.width}x{args.height}, "
          f"voxel h = {args.voxel:g}, reps = {args.reps}")
    print(f"{'':44s} {'median':>8s} {'min':>8s} {'max':>8s}")
    for name, vals in rows.items():
        print(f"{name:44s} {_stats(vals)}")
    for name, vals in sizes.items():
        print(f"{name:44s} {_stats([float(v) for v in vals])}")


if __name__ == "__main__":
    main()
