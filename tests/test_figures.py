"""The plotting module app/figures.py: what a reader of the plots relies on.

Heat-map cells are centred on the samples (read back from the plotly figure and from the
matplotlib image extent), PNG exports carry >= 200 dpi, SVG exports are XML, every axis title has
a unit, the current design is marked at its value, the orientation maps' legend covers every region
colour, and a Δ equal to the whole scan is flagged.
"""

from __future__ import annotations

import dataclasses
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from paraspace.app import figures
from paraspace.kinematics.orientation import (
    ROTATIONS,
    OrientationResult,
    OrientationSettings,
    make_region,
    tilt_indices,
)

UNITS = ("[units]", "[units³]", "[deg]", "[deg·units]", "[ratio 0-1]", "[count]")


# ---------------------------------------------------------------------------------------------
# data


def sweep_rows() -> list[dict]:
    return [{"param": "a", "value": v, "volume": 1e4 * v, "hollowness": 0.01 * v, "TI_1": 100.0 + v}
            for v in (10.0, 32.5, 55.0, 77.5, 100.0)]


def study() -> tuple[list[float], list[float], list[list[float]]]:
    xs = [10.0, 25.0, 40.0, 55.0]
    ys = [10.0, 30.0, 50.0]
    return xs, ys, [[x * 1000 + y for x in xs] for y in ys]


def synthetic_orientation(saturate: bool = True) -> OrientationResult:
    """Nine regions on a small grid. With ``saturate`` phi is feasible over the whole angle scan on
    every line (its Δφ equals the scan), and tau and psi are identical on the z line (the case in
    which one overlay region hid the other)."""
    settings = OrientationSettings(z0=130.0, angle_range=30.0, angle_step=5.0, position_step=5.0)
    angles = np.arange(-30.0, 30.0 + 1e-9, 5.0)
    regions = {}
    for line, positions in (("z", np.arange(0.0, 100.0 + 1e-9, 5.0)), ("y_prime", np.arange(-50.0, 50.0 + 1e-9, 5.0)),
                            ("x", np.arange(-50.0, 50.0 + 1e-9, 5.0))):
        for rot in ROTATIONS:
            A, S = np.meshgrid(angles, positions)
            if rot == "phi_z":
                lim = 30.0 if saturate else 20.0
                feas = (np.abs(A) <= lim) & (np.abs(S - positions.mean()) <= 20.0)
            else:
                feas = (np.abs(A) <= 10.0) & (np.abs(S - positions.mean()) <= 10.0)
            regions[(line, rot)] = make_region(line, rot, positions, angles, feas,
                                               position_step=5.0, angle_step=5.0,
                                               position_range=(float(positions[0]), float(positions[-1])),
                                               angle_range=(-30.0, 30.0))
    ti1, ti2, deltas = tilt_indices(regions)
    return OrientationResult(settings=settings, regions=regions, ti1=ti1, ti2=ti2, compute_seconds=0.0,
                             deltas=deltas)


# ---------------------------------------------------------------------------------------------
# helpers


