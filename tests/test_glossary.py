"""Every number on screen comes with its definition (app/glossary.py).

The explorer's Numbers and its pinned strip give each measure's name a hover text; the optimiser
and the studies offer measures by name. A measure any of them can show must have a definition, and
the hover text must be the definition, escaped (it is HTML inside viser's markdown)."""

from __future__ import annotations

import html
import re

import pytest

from paraspace.app import figures, glossary
from paraspace.app.explorer.numbers_panel import numbers_markdown, summary_markdown
from paraspace.app.explorer.session import ShellInfo
from paraspace.app.explorer.workspace_job import voxel_z_range
from paraspace.app.urlstate import ExplorerState
from paraspace.kinematics.bracket import bracket_of
from paraspace.kinematics.measures import measure_workspace
from paraspace.kinematics.objectives import MEASURES as OPTIMISER_MEASURES
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


def test_every_offered_measure_is_defined():
    offered = set(OPTIMISER_MEASURES) | set(figures.MEASURES)
    missing = sorted(m for m in offered if m not in glossary.DEFINITIONS)
    assert not missing, f"measures without a definition in app/glossary.py: {missing}"
    with pytest.raises(KeyError):
        glossary.define("no such measure")


def test_hover_text_is_the_escaped_definition():
    glossary.DEFINITIONS["_probe"] = 'a "quoted" <b>tag</b> & more'
    try:
        out = glossary.hover("V<1>", "_probe")
    finally:
        del glossary.DEFINITIONS["_probe"]
    title = re.search(r'title="([^"]*)"', out).group(1)
    assert "<" not in title and '"' not in title
    assert html.unescape(title) == 'a "quoted" <b>tag</b> & more'
    assert ">V&lt;1&gt;</span>" in out


@pytest.fixture(scope="module")
def shown():
    s = ExplorerState()
    res = compute_workspace(s.design, WorkspaceSettings(voxel=6.0))
    m = measure_workspace(res)
    info = ShellInfo(volume=res.volume, h=6.0, preview=False, seconds=0.1, shell_seconds=0.1, gen=1, cached=False,
                     measures=m, bracket=bracket_of(res))
    return s, res, info


def _titles(md: str) -> dict[str, str]:
    """label -> hover text of every hoverable name in ``md``."""
    return {html.unescape(lab): html.unescape(t)
            for t, lab in re.findall(r'<span title="([^"]*)"[^>]*>([^<]*)</span>', md)}


def test_every_measure_in_the_numbers_has_its_definition(shown):
    s, _, info = shown
    md = numbers_markdown(s, info, None, None, None, None)
    titles = _titles(md)
    for label, name in (("Volume", "volume"), ("certified", "bracket"), ("Voids", "voids"),
                        ("Hollowness", "hollowness"), ("Boundary", "boundary"), ("Topology", "topology"),
                        ("Compute", "compute")):
        assert titles.get(label) == glossary.DEFINITIONS[name], label
    # raw voxel counts are labelled as such, below the stable ones
    assert md.index("raw voxel counts (change with h)") > md.index("Topology")


def test_the_strip_shows_volume_and_bracket_to_the_same_digits(shown):
    s, _, info = shown
    strip = summary_markdown(s, info, None, None, None)
    plain = re.sub(r"<[^>]+>", "", strip)
    m = re.search(r"V\*\* ([0-9.e+]+) units³ ∈ \[([0-9.e+]+), ([0-9.e+]+)\]", plain)
    assert m, plain
    digits = {len(re.sub(r"e.*|[^0-9]", "", g).lstrip("0")) for g in m.groups()}
    assert digits == {4}, m.groups()  # 5.120e+06 beside 4.905e+06, never 5.12e+06
    assert float(m.group(2)) <= float(m.group(1)) * 1.0005 and float(m.group(1)) <= float(m.group(3)) * 1.0005
    assert "boundary" in plain and "TI₁ / TI₂" in plain


def test_colour_range_is_the_voxels_heights(shown):
    _, res, _ = shown
    lo, hi = voxel_z_range(res)
    k = res.occupancy.any(axis=(0, 1)).nonzero()[0]
    centres = res.grid.origin[2] + res.grid.h * k
    assert lo == pytest.approx(max(0.0, centres.min() - 3.0)) and hi == pytest.approx(centres.max() + 3.0)
    assert lo >= 0.0
