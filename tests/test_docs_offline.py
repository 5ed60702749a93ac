"""The REST API's interactive docs (/docs) render in a real Chromium with every request to any
other host refused: Swagger UI's script and style come from the API server itself."""

from __future__ import annotations

import os
import urllib.parse
from collections.abc import Iterator

import pytest

CHROMIUM = "/usr/bin/chromium"
if not os.path.exists(CHROMIUM):
    pytest.skip(f"{CHROMIUM} is missing (install Debian's chromium package to run the browser tests)",
                allow_module_level=True)

from playwright.sync_api import Route, sync_playwright  # noqa: E402

from paraspace.app.api import create_api  # noqa: E402
from paraspace.app.jobs import JobManager  # noqa: E402
from paraspace.app.serve import ApiServer, start_api  # noqa: E402

pytestmark = [pytest.mark.browser]


@pytest.fixture(scope="module")
def api() -> Iterator[ApiServer]:
    jobs = JobManager(max_workers=1)
    srv = start_api(create_api(jobs), "127.0.0.1", 0)
    yield srv
    jobs.shutdown(wait=False)
    srv.stop()


def test_docs_render_without_network(api: ApiServer) -> None:
    local = urllib.parse.urlsplit(api.url).netloc
    refused: list[str] = []

    def only_local(route: Route) -> None:
        if urllib.parse.urlsplit(route.request.url).netloc == local:
            route.continue_()
        else:
            refused.append(route.request.url)
            route.abort()

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True,
                                    args=["--no-sandbox", "--disable-gpu"])
        try:
            page = browser.new_page()
            page.route("**/*", only_local)
            page.goto(f"{api.url}/docs")
            # Swagger UI builds one block per operation from /openapi.json once its script ran
            page.wait_for_selector(".opblock", timeout=60_000)
            paths = page.locator(".opblock-summary-path").all_inner_texts()
            title = page.locator(".info .title").first.inner_text()
        finally:
            browser.close()
    assert refused == [], f"the docs page asked other hosts: {refused}"
    assert "paraspace API" in title
    assert any("/api/v1/workspace" in p for p in paths) and any("/api/v1/health" in p for p in paths), paths
