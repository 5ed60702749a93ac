"""Workspace measures against shapes whose answers are known independently (analytic volumes,
topology by construction, marching-cubes Euler characteristic)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from skimage.measure import marching_cubes

from paraspace.kinematics import column_counts
from paraspace.kinematics import euler as euler_mod
from paraspace.kinematics import morphology as morph_mod
from paraspace.kinematics import voids as voids_mod
from paraspace.kinematics.design import Design
from paraspace.kinematics.grid import GridSpec
from paraspace.kinematics.measures import box_contact_fraction, measure_fields, measure_workspace, touched_faces
from paraspace.kinematics.run_components import LabelledComponents, RunComponents
from paraspace.kinematics.workspace import WorkspaceResult, WorkspaceSettings, compute_workspace

H = 1.0
N = 44  # grid edge in voxels


def make_result(occ: np.ndarray, *, h: float = H, lo=(-N / 2, -N / 2, -N / 2), z_floor: float = -1000.0,
                chain_mask=None) -> WorkspaceResult:
    """A WorkspaceResult around a hand-made occupancy; by default the box bottom is far from the floor."""
    grid = GridSpec(origin=tuple(float(a + 0.5 * h) for a in lo), h=h, shape=occ.shape)
    settings = WorkspaceSettings(voxel=h, z_floor=z_floor, bounds=(tuple(lo), grid.hi))
    return WorkspaceResult(design=Design(), settings=settings, grid=grid, occupancy=np.asarray(occ, bool),
                           chain_mask=chain_mask, compute_seconds=0.0, n_eta=0)


def coords(lo=(-N / 2, -N / 2, -N / 2), shape=(N, N, N), h=H):
    axes = [lo[a] + h * (np.arange(shape[a]) + 0.5) for a in range(3)]
    return np.meshgrid(*axes, indexing="ij")


X, Y, Z = coords()
R2 = X ** 2 + Y ** 2 + Z ** 2


def ball(r, c=(0.0, 0.0, 0.0)):
    return (X - c[0]) ** 2 + (Y - c[1]) ** 2 + (Z - c[2]) ** 2 <= r * r


def mesh_euler(occ: np.ndarray) -> int:
    """V - E + F of the marching-cubes surface of ``occ`` (independent of the voxel Euler formula)."""
    verts, faces, _, _ = marching_cubes(np.pad(occ.astype(np.float32), 1), 0.5)
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    n_edges = len(np.unique(edges, axis=0))
    return len(verts) - n_edges + len(faces)


def ball_volume(r):
    return 4.0 / 3.0 * math.pi * r ** 3


# ----------------------------------------------------------------------------- basic shapes


def test_solid_ball():
    r = 14.0
    occ = ball(r)
    m = measure_workspace(make_result(occ))
    assert m.voxels == occ.sum() and m.volume == pytest.approx(occ.sum() * H ** 3)
    assert m.volume == pytest.approx(ball_volume(r), rel=0.01)
    assert (m.components, m.voids, m.genus, m.euler_characteristic) == (1, 0, 0, 1)
    assert m.void_volume == 0 and m.void_ratio == 0
    assert m.boundary_closed and m.boundary_complete and m.completeness_reason == "complete"
    assert m.hollowness == 0.0 and m.column_gap_ratio == 0.0  # convex: no cavity of any kind
    assert m.solidity == pytest.approx(1.0)  # digitised convex set fills its own hull
    assert m.touched_faces == [] and m.box_contact_fraction == 0.0
    # bounds: the extreme voxel cubes; the lattice points with |p| <= 14 reach +-13.5 at centres
    assert m.bounds["min"] == pytest.approx([-14.0] * 3) and m.bounds["max"] == pytest.approx([14.0] * 3)
    assert m.extents == pytest.approx([28.0] * 3)


def test_hollow_ball_void_volume_and_ratios():
    r_out, r_in = 16.0, 9.0
    occ = ball(r_out) & ~ball(r_in)
    m = measure_workspace(make_result(occ))
    assert (m.components, m.voids, m.genus) == (1, 1, 0)
    assert m.euler_characteristic == 2  # b0 - b1 + b2 = 1 - 0 + 1
    assert m.void_volume == pytest.approx(ball_volume(r_in), rel=0.03)
    expected = (r_in / r_out) ** 3
    assert m.void_ratio == pytest.approx(expected, rel=0.05)
    assert m.column_gap_ratio == pytest.approx(expected, rel=0.05)
    assert m.hollowness == pytest.approx(expected, rel=0.05)  # the void is under the top and in the hull
    assert m.boundary_closed and m.boundary_complete  # a sealed void is not a leak


def test_solid_torus_genus_one():
    big, small = 12.0, 5.0
    occ = (np.sqrt(X ** 2 + Y ** 2) - big) ** 2 + Z ** 2 <= small ** 2
    m = measure_workspace(make_result(occ))
    assert (m.components, m.voids, m.genus, m.euler_characteristic) == (1, 0, 1, 0)
    assert m.volume == pytest.approx(2 * math.pi ** 2 * big * small ** 2, rel=0.02)
    assert m.boundary_closed and not m.boundary_complete
    assert "genus 1" in m.completeness_reason
    assert not measure_workspace(make_result(occ), completeness="topological").boundary_complete


def test_two_separated_balls():
    occ = ball(7.0, (-11.0, 0.0, 0.0)) | ball(7.0, (11.0, 0.0, 0.0))
    m = measure_workspace(make_result(occ))
    assert m.components == 2 and m.filled_components == 2
    assert m.genus == 0 and m.euler_characteristic == 2
    assert not m.boundary_closed and not m.boundary_complete
    assert "2 separate pieces" in m.completeness_reason
    assert m.largest_component_fraction == pytest.approx(0.5)
    # hull = capsule; under each ball, on its inner half, lies the gap between the capsule's
    # cylinder (z = -sqrt(R^2 - y^2)) and the ball: per ball (1/2)(8/3 - 2 pi/3) R^3
    gap = 2 * (4.0 / 3.0 - math.pi / 3.0)
    assert m.hollowness == pytest.approx(gap / (gap + 8.0 * math.pi / 3.0), rel=0.1)


def test_connectivity_choice_on_diagonal_contact():
    occ = np.zeros((6, 6, 6), bool)
    occ[1:3, 1:3, 1:3] = True
    occ[3:5, 3:5, 3:5] = True  # touches the first cube at one corner only
    res = make_result(occ, lo=(0.0, 0.0, 0.0))
    assert measure_workspace(res, connectivity=1).components == 2
    assert measure_workspace(res, connectivity=3).components == 1
    with pytest.raises(ValueError, match="connectivity"):
        measure_workspace(res, connectivity=2)


def test_void_needs_dual_connectivity():
    """A hollow cube whose two-voxel wall has a staircase gap meeting only along an edge: a
    6-connected solid leaks through it (its complement is 26-connected), a 26-connected solid
    seals it (its complement is 6-connected)."""
    occ = np.zeros((11, 11, 11), bool)
    occ[1:10, 1:10, 1:10] = True
    occ[3:8, 3:8, 3:8] = False  # cavity 5^3 behind walls two voxels thick
    occ[1, 5, 5] = False  # outer wall layer, open to the outside
    occ[2, 6, 5] = False  # inner wall layer, open to the cavity; shares only an edge with (1, 5, 5)
    res = make_result(occ, lo=(0.0, 0.0, 0.0))
    m6, m26 = measure_workspace(res, connectivity=1), measure_workspace(res, connectivity=3)
    # for the 6-solid the cavity is a dent reached through the gap (a shell with one hole is a
    # ball: chi = 1); for the 26-solid it is a sealed void (chi = 1 + 1)
    assert (m6.voids, m6.genus, m6.euler_characteristic) == (0, 0, 1)
    assert (m26.voids, m26.genus, m26.euler_characteristic) == (1, 0, 2)
    assert m26.void_volume == pytest.approx(125.0 + 1.0)  # cavity + the inner gap voxel
    occ[2, 5, 5] = False  # a straight hole: leaks for both
    assert measure_workspace(make_result(occ, lo=(0.0, 0.0, 0.0)), connectivity=3).voids == 0


# ----------------------------------------------------------------------------- box and floor


def test_solid_touching_a_box_face_is_not_closed():
    occ = ball(14.0, (16.0, 0.0, 0.0))  # sticks out of the x+ face (box ends at x = 22)
    m = measure_workspace(make_result(occ))
    assert m.touched_faces == ["x+"] and m.clipped_faces == ["x+"]
    assert m.components == 1 and not m.boundary_closed and not m.boundary_complete
    assert "x+" in m.completeness_reason
    # fraction of the box's surface voxels that are reachable: the disc cut by the plane x = 21.5
    face = occ[-1].sum()
    n_surface = N ** 3 - (N - 2) ** 3
    assert m.box_contact_fraction == pytest.approx(face / n_surface)
    assert face == pytest.approx(math.pi * (14.0 ** 2 - 5.5 ** 2), rel=0.05)


def bowl(r_out, r_in, z0=0.0, lo_z=0.0):
    """Hemispherical shell open downward, centre at height z0, on a grid whose bottom is lo_z."""
    lo = (-N / 2, -N / 2, lo_z)
    x, y, z = coords(lo=lo, shape=(N, N, 28))
    rr = x ** 2 + y ** 2 + (z - z0) ** 2
    return (rr <= r_out ** 2) & (rr > r_in ** 2) & (z >= z0), lo


def test_inverted_bowl_on_the_floor():
    r_out, r_in = 20.0, 13.0
    occ, lo = bowl(r_out, r_in)
    res = make_result(occ, lo=lo, z_floor=0.0)
    m = measure_workspace(res)
    expected = (r_in / r_out) ** 3  # inner hemisphere / outer hemisphere
    assert m.hollowness == pytest.approx(expected, rel=0.05)
    assert measure_workspace(res, hollowness="shadow").hollowness == pytest.approx(expected, rel=0.05)
    assert m.column_gap_ratio == 0.0  # every column crosses the shell once
    assert m.voids == 0  # the underside is open downward
    assert m.sealed_cavity_volume == pytest.approx(m.hollow_volume)  # ... but sealed by the base
    assert m.open_cavity_ratio == 0.0
    assert m.floor_face == "z-" and m.touched_faces == ["z-"] and m.clipped_faces == []
    assert m.genus == 0 and m.boundary_closed and m.boundary_complete
    strict = measure_workspace(res, floor_closes=False)
    assert strict.clipped_faces == ["z-"] and not strict.boundary_closed and not strict.boundary_complete


def test_floating_bowl_is_incomplete_and_a_window_adds_genus():
    r_out, r_in = 20.0, 13.0
    occ, lo = bowl(r_out, r_in, z0=3.0)  # rim 3 units above the floor: the cavity leaks
    m = measure_workspace(make_result(occ, lo=lo, z_floor=0.0))
    assert m.touched_faces == [] and m.boundary_closed and m.genus == 0
    assert m.hollowness > 0.2
    assert m.open_cavity_ratio == pytest.approx(m.hollowness, rel=0.05)
    assert not m.boundary_complete and "not enclosed" in m.completeness_reason
    assert measure_workspace(make_result(occ, lo=lo, z_floor=0.0), completeness="topological").boundary_complete

    occ, lo = bowl(r_out, r_in)  # on the floor, but with a window drilled through the wall
    x, y, z = coords(lo=lo, shape=occ.shape)
    window = (y ** 2 + (z - 8.0) ** 2 <= 3.5 ** 2) & (x > 0)
    m = measure_workspace(make_result(occ & ~window, lo=lo, z_floor=0.0))
    assert m.genus == 1 and m.boundary_closed and not m.boundary_complete
    assert m.open_cavity_ratio > 0.1  # the cavity leaks through the window


def test_upright_cup_and_overhangs():
    occ, lo = bowl(20.0, 13.0)
    cup = occ[:, :, ::-1]  # open upward: its hollow is not under the workspace
    m = measure_workspace(make_result(cup, lo=lo))
    assert m.hollowness == 0.0 and m.column_gap_ratio == 0.0
    # a solid ball: hull definition 0, shadow definition counts the space under its lower half
    occ = ball(14.0)
    shadow = measure_workspace(make_result(occ), hollowness="shadow").hollowness
    assert shadow == pytest.approx(0.2, abs=0.02)  # (pi R^3 / 3) / (pi R^3 / 3 + 4 pi R^3 / 3)
    with pytest.raises(ValueError, match="hull, shadow"):
        measure_workspace(make_result(occ), hollowness="enclosed")


# ----------------------------------------------------------------------------- Euler cross-check


@pytest.mark.parametrize("name", ["ball", "hollow", "torus", "two", "double_torus"])
def test_voxel_euler_matches_marching_cubes_surface(name):
    """chi(surface) = 2 chi(solid); for the filled solid, chi(outer surface) = 2 (b0 - genus)."""
    shapes = {
        "ball": ball(13.0),
        "hollow": ball(15.0) & ~ball(8.0),
        "torus": (np.sqrt(X ** 2 + Y ** 2) - 12.0) ** 2 + Z ** 2 <= 25.0,
        "two": ball(7.0, (-11.0, 0.0, 0.0)) | ball(7.0, (11.0, 0.0, 0.0)),
        "double_torus": ((np.sqrt((X - 9.0) ** 2 + Y ** 2) - 7.0) ** 2 + Z ** 2 <= 9.0)
        | ((np.sqrt((X + 9.0) ** 2 + Y ** 2) - 7.0) ** 2 + Z ** 2 <= 9.0),
    }
    occ = shapes[name]
    m = measure_workspace(make_result(occ))
    assert mesh_euler(occ) == 2 * m.euler_characteristic
    from paraspace.kinematics.voids import void_mask

    filled = occ | void_mask(occ)
    assert mesh_euler(filled) == 2 * (m.filled_components - m.genus)
    assert m.genus == {"ball": 0, "hollow": 0, "torus": 1, "two": 0, "double_torus": 2}[name]


# ----------------------------------------------------------------------------- chain binding


def test_chain_binding_of_two_overlapping_balls():
    """Chain 1 feasible in ball A, chain 2 in ball B, chain 3 everywhere: W = A n B."""
    r, d = 10.0, 8.0
    a, b = ball(r, (-d / 2, 0, 0)), ball(r, (d / 2, 0, 0))
    mask = (a * 1 + b * 2 + 4).astype(np.uint8)
    m = measure_workspace(make_result(a & b, chain_mask=mask))
    cb = m.chain_binding
    lens = math.pi * (4 * r + d) * (2 * r - d) ** 2 / 12.0
    box = float(N ** 3)
    assert m.volume == pytest.approx(lens, rel=0.03)
    assert cb["union_volume"] == pytest.approx(box)  # chain 3 is feasible everywhere
    assert cb["lost_volume"] == pytest.approx(box - lens, rel=0.01)
    c1, c2, c3 = cb["chains"]
    assert c1["feasible_volume"] == pytest.approx(ball_volume(r), rel=0.02)
    # chain 1 fails outside A: everywhere in the box but A (the lost region excludes A n B)
    assert c1["fails_volume"] == pytest.approx(box - ball_volume(r), rel=0.01)
    assert c1["sole_limiter_volume"] == pytest.approx(ball_volume(r) - lens, rel=0.03)  # B \ A
    assert c1["fails_fraction"] == pytest.approx(c2["fails_fraction"], rel=1e-6)  # mirror images
    assert c3["fails_volume"] == 0 and c3["sole_limiter_volume"] == 0
    assert c3["only_volume"] == pytest.approx(box - (2 * ball_volume(r) - lens), rel=0.01)
    assert c3["boundary_fails_fraction"] == 0.0
    # the surface of A n B is shaped by chain 1 on B's side and chain 2 on A's side, half each
    assert c1["boundary_fails_fraction"] == pytest.approx(0.5, abs=0.05)
    assert "chain 3 fails in 0%" in cb["summary"]


# ----------------------------------------------------------------------------- serialisation


def _plain_only(x):
    if isinstance(x, dict):
        return all(isinstance(k, str) and _plain_only(v) for k, v in x.items())
    if isinstance(x, list):
        return all(_plain_only(v) for v in x)
    return x is None or type(x) in (bool, int, float, str)


def test_to_dict_is_plain_json():
    mask = (ball(10.0) * 7).astype(np.uint8)
    for occ, cm in [(ball(10.0), mask), (np.zeros((N, N, N), bool), None)]:
        d = measure_workspace(make_result(occ, chain_mask=cm)).to_dict()
        assert _plain_only(d)
        assert json.loads(json.dumps(d)) == d


def test_empty_workspace():
    m = measure_workspace(make_result(np.zeros((8, 8, 8), bool)))
    assert m.volume == 0 and m.voxels == 0 and m.components == 0 and m.bounds is None
    assert m.extents == [0.0, 0.0, 0.0] and not m.boundary_closed and not m.boundary_complete


# ----------------------------------------------------------------------------- the real design


@pytest.fixture(scope="module")
def default_h6():
    return compute_workspace(Design(), WorkspaceSettings(voxel=6.0, diagnostics=True))


def test_default_design_measures(default_h6):
    res = default_h6
    m = measure_workspace(res)
    assert m.volume == pytest.approx(res.volume) and m.volume == pytest.approx(5.12e6, rel=0.02)
    assert (m.components, m.voids, m.genus) == (1, 0, 0)
    assert m.touched_faces == ["z-"] and m.floor_face == "z-"  # the bowl stands on the base
    assert m.boundary_closed and m.boundary_complete  # as the paper says for this design
    assert 0.3 < m.hollowness < 0.5  # the inverted bowl's underside cavity
    assert m.sealed_cavity_volume == pytest.approx(m.hollow_volume)
    assert m.column_gap_ratio < 0.01
    # the extents are those of the reachable voxels
    idx = np.argwhere(res.occupancy)
    assert m.extents[2] == pytest.approx((idx[:, 2].max() - idx[:, 2].min() + 1) * res.grid.h)
    # 3-fold symmetric mechanism: the chains bind about equally; chains 2 and 3 are mirror images
    c1, c2, c3 = m.chain_binding["chains"]
    assert c2["fails_volume"] == c3["fails_volume"]
    assert abs(c1["fails_fraction"] - c2["fails_fraction"]) < 0.02
    assert c1["fails_fraction"] + c2["fails_fraction"] + c3["fails_fraction"] >= 1.0


@pytest.mark.parametrize("a", [50.0, 10.0, 80.0])
def test_measures_do_not_depend_on_empty_space_around_the_workspace(a):
    """measure_workspace works on the workspace's box (issue 10): the same occupancy inside a grid
    with 12 more empty layers in x and y and 7 on top gives the same measures (except the ones that
    describe the box itself)."""
    import dataclasses

    from paraspace.kinematics.grid import GridSpec
    from paraspace.kinematics.measures import measure_workspace
    from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

    res = compute_workspace(Design(a=a), WorkspaceSettings(voxel=4.0))
    g = res.grid
    pad = ((12, 12), (12, 12), (0, 7))
    big = dataclasses.replace(
        res, occupancy=np.pad(res.occupancy, pad),
        grid=GridSpec(origin=(g.origin[0] - 12 * g.h, g.origin[1] - 12 * g.h, g.origin[2]), h=g.h,
                      shape=tuple(n + p[0] + p[1] for n, p in zip(g.shape, pad))))
    m0, m1 = measure_workspace(res).to_dict(), measure_workspace(big).to_dict()
    for key in ("touched_faces", "clipped_faces", "box_contact_fraction", "boundary_closed", "boundary_complete",
                "completeness_reason"):
        m0.pop(key), m1.pop(key)
    assert m0 == m1


def test_each_measure_alone_equals_the_full_measurement_and_computes_only_its_steps(monkeypatch):
    """Issue 24 target 2: ``measure_fields`` with one field computes only the steps that field needs
    and gives the number the full ``measure_workspace`` gives, on several designs (chain masks too)
    and both connectivities; ``volume`` alone labels nothing and builds no hull."""
    from paraspace.kinematics import measures as mod

    for design in (Design(), Design(a=10), Design(l_s=20)):
        res = compute_workspace(design, WorkspaceSettings(voxel=6.0, diagnostics=True))
        for kw in ({}, {"connectivity": 3, "hollowness": "shadow", "completeness": "topological"}):
            full = measure_workspace(res, **kw).to_dict()
            for name in mod.MEASURE_FIELDS:
                one = mod.measure_fields(res, [name], **kw)
                assert json.loads(json.dumps(mod.jsonable(one[name]))) == full[name], name
    calls = []
    monkeypatch.setattr(mod, "hull_ranges", lambda *a: calls.append("hull"))
    monkeypatch.setattr(mod.ndi, "label", lambda *a, **k: calls.append("label"))
    monkeypatch.setattr(mod, "RunComponents", lambda *a, **k: calls.append("label"))
    one = mod.measure_fields(res, ["volume", "extents"])
    assert one["volume"] == full["volume"] and one["extents"] == full["extents"] and calls == []
    assert "components" not in one and "hollowness" not in one
    with pytest.raises(ValueError, match="names"):
        mod.measure_fields(res, ["volumes"])


def _slow_measures(monkeypatch):
    """Patch kinematics.measures back to its former path: components by a labelled grid and skimage's
    Euler number (:class:`LabelledComponents`), voids by labelling
    the whole padded complement, int32 dilations of the whole grid, every hull facet at every
    column, column gaps and cover by cumulative ors."""
    from scipy import ndimage as ndi

    from paraspace.kinematics import measures as mod

    def voids(occ, conn, runs=None, ends=None):  # the set's runs and x ends are not used on this path
        v = voids_mod.void_mask_labelled(occ, conn)
        return v, int(ndi.label(v, structure=voids_mod._structure(voids_mod.dual_connectivity(conn)))[1])

    def hollow(occ, mode="hull", hull=None):
        occ = np.asarray(occ, bool)
        u = np.logical_or.accumulate(occ[:, :, ::-1], axis=2)[:, :, ::-1] & ~occ
        if mode == "shadow":
            u[:, :, :int(np.argmax(occ.any(axis=(0, 1))))] = False
            return u
        return u & (mod.hull_mask(occ, raster=False) if hull is None else hull)

    # components by scipy's labelled grid, the Euler number by skimage (LabelledComponents)
    monkeypatch.setattr(mod, "RunComponents", LabelledComponents)
    monkeypatch.setattr(mod, "_voids", voids)
    monkeypatch.setattr(mod, "feature_filter", morph_mod.feature_filter_reference)
    hull = mod.hull_mask
    monkeypatch.setattr(mod, "hull_mask", lambda occ, raster=False: hull(occ, raster=False))
    monkeypatch.setattr(mod, "hollow_mask", hollow)
    monkeypatch.setattr(mod, "column_gap_count", lambda occ: int(mod.column_gap_mask(occ).sum()))
    # the hull, its underside, the sealed part of it and the gaps counted on the grid by the definitions
    for name in ("hull_ranges", "under_ranges", "gap_count", "count_in_ranges"):
        monkeypatch.setattr(mod, name, getattr(column_counts, name + "_reference"))


def test_fast_measures_equal_the_former_path_on_several_designs(monkeypatch):
    """Issue 24 target 1: the measures' kernels (Euler numbers from one pass of configuration counts,
    voids from the voxels enclosed along all three axes, capped and mirrored dilations, tiled hull
    columns, column passes) give every measure of the former path (skimage, whole-complement
    labelling, int32 dilations, every facet at every column, cumulative ors), on several designs,
    both connectivities, at coarse voxels; and each kernel equals its reference on random fields."""
    from skimage.measure import euler_number

    from paraspace.kinematics import measures as mod

    rng = np.random.default_rng(24)
    for _ in range(12):
        occ = rng.random(tuple(rng.integers(2, 14, 3))) < rng.uniform(0.1, 0.9)
        sym = occ | occ[:, ::-1]
        r = rng.uniform(0.8, 4.0)
        for conn in (1, 3):
            assert euler_mod.euler_characteristic(occ, conn) == int(euler_number(occ, connectivity=conn))
            assert np.array_equal(voids_mod.void_mask(occ, conn), voids_mod.void_mask_labelled(occ, conn))
        assert np.array_equal(morph_mod.ball_dilate(sym, r, symmetric=True), morph_mod.ball_dilate_reference(sym, r))
        assert np.array_equal(morph_mod.ball_dilate(occ, r, complement=True), ~morph_mod.ball_dilate_reference(~occ, r))
        assert np.array_equal(mod.hull_mask(occ), mod.hull_mask(occ, raster=False))
        assert mod.column_gap_count(occ) == int(mod.column_gap_mask(occ).sum())
    results = [compute_workspace(d, WorkspaceSettings(voxel=6.0)) for d in (Design(), Design(a=10), Design(l_s=20))]
    options = ({}, {"connectivity": 3, "hollowness": "shadow", "completeness": "topological"})
    fast = [measure_workspace(res, **kw).to_dict() for res in results for kw in options]
    _slow_measures(monkeypatch)
    slow = [measure_workspace(res, **kw).to_dict() for res in results for kw in options]
    assert fast == slow


def test_void_flood_and_extreme_hull_points_equal_the_former_path():
    """Issue 24 target 1: the voids by a flood from the leaking candidates (kinematics/void_flood.py)
    are the set and number of the former labelling of every candidate component, and of the
    definition (the whole padded complement labelled); the hull from the extreme column ends only is
    the mask of the hull of every column end; on random fields and on designs with and without voids
    (with the base layer of ``sealed_mask``: a large sealed cavity), both connectivities."""
    from paraspace.kinematics import measures as mod

    rng = np.random.default_rng(2024)
    fields = [rng.random(tuple(rng.integers(2, 12, 3))) < rng.uniform(0.1, 0.9) for _ in range(20)]
    for d, h in ((Design(), 6.0), (Design(l_s=20), 6.0), (Design(a=10), 8.0), (Design(d_s=80), 8.0)):
        occ = compute_workspace(d, WorkspaceSettings(voxel=h)).occupancy
        fields += [occ, np.concatenate([np.ones(occ.shape[:2] + (1,), bool), occ], axis=2)]
    shell = np.zeros((9, 9, 9), bool)  # a hollow cube with a 2-voxel void inside and a speck in it
    shell[1:8, 1:8, 1:8] = True
    shell[3:6, 3:6, 3:5] = False
    shell[4, 4, 3] = True
    fields.append(shell)
    n_with_voids = 0
    for occ in fields:
        for conn in (1, 3):
            voids, n = voids_mod._voids(occ, conn)
            ref, n_ref = voids_mod._voids_labelled_candidates(occ, conn)
            assert np.array_equal(voids, ref) and n == n_ref
            assert np.array_equal(voids, voids_mod.void_mask_labelled(occ, conn))
            n_with_voids += n > 0
        assert np.array_equal(mod.hull_mask(occ), mod.hull_mask(occ, extreme=False))
    assert n_with_voids >= 4  # the comparison saw voids, not only empty sets


def test_run_components_and_separable_seeds_equal_the_former_path(monkeypatch):
    """Issue 24 target 1 (meas2): the components counted from runs along z and the leak seeds of the
    void flood found by separable ors give every measure of the former path (scipy's labelling of
    the grid, every dual neighbour of every candidate tested), on several designs, both option
    sets, and on odd shapes: empty and full grids, a one-voxel grid, a thin odd-sized box, a hollow
    ball with specks beside it (fragments: the pieces' mask is painted from the runs) and a shell
    with a void; the seed kernel equals the former one, the Euler number read on the columns' spans
    equals skimage's and the row-wise dilation equals the int32 reference, on random fields and blobs."""
    from paraspace.kinematics import measures as mod
    from paraspace.kinematics import void_flood

    rng = np.random.default_rng(2411)
    for _ in range(40):
        shape = tuple(rng.integers(1, 12, 3))
        occ = rng.random(shape) < rng.uniform(0.05, 0.95)
        cand = (rng.random(shape) < rng.uniform(0.05, 0.95)) & ~occ
        for full in (False, True):
            new, old = np.empty(shape, bool), np.empty(shape, bool)
            void_flood._seed_kernel(cand, occ, full, new)
            void_flood._seed_kernel_reference(cand, occ, full, old)
            assert np.array_equal(new, old)
    from skimage.measure import euler_number

    for _ in range(40):  # the Euler kernel reads only the columns' spans: fields with empty columns and layers
        occ = rng.random(tuple(rng.integers(1, 12, 3))) < rng.uniform(0.05, 0.95)
        occ[rng.random(occ.shape[:2]) < 0.3] = False
        occ[:, :, :rng.integers(0, occ.shape[2] + 1)] = False
        for conn in (1, 3):
            assert euler_mod.euler_characteristic(occ, conn) == int(euler_number(occ, connectivity=conn))
            # and from the runs: an event sweep per column of windows (runs that start or end at the
            # same height in two columns, columns full to the top, empty columns)
            assert RunComponents(occ, conn).euler_characteristic(conn) == int(euler_number(occ, connectivity=conn))

    from scipy import ndimage as ndi

    for _ in range(30):  # blobs with empty margins: z rows with no set voxel near, skipped by the dilation
        blob = ndi.gaussian_filter(rng.random(tuple(rng.integers(8, 30, 3))), 2.0) > 0.5
        sym = blob | blob[:, ::-1]
        r = rng.uniform(0.8, 6.0)
        assert np.array_equal(morph_mod.ball_dilate(sym, r, symmetric=True), morph_mod.ball_dilate_reference(sym, r))
        assert np.array_equal(morph_mod.ball_dilate(blob, r), morph_mod.ball_dilate_reference(blob, r))
        assert np.array_equal(morph_mod.ball_dilate(sym, r, complement=True, symmetric=True),
                              ~morph_mod.ball_dilate_reference(~sym, r))

    specks = (R2 <= 12 ** 2) & (R2 > 7 ** 2)
    specks[2, 2, 2] = specks[5, 40, 3] = specks[40, 5, 41] = True
    shell = np.zeros((11, 9, 7), bool)
    shell[1:10, 1:8, 1:6] = True
    shell[4:7, 3:6, 3] = False
    odd = np.zeros((3, 17, 5), bool)
    odd[1, 2:15, 1:4] = True
    results = [compute_workspace(d, WorkspaceSettings(voxel=6.0)) for d in (Design(), Design(a=10), Design(l_s=20))]
    results += [make_result(m, lo=(-m.shape[0] / 2, -m.shape[1] / 2, -m.shape[2] / 2)) for m in
                (np.zeros((5, 6, 7), bool), np.ones((5, 6, 7), bool), np.ones((1, 1, 1), bool), odd, shell)]
    results.append(make_result(specks))
    results.append(make_result(specks, z_floor=-N / 2))
    options = ({}, {"connectivity": 3, "hollowness": "shadow", "completeness": "topological"},
               {"piece_fraction": 0.0})
    fast = [measure_workspace(res, **kw).to_dict() for res in results for kw in options]
    assert fast[-6]["fragments"] == 3 and fast[-6]["voids"] == 1  # the specks and the void were seen
    monkeypatch.setattr(mod, "RunComponents", LabelledComponents)  # components and Euler numbers
    # the voids are counted in kinematics.voids
    monkeypatch.setattr(voids_mod, "count_components", lambda occ, conn=1: LabelledComponents(occ, conn).count)
    monkeypatch.setattr(void_flood, "_seed_kernel", void_flood._seed_kernel_reference)
    slow = [measure_workspace(res, **kw).to_dict() for res in results for kw in options]
    assert fast == slow


def _enclosed_by_definition(occ: np.ndarray) -> np.ndarray:
    """Unreachable voxels strictly between the first and the last reachable voxel of their x, y and z
    lines, from cumulative ors from both ends of each axis (the cavities' candidates)."""
    inside = ~occ
    for a in range(3):
        before = np.logical_or.accumulate(occ, axis=a)
        after = np.flip(np.logical_or.accumulate(np.flip(occ, a), axis=a), a)
        inside &= before & after
    return inside


def _between_runs(occ: np.ndarray) -> np.ndarray:
    """Voxels between the first and the last reachable voxel of their z column (inclusive)."""
    return np.logical_or.accumulate(occ, axis=2) & np.flip(np.logical_or.accumulate(np.flip(occ, 2), axis=2), 2)


def test_parallel_cavities_kernels_equal_the_former_passes():
    """Issue 24 target 7 (cav7): the parallel kernels of the cavities step -- the candidates with
    their per-slice extents (from the grid and from its runs), the grid on its base layer (and its
    runs), the seed count that skips an empty flood,
    the box's copy and paste, the open/sealed counts, the x ends of the grid on its base layer from the
    grid's own -- and the per-slice count and extent of the
    grid (the measures' bounds and crop) give exactly their definitions or the former serial passes
    (the candidates from cumulative ors along each axis, numpy's ``any`` box, ``concatenate``,
    ``ascontiguousarray``, slice assignment, ``count_nonzero``) and the voids of the labelled
    definition, on designs and odd shapes (empty, full, one voxel, a shell with a sealed void, a box
    open at one side, a box open at its bottom, random fields), with 1 and 2 numba threads."""
    import numba

    from paraspace.kinematics import measures as mod
    from paraspace.kinematics import void_flood

    rng = np.random.default_rng(2711)
    shell = np.zeros((11, 9, 7), bool)
    shell[1:10, 1:8, 1:6] = True
    shell[4:7, 3:6, 3] = False
    cup = np.zeros((10, 9, 8), bool)  # a box open at its top: nothing sealed without the floor
    cup[1:9, 1:8, 1:7] = True
    cup[3:7, 3:6, 3:] = False
    bowl = np.zeros((10, 9, 8), bool)  # a box open at its bottom face: sealed only by the base layer
    bowl[1:9, 1:8, :7] = True
    bowl[3:7, 3:6, :5] = False
    shapes = [np.zeros((5, 6, 7), bool), np.ones((5, 6, 7), bool), np.ones((1, 1, 1), bool),
              np.zeros((1, 1, 1), bool), np.zeros((0, 3, 4), bool), shell, cup, bowl]
    shapes += [rng.random(tuple(rng.integers(1, 14, 3))) < rng.uniform(0.3, 0.95) for _ in range(25)]
    shapes += [np.asarray(compute_workspace(d, WorkspaceSettings(voxel=6.0)).occupancy, bool)
               for d in (Design(), Design(a=10), Design(l_s=20))]
    threads = [n for n in (1, 2) if n <= numba.config.NUMBA_NUM_THREADS]
    before = numba.get_num_threads()
    try:
        for n in threads:
            numba.set_num_threads(n)
            for occ in shapes:
                occ = np.ascontiguousarray(occ)
                floored = np.concatenate([np.ones(occ.shape[:2] + (1,), bool), occ], axis=2)
                for grid in (occ, floored):
                    if not grid.size:
                        assert voids_mod._candidates_box(grid) is None
                        continue
                    old, new = _enclosed_by_definition(grid), np.ones(grid.shape, bool)
                    ext = np.empty((grid.shape[0], 4), np.int64)
                    voids_mod._enclosed_ext_kernel(grid, new, ext)
                    assert np.array_equal(new, old)
                    # from the runs: the same candidates and slice extents; the floored grid's runs
                    # built from the set's equal its own
                    runs = RunComponents(grid).runs
                    n0, n1, n2 = grid.shape
                    fx, lx = np.empty((n1, n2), np.int32), np.empty((n1, n2), np.int32)
                    voids_mod._x_ends_runs_kernel(*runs, n0, n1, fx, lx)
                    on = grid.any(axis=0)  # the x ends by their definition (n0, -1 on an empty line)
                    assert np.array_equal(fx, np.where(on, np.argmax(grid, axis=0), n0))
                    assert np.array_equal(lx, np.where(on, n0 - 1 - np.argmax(grid[::-1], axis=0), -1))
                    from_runs, ext_runs = np.zeros(grid.shape, bool), np.empty_like(ext)
                    voids_mod._enclosed_runs_kernel(*runs, n1, n2, fx, lx, from_runs, ext_runs)
                    assert np.array_equal(from_runs, old) and np.array_equal(ext_runs, ext)
                    from_runs[...] = True  # only the gaps are written: the rest keeps what was there
                    voids_mod._enclosed_runs_kernel(*runs, n1, n2, fx, lx, from_runs, ext_runs)
                    assert np.array_equal(from_runs, old | grid | ~_between_runs(grid))
                    if grid is floored:
                        built = voids_mod._floored_runs(*RunComponents(occ).runs)
                        assert all(np.array_equal(a, b) for a, b in zip(built, runs))
                        # the floored grid's x ends from the set's own: the same as from its runs
                        ffx, flx = voids_mod.floored_x_ends(voids_mod.x_ends(RunComponents(occ).runs, occ.shape), n0)
                        assert np.array_equal(ffx, fx) and np.array_equal(flx, lx)
                    found = voids_mod._candidates_box(grid)
                    from_runs = voids_mod._candidates_box(None, runs, grid.shape)  # type: ignore[assignment]
                    if not old.any():
                        assert found is None and from_runs is None
                        continue
                    flags = [old.any(axis=a) for a in ((1, 2), (0, 2), (0, 1))]
                    box = tuple(slice(int(np.argmax(f)) - 1, len(f) - int(np.argmax(f[::-1])) + 1) for f in flags)
                    outside = old.copy()
                    outside[box] = False
                    assert not outside.any()  # every candidate in the box
                    for got in (found, from_runs):  # the set and its candidates cut to the box, contiguous
                        assert got[2] == box
                        assert np.array_equal(got[1], old[box]) and np.array_equal(got[0], grid[box])
                        assert got[0].flags.c_contiguous and got[1].flags.c_contiguous
                if occ.size:
                    out = np.zeros(floored.shape, bool)
                    voids_mod._floored_kernel(occ, out)
                    assert np.array_equal(out, floored)
                    cut = tuple(slice(a // 3, a - a // 4) for a in occ.shape)
                    sub = occ[cut]
                    assert np.array_equal(void_flood._contiguous(sub), np.ascontiguousarray(sub))
                    pasted, ref = np.ones(occ.shape, bool), np.zeros(occ.shape, bool)
                    ref[cut] = sub
                    voids_mod._paste_kernel(np.ascontiguousarray(sub), *(c.start for c in cut), pasted)
                    assert np.array_equal(pasted, ref)
                    # with its corner below the grid's floor along z (the sealed cavities' layer shift)
                    shift = cut[2].start + 1
                    pasted[...] = True
                    ref[...] = False
                    ref[cut[0], cut[1], :max(cut[2].stop - shift, 0)] = sub[:, :, shift - cut[2].start:]
                    voids_mod._paste_kernel(np.ascontiguousarray(sub), cut[0].start, cut[1].start,
                                            cut[2].start - shift, pasted)
                    assert np.array_equal(pasted, ref)
                    ext = np.empty((occ.shape[0], 11), np.int64)
                    mod._occ_extent_kernel(occ, ext)
                    assert int(ext[:, 0].sum()) == int(np.count_nonzero(occ))
                    assert np.array_equal(ext[:, 0], occ.sum(axis=(1, 2)))
                    n1 = occ.shape[1]
                    for i in range(occ.shape[0]):
                        js, ks = np.nonzero(occ[i])
                        assert list(ext[i, 1:5]) == ([js.min(), js.max(), ks.min(), ks.max()] if js.size
                                                     else [occ.shape[1], -1, occ.shape[2], -1])
                        # the voxels on the faces: rows j = 0 and n_y - 1, the z ends of the other rows
                        # and of those two
                        edge = [0] if n1 == 1 else [0, n1 - 1]
                        inner = occ[i, 1:n1 - 1]
                        assert list(ext[i, 5:11]) == [
                            occ[i, 0].sum(), occ[i, n1 - 1].sum(), inner[:, 0].sum(), inner[:, -1].sum(),
                            occ[i, edge, 0].sum(), occ[i, edge, -1].sum()]
                for conn in (1, 3):
                    for floor in (False, True):
                        sealed = voids_mod.sealed_mask(occ, conn, floor=floor)
                        ref = (voids_mod.void_mask_labelled(floored, conn)[:, :, 1:] if floor
                               else voids_mod.void_mask_labelled(occ, conn))
                        assert np.array_equal(sealed, ref)
                        if occ.size:  # with the set's runs: the same set
                            with_runs = voids_mod.sealed_mask(occ, conn, floor=floor, runs=RunComponents(occ).runs)
                            assert np.array_equal(with_runs, ref)
                        if occ.size:  # the sealed voxels in their box, counted under a random set
                            occ_runs = RunComponents(occ).runs
                            for runs, ends in ((None, None), (occ_runs, None),
                                               (occ_runs, voids_mod.x_ends(occ_runs, occ.shape))):
                                found = voids_mod.sealed_box(occ, conn, floor=floor, runs=runs, ends=ends)
                                assert (found is None) == (not ref.any())
                                if found is None:
                                    continue
                                sub, (i0, j0, k0) = found
                                m0, m1, m2 = sub.shape
                                assert not sub[:, :, :max(0, -k0)].any()  # the base layer is never sealed
                                inside = np.zeros(occ.shape, bool)
                                inside[i0:i0 + m0, j0:j0 + m1, max(k0, 0):k0 + m2] = sub[:, :, max(0, -k0):]
                                assert np.array_equal(inside, ref)
                                lo, hi = rng.integers(-2, occ.shape[2] + 2, (2,) + occ.shape[:2])
                                ranges = column_counts.ColumnRanges(lo, hi, 0)
                                got = column_counts.count_in_ranges(ranges, sub, (i0, j0, k0))
                                k = np.arange(occ.shape[2])
                                within = (k >= lo[:, :, None]) & (k <= hi[:, :, None])
                                assert got == int(np.count_nonzero(within & ref))
                                assert got == column_counts.count_in_ranges_reference(ranges, sub, (i0, j0, k0))
            assert voids_mod.sealed_mask(bowl, 1, floor=True).any()
            assert not voids_mod.sealed_mask(bowl, 1, floor=False).any()
            assert voids_mod.sealed_mask(shell, 1, floor=False).sum() == 9 and not voids_mod.sealed_mask(cup, 1).any()
    finally:
        numba.set_num_threads(before)


def test_hull_raster_equals_every_facet_at_every_column():
    """The hull's columns from the triangles whose projection covers them (kinematics/hull.py,
    the default) equal those from every facet's inequality tested at every column, on a rough blob,
    tilted slabs and wedges (facets nearly vertical, nearly flat, and columns on their edges), lines
    and planes of voxels (no 3-D hull), single columns, and random fields; and the hull contains the
    set and is convex along every grid line (the mask of a convex set)."""
    from paraspace.kinematics import hull as mod

    rng = np.random.default_rng(7)
    x, y, z = np.ogrid[-1:1:150j, -1:1:133j, -1:1:24j]
    fields = [(x ** 2 + 1.3 * y ** 2 + (z + 0.2 * x * y) ** 2 < 0.8) & (rng.random((150, 133, 24)) < 0.97)]
    i, j, k = np.ogrid[:40, :37, :30]
    fields += [np.abs(3 * i - 2 * j + 5 * k - 60) <= 4, (i + j <= 45) & (k <= (i + 2 * j) // 5) & (k >= i // 7),
               (i == 20) & (j == 5) & (k > 3), (i == 20) & np.ones_like(j, bool) & (k < 12), (k == 0) & (i + j < 30),
               (np.abs(i - 20) + np.abs(j - 18) + np.abs(k - 15) <= 12)]
    fields += [rng.random(tuple(rng.integers(2, 16, 3))) < rng.uniform(0.02, 0.9) for _ in range(60)]
    hulls = 0
    for occ in fields:
        occ = np.broadcast_to(occ, np.broadcast_shapes(occ.shape, (1, 1, 1))).copy()
        fast = mod.hull_mask(occ)
        assert np.array_equal(fast, mod.hull_mask(occ, raster=False))
        assert not (occ & ~fast).any()
        for axis in range(3):  # no gap inside a line of the mask
            first = np.argmax(fast, axis=axis)
            last = fast.shape[axis] - 1 - np.argmax(np.flip(fast, axis=axis), axis=axis)
            counts = fast.sum(axis=axis)
            assert np.all((counts == 0) | (counts == last - first + 1))
        hulls += int(fast.sum() > occ.sum())
    assert hulls >= 40  # most fields have a hull larger than themselves


def test_column_counts_from_the_runs_equal_the_grid_definitions():
    """The hull volume, the hull underside, the column gaps and the sealed underside counted from the
    runs per column (kinematics/column_counts.py) equal the grid definitions: the hull's mask
    (kinematics/hull.py), the covered voxels by cumulative ors, ``column_gap_mask``, and the sealed
    mask painted and counted; on random fields, a bowl on the floor, a hollow ball, lines and
    planes of voxels (no 3-D hull: ``K = W``, no underside) and single voxels; and each count equals its
    ``*_reference`` (the tests' slow path)."""
    from paraspace.kinematics import measures as mod

    rng = np.random.default_rng(2412)
    sealed_seen = unders_seen = 0
    i, j, k = np.ogrid[:24, :21, :18]
    ball = (i - 12) ** 2 + (j - 10) ** 2 + (k - 8) ** 2
    dome = (i - 12) ** 2 + (j - 10) ** 2 + k ** 2  # a dome standing on the floor: its underside sealed
    fields = [(ball <= 64) & (ball >= 25), (ball <= 64) & (ball >= 25) & (k >= 8), (dome <= 81) & (dome >= 36),
              (i == 3) & (j == 4) & (k > 2),
              (k == 5) & (i + j < 20), np.zeros((3, 4, 5), bool), (i == 2) & (j == 2) & (k == 2)]
    fields += [rng.random(tuple(rng.integers(1, 15, 3))) < rng.uniform(0.02, 0.9) for _ in range(80)]
    for occ in fields:
        occ = np.ascontiguousarray(np.broadcast_to(occ, np.broadcast_shapes(occ.shape, (1, 1, 1))))
        runs = RunComponents(occ).runs
        shape = occ.shape
        kk = np.arange(shape[2])
        assert column_counts.gap_count(runs, shape) == int(mod.column_gap_mask(occ).sum())
        assert column_counts.gap_count(runs, shape) == column_counts.gap_count_reference(runs, shape)
        if not occ.any():
            continue
        hull = column_counts.hull_ranges(runs, shape)
        mask = mod.hull_mask(occ, raster=False)
        # qhull in a thread of its own (what measure_fields starts first): the same ranges
        bg = column_counts.hull_ranges_of(column_counts.start_hull(runs, shape), shape)
        assert (bg is None) == (hull is None)
        if hull is not None:
            assert bg.voxels == hull.voxels and np.array_equal(bg.lo, hull.lo) and np.array_equal(bg.hi, hull.hi)
        if hull is None:  # coplanar centres: the hull is the set, nothing under it
            assert np.linalg.matrix_rank(np.argwhere(occ) - np.argwhere(occ)[0]) < 3
            assert np.array_equal(mask, occ)
            assert column_counts.under_ranges(runs, shape, None).voxels == 0 == int(mod.hollow_mask(occ).sum())
            assert column_counts.hull_ranges_reference(runs, shape) is None
            continue
        within = (kk >= hull.lo[:, :, None]) & (kk <= hull.hi[:, :, None])
        assert np.array_equal(within, mask) and hull.voxels == int(mask.sum())
        ref = column_counts.hull_ranges_reference(runs, shape)
        assert ref.voxels == hull.voxels and np.array_equal(
            (kk >= ref.lo[:, :, None]) & (kk <= ref.hi[:, :, None]), within)
        under = column_counts.under_ranges(runs, shape, hull)
        truth = mod.hollow_mask(occ, "hull")  # covered, in the hull, unreachable
        assert under.voxels == int(truth.sum())
        span = (kk >= under.lo[:, :, None]) & (kk <= under.hi[:, :, None])
        assert np.array_equal(span & ~occ, truth)
        ref = column_counts.under_ranges_reference(runs, shape, hull)
        assert ref.voxels == under.voxels and np.array_equal(
            span, (kk >= ref.lo[:, :, None]) & (kk <= ref.hi[:, :, None]))
        for conn in (1, 3):  # the sealed underside, counted in the sealed voxels' box
            found = voids_mod.sealed_box(occ, conn, floor=True, runs=runs)
            sealed = voids_mod.sealed_mask(occ, conn, floor=True)
            assert not (sealed & occ).any()
            got = 0 if found is None else column_counts.count_in_ranges(under, *found)
            assert got == int(np.count_nonzero(truth & sealed))
            if found is not None:
                assert got == column_counts.count_in_ranges_reference(under, *found)
            sealed_seen += got
        unders_seen += under.voxels
    assert sealed_seen > 0 and unders_seen > 0


def test_hull_mask_against_supporting_planes_by_brute_force():
    """The hull mask (qhull with its input joggled, then the exact lattice raster: kinematics/hull.py)
    equals the brute-force hull of small random sets: every plane through three of the set's centres
    with all of them on one side (exact integers) bounds it, and a voxel is in the hull iff its centre
    is inside every such plane; and equals the exact (unjoggled) hull's every-facet test on designs
    whose lattice hulls have many coplanar points."""
    from itertools import combinations

    from paraspace.kinematics import hull as mod

    rng = np.random.default_rng(31)
    checked = 0
    while checked < 40:
        shape = tuple(int(v) for v in rng.integers(2, 7, 3))
        occ = rng.random(shape) < rng.uniform(0.03, 0.25)
        pts = np.argwhere(occ).astype(np.int64)
        if len(pts) < 4 or np.linalg.matrix_rank(pts - pts[0]) < 3:
            continue
        idx = np.array(list(combinations(range(len(pts)), 3)))
        a, b, c = pts[idx[:, 0]], pts[idx[:, 1]], pts[idx[:, 2]]
        n = np.cross(b - a, c - a)
        d = np.einsum("ij,ij->i", n, a)
        side = pts @ n.T - d  # (points, planes)
        n, d, side = n[np.any(n != 0, axis=1)], d[np.any(n != 0, axis=1)], side[:, np.any(n != 0, axis=1)]
        flip = np.all(side >= 0, axis=0)
        keep = flip | np.all(side <= 0, axis=0)
        n = np.where(flip[:, None], -n, n)[keep]
        d = np.where(flip, -d, d)[keep]
        centres = np.argwhere(np.ones(shape, bool))
        inside = np.all(centres @ n.T <= d, axis=1).reshape(shape)
        assert np.array_equal(mod.hull_mask(occ), inside), shape
        checked += 1
    for design, h in ((Design(d_s=80), 1.0), (Design(), 2.0), (Design(a=10), 1.5)):
        occ = compute_workspace(design, WorkspaceSettings(voxel=h)).occupancy
        assert np.array_equal(mod.hull_mask(occ), mod.hull_mask(occ, raster=False))


def test_box_contact_and_touched_faces_against_the_face_voxels():
    # |W n B| / |B| and the touched faces from the face voxels listed by their indices (brute force),
    # by the functions and by measure_workspace's fields
    rng = np.random.default_rng(11)
    for shape in ((1, 1, 1), (2, 3, 4), (3, 3, 3), (4, 5, 6), (7, 2, 9), (9, 8, 7), (5, 1, 4), (3, 6, 1), (6, 4, 3)):
        for p in (0.02, 0.5, 0.97):
            occ = rng.random(shape) < p
            idx = np.indices(shape)
            on = np.zeros(shape, bool)
            faces = []
            for a in range(3):
                for side, k in (("-", 0), ("+", shape[a] - 1)):
                    layer = idx[a] == k
                    on |= layer
                    if (occ & layer).any():
                        faces.append("xyz"[a] + side)
            assert box_contact_fraction(occ) == (occ & on).sum() / on.sum(), shape
            assert touched_faces(occ) == faces, shape
            if occ.any():  # measure_workspace reads both from its slices' counts, not from the faces
                fields = measure_fields(make_result(occ), ["box_contact_fraction", "touched_faces"])
                assert fields["box_contact_fraction"] == (occ & on).sum() / on.sum(), shape
                assert fields["touched_faces"] == faces, shape


def test_the_hull_runs_beside_the_steps_before_it(monkeypatch):
    """A full evaluation starts the hull's qhull (which releases the GIL) in a thread of its own before
    the feature filter, so both run at once, and reads it only after: the same measures as with qhull
    in the caller's thread at the hull step. A field that reads no hull starts none."""
    import threading

    from paraspace.kinematics import hull as hull_mod
    from paraspace.kinematics import measures as mod

    res = compute_workspace(Design(), WorkspaceSettings(voxel=6.0))
    events: list[tuple[str, str]] = []
    real_qhull, real_filter = hull_mod.PendingHull._qhull, mod.feature_filter

    def qhull(self):
        events.append(("qhull", threading.current_thread().name))
        real_qhull(self)

    def feature_filter(*a, **k):
        events.append(("filter", threading.current_thread().name))
        return real_filter(*a, **k)

    monkeypatch.setattr(hull_mod.PendingHull, "_qhull", qhull)
    monkeypatch.setattr(mod, "feature_filter", feature_filter)
    got = measure_workspace(res)
    main = threading.current_thread().name
    assert events == [("qhull", "qhull"), ("filter", main)]  # qhull started first, in its own thread
    events.clear()
    monkeypatch.setattr(mod._Steps, "start_hull", lambda self: None)  # qhull at the hull step, in this thread
    assert measure_workspace(res) == got
    assert events == [("filter", main), ("qhull", main)]
    monkeypatch.undo()
    monkeypatch.setattr(hull_mod.PendingHull, "_qhull", qhull)
    events.clear()
    mod.measure_fields(res, ["components", "stable_genus"])
    assert events == []
