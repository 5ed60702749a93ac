"""The README's pictures of each preset in the explorer: docs/screenshots/mechanism_<preset>.png.

Run from the checkout: ``PYTHONPATH=. python scripts/mechanism_screenshots.py [PRESET ...]``. An
in-process explorer, headless Debian Chromium (Playwright), viewport 1440x900; each page waits for
its full, measured workspace, then 6 s for the browser to draw it.
"""

from __future__ import annotations

import pathlib
import sys
import time

from playwright.sync_api import sync_playwright

from paraspace.app.explorer import Explorer

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
from explorer_client import wait_for  # noqa: E402

ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--no-first-run"]
QUERIES = {"gough-stewart": "mech=gough-stewart&z=140", "6-pups": "mech=6-pups&z=150", "6-pss": "mech=6-pss&z=150"}


def main(names: list[str]) -> None:
    out = ROOT / "docs" / "screenshots"
    exp = Explorer("127.0.0.1", 0).start()
    exp.warm.wait(300)
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", headless=True, args=ARGS)
        for name in names or list(QUERIES):
            before = set(exp.sessions)
            ctx = browser.new_context(viewport={"width": 1440, "height": 900})
            page = ctx.new_page()
            page.goto(exp.url + "?" + QUERIES[name])
            s = wait_for(lambda before=before: next((s for cid, s in list(exp.sessions.items())
                                       if cid not in before and s.ready.is_set()), None), 60, "session")

            def done(s=s) -> bool:
                b, info = s.bundle, s.ctx.ws_info
                return (b is not None and b.mechanism == s.state.mechanism and info is not None
                        and not info.preview and info.measures is not None and not exp.jobs.active(s.job_client))

            wait_for(done, 300, "the workspace")
            toast = page.locator(".mantine-Notification-root", has_text="Software WebGL")
            try:
                toast.first.wait_for(timeout=3000)
                toast.first.locator(".mantine-Notification-closeButton").click()
            except Exception:  # noqa: BLE001 - not shown
                pass
            time.sleep(6)
            page.screenshot(path=str(out / f"mechanism_{name}.png"))
            print(name, s.bundle.result.volume, flush=True)
            ctx.close()
        browser.close()
    exp.stop()


if __name__ == "__main__":
    main(sys.argv[1:])
