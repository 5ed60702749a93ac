"""The design report (app/report.py, `paraspace report`, the Share tab's button).

Checked as a reader would: the page loads in a real Chromium with the network off and every
picture decodes; every number it prints is the number the core computes for that design
(independently recomputed here); each measure carries its glossary definition; the parameters
that differ across the set, and only those, are highlighted; the link restores the design; user
text is escaped; bad input names its field."""

from __future__ import annotations

import base64
import html
import io
import os
import re
import urllib.parse

import numpy as np
import pytest

from paraspace.app.glossary import DEFINITIONS
from paraspace.app.numfmt import significant
from paraspace.app.report import MAX_DESIGNS, compute_entry, report_html
from paraspace.app.urlstate import parse_query
from paraspace.kinematics.design import Design
from paraspace.kinematics.measures import measure_workspace
from paraspace.kinematics.orientation import OrientationSettings
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

H = 8.0
CHROMIUM = "/usr/bin/chromium"


@pytest.fixture(scope="module")
def two():
    s = WorkspaceSettings(voxel=H)
    return [compute_entry("paper <default>", Design(), s, OrientationSettings(angle_step=10.0),
                          link="http://127.0.0.1:8080/?a=50&voxel=8"),
            compute_entry("a = 80", Design(a=80.0), s, None)]


@pytest.fixture(scope="module")
def page(two):
    return report_html(two, version="test")


def _images(text: str) -> list[bytes]:
    return [base64.b64decode(m) for m in re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', text)]


def test_self_contained_and_pictures_decode(page):
    from PIL import Image

    # nothing fetched from anywhere: no src/href other than data: URIs and the explorer links
    for attr, url in re.findall(r'(src|href)=["\']([^"\']*)', page):
        assert url.startswith("data:image/png;base64,") or (attr == "href" and url.startswith("http://127.0.0.1"))
    assert "<script" not in page.lower() and "@import" not in page
    imgs = _images(page)
    # per design: the mechanism, the four shell views; the first also its orientation maps
    assert len(imgs) == 2 * 2 + 1
    for png in imgs:
        im = Image.open(io.BytesIO(png))
        assert im.format == "PNG" and im.size[0] > 200 and im.size[1] > 200
        px = im.convert("L").getextrema()
        assert px[1] - px[0] > 50  # not a blank picture


def test_numbers_are_the_cores_numbers(page):
    for d in (Design(), Design(a=80.0)):
        res = compute_workspace(d, WorkspaceSettings(voxel=H, method="dense"))  # the engine's oracle path
        m = measure_workspace(res)
        assert f"{significant(res.volume, 4)} units³ (h = {H:g})" in page
        assert f"<td>{significant(m.hollowness, 3)}</td>" in page
    # each measure row carries its definition
    for name in ("volume", "bracket", "boundary", "hollowness", "stable_genus", "TI_1", "TI_2"):
        assert html.escape(DEFINITIONS[name]) in page, name


def test_differing_parameters_and_only_those_are_highlighted(page):
    table = page.split('<table class="compare">')[1].split("</table>")[0]
    marked = re.findall(r'<tr class="differs"><th>([^<]*)</th>', table)
    assert [html.unescape(x) for x in marked] == ["a · platform radius"]


def test_user_text_is_escaped_and_the_link_restores_the_design(page):
    assert "paper &lt;default&gt;" in page and "paper <default>" not in page
    link = re.search(r"href='(http://127\.0\.0\.1[^']*)'", page).group(1)
    state, msgs = parse_query(urllib.parse.urlsplit(html.unescape(link)).query)
    assert msgs == [] and state.design == Design()


def test_bounds_on_the_set(two):
    with pytest.raises(ValueError, match=r"designs: .*valid range \[1, 8\]"):
        report_html([two[0]] * (MAX_DESIGNS + 1))
    with pytest.raises(ValueError, match="at least 1"):
        report_html([])


def test_cli_writes_the_report_and_names_bad_fields(tmp_path, capsys):
    from paraspace.app.cli import main

    out = tmp_path / "r.html"
    assert main(["report", "--voxel", "10", "--no-orientation", "--compare", "d_s=10", "--out", str(out)]) == 0
    text = out.read_text(encoding="utf-8")
    assert "d_s = 10" in text and "The designs side by side" in text and len(_images(text)) == 4
    assert main(["report", "--compare", "d_s=ten", "--out", str(out)]) == 2
    assert "d_s = 'ten' is invalid: valid range [0, 1000]" in capsys.readouterr().err
    assert main(["report", "--compare", "z=1", "--out", str(out)]) == 2
    assert "compare = 'z=1' is invalid" in capsys.readouterr().err
    assert main(["report", "--out", str(tmp_path / "r.pdf")]) == 2
    assert "out = " in capsys.readouterr().err


@pytest.mark.browser
@pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="Debian's chromium is missing")
def test_opens_offline_in_chromium(page, tmp_path):
    from playwright.sync_api import sync_playwright

    path = tmp_path / "report.html"
    path.write_text(page, encoding="utf-8")
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=["--no-sandbox", "--disable-gpu"])
        try:
            ctx = b.new_context(offline=True)
            pg = ctx.new_page()
            failed: list[str] = []
            pg.on("requestfailed", lambda r: failed.append(r.url))
            pg.goto(path.as_uri())
            assert pg.evaluate("() => [...document.images].every(i => i.complete && i.naturalWidth > 0)")
            assert pg.evaluate("() => document.images.length") == 5
            assert failed == []
            assert "The designs side by side" in pg.inner_text("body")
            pdf = pg.pdf(format="A4")  # print-ready: one page per design after the table
            assert pdf[:5] == b"%PDF-" and pdf.count(b"/Type /Page") - pdf.count(b"/Type /Pages") >= 3
        finally:
            b.close()


@pytest.mark.parametrize("design", [Design(), Design(eta_range="from-zero", a=80.0, r=90.0, eta_s=90.0)],
                         ids=["paper", "from-zero arcs of 90 deg"])
def test_the_mechanism_view_names_every_chain_in_view_and_off_its_rails(design):
    """Each chain's name is drawn inside the axes (the first version put chain 1's outside them, where
    it was cut off), off its arc and radial rail, and the legend lies below the axes, off the drawing."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from paraspace.app.report import mechanism_figure

    fig = mechanism_figure(design)
    ax = fig.axes[0]
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    r = canvas.get_renderer()
    box = ax.get_window_extent(r)
    labels = [t for t in ax.texts if t.get_text().startswith("chain ")]
    assert sorted(t.get_text() for t in labels) == ["chain 1", "chain 2", "chain 3"]
    rails = [line for line in ax.get_lines() if line.get_color() in ("#0072B2", "#D55E00")]  # arcs, radial rails
    assert len(rails) == 6
    points = np.concatenate([ax.transData.transform(np.column_stack(line.get_data())) for line in rails])
    for t in labels:
        ext = t.get_window_extent(r)
        assert box.x0 <= ext.x0 and ext.x1 <= box.x1 and box.y0 <= ext.y0 and ext.y1 <= box.y1, t.get_text()
        inside = ((points[:, 0] > ext.x0) & (points[:, 0] < ext.x1) & (points[:, 1] > ext.y0) & (points[:, 1] < ext.y1))
        assert not inside.any(), f"{t.get_text()} covers a rail"
    assert ax.get_legend().get_window_extent(r).y1 <= box.y0