def png_dpi(data: bytes) -> tuple[float, float]:
    """Dots per inch from the PNG pHYs chunk (pixels per metre)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos = 8
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        if kind == b"pHYs":
            ppx, ppy, unit = struct.unpack(">IIB", body)
            assert unit == 1, "pHYs unit is not the metre"
            return ppx * 0.0254, ppy * 0.0254
        pos += 12 + length
    raise AssertionError("no pHYs chunk")


def png_size(data: bytes) -> tuple[int, int]:
    w, h = struct.unpack(">II", data[16:24])
    return w, h


# ---------------------------------------------------------------------------------------------
# tests


def test_heatmap_cells_are_centred_on_the_samples():
    xs, ys, grid = study()
    spec = figures.study_spec(xs, ys, grid, current=(25.0, 30.0), current_value=25030.0, panels=("heatmap",))
    # plotly: one heat-map value per sample, at the sample (plotly puts cell edges midway between)
    heat = [t for t in figures.to_plotly(spec).data if t.type == "heatmap"]
    assert len(heat) == 1
    assert list(heat[0].x) == xs and list(heat[0].y) == ys
    assert np.asarray(heat[0].z).shape == (len(ys), len(xs))
    # matplotlib: the image extent puts cell i's centre on sample i
    fig = figures.to_matplotlib(spec)
    ax = fig.axes[0]
    (im,) = ax.get_images()
    x0, x1, y0, y1 = im.get_extent()
    nx, ny = len(xs), len(ys)
    centres_x = [x0 + (i + 0.5) * (x1 - x0) / nx for i in range(nx)]
    centres_y = [y0 + (j + 0.5) * (y1 - y0) / ny for j in range(ny)]
    assert centres_x == pytest.approx(xs) and centres_y == pytest.approx(ys)
    assert np.asarray(im.get_array()).shape == (ny, nx)


def test_heatmap_uneven_samples_cells_centred():
    xs, ys = [10.0, 20.0, 50.0], [5.0, 6.0]
    spec = figures.study_spec(xs, ys, [[1, 2, 3], [4, 5, 6]], panels=("heatmap",))
    fig = figures.to_matplotlib(spec)
    mesh = fig.axes[0].collections[0]
    # pcolormesh edges midway between samples: each cell's centre is its sample
    coords = mesh.get_coordinates()  # (ny + 1, nx + 1, 2)
    cx = (coords[0, :-1, 0] + coords[0, 1:, 0]) / 2
    assert coords[0, 1, 0] == pytest.approx(15.0) and coords[0, 2, 0] == pytest.approx(35.0)
    assert cx[1] == pytest.approx(25.0)  # (15 + 35) / 2: the cell is centred between its edges
    assert list(figures.to_plotly(spec).data[0].x) == xs


@pytest.mark.parametrize("build", ["sweep", "study", "orientation"])
def test_png_at_least_200_dpi_and_svg_parses(build):
    spec = {"sweep": lambda: figures.sweep_spec(sweep_rows(), "a", current=55.0, current_value=5.5e5),
            "study": lambda: figures.study_spec(*study(), current=(25.0, 30.0)),
            "orientation": lambda: figures.orientation_spec(synthetic_orientation())}[build]()
    png = figures.export(spec, "png")
    dpi_x, dpi_y = png_dpi(png)
    assert dpi_x >= 199.9 and dpi_y >= 199.9
    w, h = png_size(png)
    assert w >= spec.size[0] * 200 * 0.9 and h >= spec.size[1] * 200 * 0.5  # pixels to match (layout may trim)
    svg = figures.export(spec, "svg")
    root = ET.fromstring(svg)
    assert root.tag.endswith("svg")
    assert spec.title.split(" - ")[0] in svg.decode()  # the title is in the file
    assert figures.export(spec, "pdf")[:5] == b"%PDF-"


def test_every_axis_title_has_a_unit():
    specs = [figures.sweep_spec(sweep_rows(), p, m, current=55.0) for p in ("a", "eta_s", "l_s")
             for m in ("volume", "hollowness", "TI_1")]
    specs += [figures.study_spec(*study()), figures.orientation_spec(synthetic_orientation())]
    for spec in specs:
        assert spec.title
        for p in spec.panels:
            titles = [p.x_title, p.y_title] + ([p.z_title] if p.kind in ("heatmap", "surface") else [])
            for t in titles:
                if t:  # the orientation grid labels the position axis once per row
                    assert any(u in t for u in UNITS), f"no unit in {t!r}"
        fig = figures.to_plotly(spec)
        assert fig.layout.title.text
        for ax_name in [k for k in fig.layout.to_plotly_json() if k.startswith(("xaxis", "yaxis"))]:
            t = fig.layout[ax_name].title.text
            if t:
                assert any(u in t for u in UNITS), f"{ax_name}: {t!r}"
    assert figures.sweep_spec(sweep_rows(), "a").panels[0].y_title == "V - workspace volume [units³]"
    assert figures.sweep_spec(sweep_rows(), "eta_s").panels[0].x_title.endswith("[deg]")


def test_sweep_of_any_measure_and_current_design_marker():
    rows = sweep_rows()
    assert figures.plottable_measures(rows)[:3] == ["volume", "hollowness", "TI_1"]
    spec = figures.sweep_spec(rows, "a", "hollowness", current=55.0, current_value=0.55)
    fig = figures.to_plotly(spec)
    line = fig.data[0]
    assert list(line.x) == [r["value"] for r in rows] and list(line.y) == [r["hollowness"] for r in rows]
    marks = [t for t in fig.data if t.name and t.name.startswith("current design")]
    assert len(marks) == 1 and list(marks[0].x) == [55.0] and list(marks[0].y) == [0.55]
    vlines = [s for s in fig.layout.shapes if s.type == "line"]
    assert len(vlines) == 1 and vlines[0].x0 == vlines[0].x1 == 55.0
    # matplotlib: the same marker at the same place
    ax = figures.to_matplotlib(spec).axes[0]
    pts = [ln for ln in ax.get_lines() if ln.get_label().startswith("current design")]
    xy = {(float(x), float(y)) for ln in pts for x, y in zip(ln.get_xdata(), ln.get_ydata())}
    assert (55.0, 0.55) in xy
    assert any(list(ln.get_xdata()) == [55.0, 55.0] for ln in pts)  # the vertical line


def test_study_marks_current_design_on_both_panels():
    xs, ys, grid = study()
    spec = figures.study_spec(xs, ys, grid, current=(25.0, 30.0), current_value=25030.0)
    assert [p.kind for p in spec.panels] == ["surface", "heatmap"]
    fig = figures.to_plotly(spec)
    cur = [t for t in fig.data if t.name and t.name.startswith("current design")]
    assert {t.type for t in cur} == {"scatter3d", "scatter"}
    for t in cur:
        assert list(t.x) == [25.0] and list(t.y) == [30.0]
        if t.type == "scatter3d":
            assert list(t.z) == [25030.0]
    best = [t for t in fig.data if t.name and t.name.startswith("max")]
    assert best and all(list(t.x) == [55.0] and list(t.y) == [50.0] for t in best)


def test_orientation_legend_covers_every_region_colour():
    res = synthetic_orientation()
    spec = figures.orientation_spec(res)
    assert len(spec.panels) == 9  # one panel per (line, rotation): regions never overlap or hide
    region_colours = {p.mask.color for p in spec.panels if p.mask is not None}
    assert len(region_colours) == 3
    assert region_colours <= {e.color for e in spec.legend if e.kind == "fill"}
    # plotly: every colour drawn by a region is a legend entry's colour
    fig = figures.to_plotly(spec)
    drawn = {t.colorscale[-1][1] for t in fig.data if t.type == "heatmap"}
    legend = {t.marker.color for t in fig.data if t.showlegend and t.mode == "markers"}
    assert drawn == region_colours and drawn <= legend
    # each heat map is two-valued (transparent / one colour): no blend colours exist
    assert all(t.colorscale[0][1] == "rgba(0,0,0,0)" and len(t.colorscale) == 2 for t in fig.data
               if t.type == "heatmap")
    # matplotlib: the figure legend has a patch of every region colour
    from matplotlib.colors import to_hex

    mfig = figures.to_matplotlib(spec)
    patches = {to_hex(h.get_facecolor()).upper() for h in mfig.legends[0].get_patches()}
    assert {c.upper() for c in region_colours} <= patches
    # the identical tau and psi regions of the z line are both visible
    z_tau = next(p for p in spec.panels if p.mask is not None and p.title.startswith("τ on z"))
    z_psi = next(p for p in spec.panels if p.mask is not None and p.title.startswith("ψ on z"))
    assert np.array_equal(z_tau.mask.inside, z_psi.mask.inside) and z_tau.mask.inside.any()


def test_saturated_delta_is_flagged():
    res = synthetic_orientation(saturate=True)
    sats = figures.orientation_saturation(res)
    assert {(s.line, s.rotation, s.coordinate) for s in sats} == {(ln, "phi_z", "angle") for ln in ("z", "y_prime", "x")}
    assert all(s.delta == 60.0 and s.scan == (-30.0, 30.0) and s.index == "TI_1" for s in sats)
    warning = figures.saturation_warning(res)
    assert "TI₁ is a lower bound" in warning and "TI₂" not in warning and "[-30°, 30°]" in warning
    spec = figures.orientation_spec(res)
    assert spec.warnings == [warning]
    phi = [p for p in spec.panels if p.mask is not None and p.title.startswith("φ")]
    assert all(p.boxes[0].saturated and p.notes for p in phi)
    assert not any(b.saturated for p in spec.panels if not p.title.startswith("φ") for b in p.boxes)
    assert any(e.kind == "saturated" for e in spec.legend)
    # the saturated box is drawn inside the frame: the axis range reaches beyond the scan
    assert all(p.x_range[0] < -30.0 and p.x_range[1] > 30.0 for p in spec.panels)
    fig = figures.to_plotly(spec)
    assert "lower bound" in fig.layout.title.text
    assert sum(1 for s in fig.layout.shapes if s.type == "rect" and s.line.dash == "dashdot") == 3
    # not saturated: nothing flagged
    calm = synthetic_orientation(saturate=False)
    assert figures.orientation_saturation(calm) == [] and figures.saturation_warning(calm) == ""
    assert not figures.orientation_spec(calm).warnings


def test_titles_are_escaped_for_plotly():
    rows = sweep_rows()
    spec = figures.sweep_spec(rows, "a")
    spec = dataclasses.replace(spec, title="<img src=x onerror=alert(1)>")
    assert "<img" not in figures.to_plotly(spec).layout.title.text


def test_cli_never_loads_plotly(tmp_path):
    """``paraspace sweep --plot`` draws with matplotlib; plotly stays a web-side dependency."""
    code = ("import sys, paraspace.app.figures as f\n"
            "rows = [{'value': 1.0, 'volume': 2.0}, {'value': 2.0, 'volume': 3.0}]\n"
            "f.export(f.sweep_spec(rows, 'a', current=1.5), 'svg')\n"
            "print('plotly' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_export_format_by_suffix():
    assert [figures.export_format(n) for n in ("a.png", "b.SVG", "c.pdf")] == ["png", "svg", "pdf"]
    with pytest.raises(ValueError):
        figures.export_format("x.doc")
