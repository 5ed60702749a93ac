"""The workspace and IK of any mechanism description (kinematics/mechanism_workspace.py).

Checked against independent computations: the description's plain brute force
(kinematics/mechanism.reachable_brute_force: every carriage joint on a grid, lengths and cones from
the description's own forward model) per voxel for each preset, with and without cones; a
closed-form oracle for the fixed-length legs of 6-PSS (a brute force cannot hit a fixed length);
the paper's engine (kinematics/workspace.py) on the paper preset and, with d_s = eta_s = 0, on the
Gough-Stewart preset; and IK against a brute-force maximisation of the margin.
Coarse voxels (h = 8) and small samples throughout.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage as ndi

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.mechanism import carriage_samples, parse_mechanism, reachable_brute_force
from paraspace.kinematics.mechanism_workspace import (
    bracket_caveat,
    compute_general_workspace,
    compute_mechanism_workspace,
    kernel_tables,
    mechanism_ik,
    paper_design,
    platform_rotation,
)
from paraspace.kinematics.presets import gough_stewart, paper, preset, six_pss
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

H = 8.0
#: the paper's arc stroke (30 deg) at eta_step 0.5 has 61 samples: the brute force takes the same
#: revolute values, so a brute-force pass implies an engine pass exactly (the engine is exact in
#: the prismatic joint, which the brute force samples finely)
BRUTE = {"revolute": 61, "prismatic": 2001}


def _sample_voxels(res, n_band: int = 70, n_other: int = 25, seed: int = 0) -> np.ndarray:
    """Voxel centres: mostly from the band around the boundary (where a sampled and an exact test
    can differ), some deep inside and some outside."""
    occ = res.occupancy
    band = ndi.binary_dilation(occ, iterations=1) & ~ndi.binary_erosion(occ, iterations=1)
    rng = np.random.default_rng(seed)
    picks = []
    for mask, n in ((band, n_band), (occ & ~band, n_other), (~occ & ~band, n_other)):
        idx = np.argwhere(mask)
        if len(idx):
            picks.append(idx[rng.choice(len(idx), min(n, len(idx)), replace=False)])
    idx = np.concatenate(picks)
    xs, ys, zs = res.grid.axes()
    return np.stack([xs[idx[:, 0]], ys[idx[:, 1]], zs[idx[:, 2]]], axis=1), idx


def _witness_ok(mech, point, orientation) -> bool:
    """The IK's carriage values put every leg in range by the description's own forward model."""
    rot = platform_rotation(mech, orientation)
    sol = mechanism_ik(mech, point, orientation)
    lengths = mech.leg_lengths([c.q for c in sol], point, rot)
    lo = np.array([leg.length[0] for _, _, leg in mech.legs])
    hi = np.array([leg.length[1] for _, _, leg in mech.legs])
    return bool(np.all((lengths >= lo - 1e-6) & (lengths <= hi + 1e-6)))


def _with_cones(mech, u_axis, u_angle, s_axis, s_angle):
    data = mech.to_dict()
    for chain in data["chains"]:
        for leg in chain["legs"]:
            leg["u_cone"] = {"axis": u_axis, "angle": u_angle}
            leg["s_cone"] = {"axis": s_axis, "angle": s_angle}
    return parse_mechanism(data)


CASES = [
    ("paper", None, (0.0, 0.0, 0.0)),
    ("paper", None, (10.0, -8.0, 5.0)),
    ("gough-stewart", None, (0.0, 0.0, 0.0)),
    ("gough-stewart", None, (15.0, 10.0, -5.0)),
    ("6-pups", None, (0.0, 0.0, 0.0)),
    ("6-pups", None, (-10.0, 5.0, 10.0)),
    # cones about axes that are not the normal: tilted U axes, an S axis off the platform normal
    ("gough-stewart", ([0.2, 0.0, 1.0], 50.0, [0.0, 0.3, 1.0], 60.0), (0.0, 0.0, 0.0)),
    ("6-pups", ([-0.3, 0.1, 1.0], 45.0, [0.1, 0.0, 1.0], 55.0), (5.0, 0.0, 0.0)),
    ("paper", ([0.1, -0.1, 1.0], 40.0, [0.0, 0.0, 1.0], 50.0), (0.0, 0.0, 0.0)),
]


@pytest.mark.parametrize("name, cones, orientation", CASES)
def test_engine_equals_the_brute_force_per_voxel(name, cones, orientation) -> None:
    mech = preset(name)
    if cones is not None:
        mech = _with_cones(mech, *cones)
    res = compute_general_workspace(mech, WorkspaceSettings(voxel=H, orientation=orientation))
    assert res.engine == "general" and 20 < res.voxels
    pts, idx = _sample_voxels(res)
    engine = res.occupancy[idx[:, 0], idx[:, 1], idx[:, 2]]
    brute = reachable_brute_force(mech, pts, platform_rotation(mech, orientation), samples=BRUTE)
    assert engine.any() and not engine.all()
    # the brute force's carriage values are among the engine's (same revolute samples, the exact
    # prismatic joint covers every prismatic sample): a brute-force pass is an engine pass
    assert not np.any(brute & ~engine), pts[brute & ~engine]
    # the engine is exact in the prismatic joint: where the brute force's 2001 samples miss a thin
    # feasible interval the engine's pose still has carriage values that put every leg in range
    missed = np.flatnonzero(engine & ~brute)
    assert len(missed) <= 3, pts[missed]
    if cones is None:
        for i in missed:
            assert _witness_ok(mech, pts[i], orientation), pts[i]


def test_six_pss_fixed_legs_equal_the_closed_form() -> None:
    """A fixed-length leg on a vertical rail: the rail value solves ``|B - D0 - s z| = L``, i.e.
    ``s = (B - D0)_z -+ sqrt(L^2 - |(B - D0)_xy|^2)``; reachable iff a root of every leg lies on the rail."""
    mech = six_pss(leg_length=130.0, rail_stroke=120.0)
    for orientation in [(0.0, 0.0, 0.0), (12.0, -6.0, 4.0)]:
        res = compute_general_workspace(mech, WorkspaceSettings(voxel=H, orientation=orientation))
        pts, idx = _sample_voxels(res, 150, 50)
        engine = res.occupancy[idx[:, 0], idx[:, 1], idx[:, 2]]
        rot = platform_rotation(mech, orientation)
        ok = np.ones(len(pts), bool)
        for _, _, leg in mech.legs:
            v = pts + rot @ np.asarray(leg.platform) - np.asarray(leg.base)
            disc = 130.0 ** 2 - v[:, 0] ** 2 - v[:, 1] ** 2
            root = np.sqrt(np.maximum(disc, 0.0))
            on = [(disc >= 0) & (v[:, 2] + sg * root >= -1e-9) & (v[:, 2] + sg * root <= 120.0 + 1e-9)
                  for sg in (-1.0, 1.0)]
            ok &= on[0] | on[1]
        assert 20 < ok.sum() < len(pts) - 20
        np.testing.assert_array_equal(engine, ok)


def test_paper_preset_routes_to_the_paper_engine_and_the_general_engine_agrees() -> None:
    """The preset is voxel-identical to today's engine (it IS today's engine), and the general engine
    on the same grid decides the same voxels (the same arc samples, exact in d both)."""
    for params, orientation in [({}, (0.0, 0.0, 0.0)), ({"eta_range": "from-zero", "a": 40.0}, (8.0, 4.0, -6.0))]:
        design = Design(**params)
        settings = WorkspaceSettings(voxel=H, orientation=orientation)
        today = compute_workspace(design, settings)
        mech = preset("paper", params)
        assert paper_design(mech) == design
        routed = compute_mechanism_workspace(mech, settings)
        assert routed.engine == "paper" and routed.grid == today.grid
        np.testing.assert_array_equal(routed.occupancy, today.occupancy)
        general = compute_general_workspace(mech, WorkspaceSettings(voxel=H, orientation=orientation,
                                                                    bounds=(today.grid.lo, today.grid.hi)))
        assert general.grid == today.grid
        np.testing.assert_array_equal(general.occupancy, today.occupancy)


def test_gough_stewart_equals_the_paper_model_without_strokes() -> None:
    """With base_radius = sqrt(r^2 + b^2/4), base_half_angle = atan(b/2r), platform_radius = a and
    platform_half_angle = 30 the Gough-Stewart preset is the paper's mechanism with d_s = eta_s = 0."""
    design = Design(d_s=0.0, eta_s=0.0)
    gs = gough_stewart(base_radius=math.hypot(100.0, 7.0), base_half_angle=math.degrees(math.atan2(7.0, 100.0)),
                       platform_radius=50.0, platform_half_angle=30.0, l_min=114.5, l_max=164.5)
    for orientation in [(0.0, 0.0, 0.0), (20.0, -10.0, 5.0)]:
        settings = WorkspaceSettings(voxel=H, orientation=orientation)
        today = compute_workspace(design, settings)
        assert today.voxels > 100
        res = compute_mechanism_workspace(gs, WorkspaceSettings(voxel=H, orientation=orientation,
                                                                bounds=(today.grid.lo, today.grid.hi)))
        assert res.engine == "general"
        np.testing.assert_array_equal(res.occupancy, today.occupancy)
        # and its own default box holds the same workspace (never clipped)
        own = compute_mechanism_workspace(gs, settings)
        assert own.voxels == today.voxels


@pytest.mark.parametrize("name", ["gough-stewart", "6-pups", "6-pss"])
def test_default_box_never_clips(name) -> None:
    res = compute_mechanism_workspace(preset(name), WorkspaceSettings(voxel=H, orientation=(5.0, 10.0, 0.0)))
    occ = res.occupancy
    assert res.voxels > 20
    for axis in range(3):
        assert not np.take(occ, -1, axis=axis).any()
        if axis < 2:
            assert not np.take(occ, 0, axis=axis).any()
    assert abs(res.grid.lo[2] - 0.0) < 1e-9  # the bottom is the floor z = 0


def _brute_margin(mech, point, rot, samples):
    best = []
    for chain in mech.chains:
        _, bases, _ = carriage_samples(chain, samples)
        u = np.array([leg.platform for leg in chain.legs]) @ rot.T
        length = np.linalg.norm(point + u[None] - bases, axis=2)
        lo = np.array([leg.length[0] for leg in chain.legs])
        hi = np.array([leg.length[1] for leg in chain.legs])
        m = np.minimum(length - lo, hi - length).min(axis=1)
        best.append(float(m.max()))
    return best


@pytest.mark.parametrize("name, point, orientation", [
    ("paper", (10.0, -5.0, 130.0), (5.0, 0.0, -3.0)),
    ("paper", (40.0, 30.0, 110.0), (0.0, 0.0, 0.0)),
    ("6-pups", (5.0, 10.0, 160.0), (0.0, 8.0, 0.0)),
    ("gough-stewart", (0.0, 5.0, 135.0), (3.0, 0.0, 2.0)),
])
def test_ik_maximises_the_smallest_margin(name, point, orientation) -> None:
    mech = preset(name)
    rot = platform_rotation(mech, orientation)
    sol = mechanism_ik(mech, point, orientation)
    brute = _brute_margin(mech, np.asarray(point), rot, {"revolute": 61, "prismatic": 501})
    for chain_sol, chain, b in zip(sol, mech.chains, brute):
        # the reported lengths and margin are those of the reported carriage values (forward model)
        lengths = np.linalg.norm(mech.platform_points(point, rot)[[i for i, (c, _, _) in enumerate(mech.legs)
                                                                    if c == chain_sol.chain]]
                                 - chain.base_points(chain_sol.q), axis=1)
        np.testing.assert_allclose(lengths, chain_sol.lengths, atol=1e-9)
        margin = min(min(x - leg.length[0], leg.length[1] - x) for x, leg in zip(lengths, chain.legs))
        assert margin == pytest.approx(chain_sol.margin, abs=1e-9)
        # at least the brute force's best (the same revolute samples, a finer search in s); at most
        # half a brute-force prismatic step better (the margin is 1-Lipschitz in s)
        step = max((j.range[1] - j.range[0]) / 500 for j in chain.carriage) if chain.carriage else 0.0
        assert b - 1e-9 <= chain_sol.margin <= b + 0.5 * step + 1e-9
        assert chain_sol.feasible == (chain_sol.margin >= -1e-9)
    assert all(c.feasible for c in sol)


def test_general_results_work_with_measures_and_shell() -> None:
    from paraspace.kinematics.measures import measure_workspace
    from paraspace.kinematics.shell import workspace_shell

    res = compute_mechanism_workspace(preset("6-pups"), WorkspaceSettings(voxel=H))
    m = measure_workspace(res)
    assert m.voxels == res.voxels and m.volume == res.volume and m.components >= 1
    mesh = workspace_shell(res)
    assert len(mesh.faces) > 0


def test_refusals_name_the_field() -> None:
    gs = gough_stewart()
    with pytest.raises(ParameterError, match="bracket = True is invalid: expected not available with joint cones"):
        compute_mechanism_workspace(_with_cones(gs, [0, 0, 1], 60.0, [0, 0, 1], 60.0),
                                    WorkspaceSettings(voxel=H, bracket=True))
    with pytest.raises(ParameterError, match="diagnostics"):
        compute_mechanism_workspace(gs, WorkspaceSettings(voxel=H, diagnostics=True))
    with pytest.raises(ParameterError, match="joints"):
        compute_mechanism_workspace(gs, WorkspaceSettings(voxel=H, joints=Joints(theta_u=30.0)))
    with pytest.raises(ParameterError, match=r"length_step = 0 is invalid: valid range \[0.01, 100\]"):
        compute_mechanism_workspace(gs, WorkspaceSettings(voxel=H), length_step=0)
    data = gs.to_dict()
    data["chains"][2]["legs"][0]["diameter"] = 5.0
    with pytest.raises(ParameterError, match="bracket = True is invalid: expected not available with leg diameters"):
        compute_mechanism_workspace(parse_mechanism(data), WorkspaceSettings(voxel=H, bracket=True))
    # the paper's mechanism keeps every option of the paper's engine
    assert compute_mechanism_workspace(paper(), WorkspaceSettings(voxel=H, bracket=True)).volume_inner is not None


def _table_mechanism(kind: str = "x-y table"):
    """Three chains on a turntable with an x-y table (revolute + two prismatic joints), two legs each:
    the y joint (the longer stroke) is solved exactly, the x joint and the turntable sampled."""
    chains = []
    for gamma in (0.0, 120.0, 240.0):
        c, s = math.cos(math.radians(gamma)), math.sin(math.radians(gamma))
        legs = []
        for sign in (1.0, -1.0):
            bx, by = 90.0, sign * 10.0
            px, py = 40.0, sign * 20.0
            legs.append({"base": [c * bx - s * by, s * bx + c * by, 0.0],
                         "platform": [c * px - s * py, s * px + c * py, 0.0], "length": [110.0, 160.0]})
        carriage = {
            "x-y table": [{"type": "revolute", "axis": [0, 0, 1], "range": [-10.0, 10.0]},
                          {"type": "prismatic", "axis": [c, s, 0], "range": [-10.0, 10.0]},
                          {"type": "prismatic", "axis": [-s, c, 0.2], "range": [-15.0, 15.0]}],
            # a slide, then a turntable about the slid frame's tilted axis (a revolute after the exact joint)
            "slide-turn": [{"type": "prismatic", "axis": [-c, -s, 0.3], "range": [0.0, 30.0]},
                           {"type": "revolute", "axis": [0.1, 0.0, 1.0], "range": [-10.0, 10.0]}],
            # a turntable only: sampled, tested at s = 0
            "turntable": [{"type": "revolute", "axis": [0, 0, 1], "range": [-10.0, 10.0]}],
        }[kind]
        chains.append({"carriage": carriage, "legs": legs})
    return parse_mechanism({"name": "x-y tables", "chains": chains})


@pytest.mark.parametrize("kind, samples", [("x-y table", 21 * 21), ("slide-turn", 21), ("turntable", 21)])
def test_other_carriages_equal_the_brute_force(kind, samples) -> None:
    mech = _table_mechanism(kind)
    orientation = (5.0, 0.0, 3.0)
    res = compute_general_workspace(mech, WorkspaceSettings(voxel=H, orientation=orientation, eta_step=1.0),
                                    length_step=1.0)
    assert res.samples == (samples,) * 3
    pts, idx = _sample_voxels(res, 60, 20)
    engine = res.occupancy[idx[:, 0], idx[:, 1], idx[:, 2]]
    # the brute force's turntable and x values are the engine's samples; its y values lie in the
    # exactly-solved stroke
    brute = reachable_brute_force(mech, pts, platform_rotation(mech, orientation),
                                  samples={"revolute": 21, "prismatic": 21 if kind == "x-y table" else 301})
    assert 10 < engine.sum() < len(pts) - 10
    assert not np.any(brute & ~engine)
    for i in np.flatnonzero(engine & ~brute):
        sol = mechanism_ik(mech, pts[i], orientation, eta_step=1.0, length_step=1.0)
        rot = platform_rotation(mech, orientation)
        lengths = mech.leg_lengths([c.q for c in sol], pts[i], rot)
        assert np.all((lengths >= 110.0 - 1e-6) & (lengths <= 160.0 + 1e-6)), pts[i]


def _reference_mechanism():
    data = preset("6-pups").to_dict()
    data["reference"] = [10.0, -5.0, 3.0]
    return parse_mechanism(data)


@pytest.mark.parametrize("name", ["paper", "gough-stewart", "6-pups", "6-pss", "x-y tables", "slide-turn",
                                  "reference"])
def test_jacobians_match_finite_differences(name) -> None:
    """dl/dx = J_x (x = [P, phi, theta, psi], radians) and dl/dq = -C (J_q = [I | C]) by central
    differences of the description's own forward model (Mechanism.leg_lengths)."""
    from paraspace.kinematics.mechanism_jacobian import mechanism_jacobians

    mech = {"x-y tables": _table_mechanism, "slide-turn": lambda: _table_mechanism("slide-turn"),
            "reference": _reference_mechanism}.get(name, lambda: preset(name))()
    rng = np.random.default_rng(7)
    position = np.array([4.0, -6.0, 140.0])
    angles = np.array([7.0, -4.0, 5.0])  # psi, theta, phi (degrees)
    q = [[float(rng.uniform(*j.range)) for j in chain.carriage] for chain in mech.chains]
    jac = mechanism_jacobians(mech, position, angles, q)

    def lengths(pos, ang, qq):
        return mech.leg_lengths(qq, pos, platform_rotation(mech, ang))

    eps = 1e-6
    fd_x = np.zeros((6, 6))
    for k in range(3):
        dp = np.zeros(3)
        dp[k] = eps
        fd_x[:, k] = (lengths(position + dp, angles, q) - lengths(position - dp, angles, q)) / (2 * eps)
    for k, idx in enumerate((2, 1, 0)):  # Theta = [phi, theta, psi]; angles = (psi, theta, phi)
        da = np.zeros(3)
        da[idx] = np.degrees(eps)
        fd_x[:, 3 + k] = (lengths(position, angles + da, q) - lengths(position, angles - da, q)) / (2 * eps)
    np.testing.assert_allclose(jac.J_x, fd_x, atol=1e-6)
    col = 6
    for c, chain in enumerate(mech.chains):
        for m, joint in enumerate(chain.carriage):
            step = np.degrees(eps) if joint.type == "revolute" else eps
            qp = [list(x) for x in q]
            qm = [list(x) for x in q]
            qp[c][m] += step
            qm[c][m] -= step
            fd = (lengths(position, angles, qp) - lengths(position, angles, qm)) / (2 * eps)
            np.testing.assert_allclose(-jac.J_q[:, col], fd, atol=1e-6)
            col += 1
    assert col == jac.J_q.shape[1]
    np.testing.assert_allclose(jac.J_q[:, :6], np.eye(6))
    assert np.isfinite(jac.condition_number) and jac.condition_number >= 1.0


def test_paper_preset_jacobians_are_the_papers() -> None:
    """The paper preset's Jacobians are kinematics/jacobian.py's (eqs. (22)-(26), columns reordered:
    the paper's q is [l, d_1..d_3, eta_1..eta_3], the description's [l, eta_1, d_1, eta_2, d_2, ...])."""
    from paraspace.kinematics.jacobian import jacobians
    from paraspace.kinematics.mechanism_jacobian import mechanism_jacobians
    from paraspace.kinematics.pose import Pose

    design = Design(a=40.0, eta_range="from-zero")
    mech = preset("paper", {"a": 40.0, "eta_range": "from-zero"})
    pose = Pose(5.0, -3.0, 135.0, 6.0, -4.0, 3.0)
    d, eta = np.array([10.0, 20.0, 35.0]), np.array([5.0, 12.0, 25.0])
    ours = mechanism_jacobians(mech, pose.position, (pose.psi, pose.theta, pose.phi),
                               [[eta[i], d[i]] for i in range(3)])
    theirs = jacobians(design, pose, d, eta)
    np.testing.assert_allclose(ours.J_x, theirs.J_x, atol=1e-12)
    order = [0, 1, 2, 3, 4, 5, 7, 9, 11, 6, 8, 10]  # ours -> [l, d_1..d_3, eta_1..eta_3]
    np.testing.assert_allclose(ours.J_q[:, order], theirs.J_q, atol=1e-10)


@pytest.mark.parametrize("name", ["paper", "gough-stewart", "6-pups", "6-pss", "gs-cones", "x-y table", "slide-turn"])
def test_blocks_and_dense_give_the_same_voxels(name) -> None:
    """The general engine's cube certificates (kinematics/mechanism_workspace._blocks_kernel) never
    change a voxel: blocks == dense at two voxel sizes and two orientations."""
    mech = {"gs-cones": lambda: _with_cones(preset("gough-stewart"), [0.2, 0.0, 1.0], 50.0, [0.0, 0.3, 1.0], 60.0),
            "x-y table": _table_mechanism, "slide-turn": lambda: _table_mechanism("slide-turn")}.get(
        name, lambda: preset(name))()
    for h, orientation in [(H, (0.0, 0.0, 0.0)), (6.0, (10.0, -5.0, 3.0))]:
        dense = compute_general_workspace(mech, WorkspaceSettings(voxel=h, orientation=orientation, method="dense"))
        blocks = compute_general_workspace(mech, WorkspaceSettings(voxel=h, orientation=orientation,
                                                                   method="blocks"))
        assert dense.voxels > 50
        np.testing.assert_array_equal(blocks.occupancy, dense.occupancy)


def test_sweep_over_a_preset_parameter() -> None:
    """A longer lift only adds carriage values: the workspaces nest voxel by voxel (fixed box), a
    zero lift is the Gough-Stewart platform's, and the sweep's rows are those workspaces; the paper
    preset's rows are the paper engine's."""
    from paraspace.kinematics.sweep import sweep_preset

    box = ((-120.0, -120.0, 0.0), (120.0, 120.0, 240.0))
    settings = WorkspaceSettings(voxel=H, bounds=box)
    occ = [compute_mechanism_workspace(preset("6-pups", {"lift": v}), settings).occupancy for v in (0.0, 20.0, 40.0)]
    assert 100 < occ[0].sum() < occ[1].sum() < occ[2].sum()
    assert not np.any(occ[0] & ~occ[1]) and not np.any(occ[1] & ~occ[2])
    np.testing.assert_array_equal(occ[0], compute_mechanism_workspace(gough_stewart(), settings).occupancy)
    rows = sweep_preset("6-pups", "lift", [0.0, 20.0, 40.0], settings=settings)
    assert [r["voxels"] for r in rows] == [int(o.sum()) for o in occ]
    assert [r["lift"] for r in rows] == [0.0, 20.0, 40.0] and rows[0]["engine"] == "general"
    assert all(r["volume"] == r["voxels"] * H ** 3 for r in rows)
    paper_rows = sweep_preset("paper", "a", [40.0, 60.0], settings=WorkspaceSettings(voxel=H))
    assert [r["voxels"] for r in paper_rows] == [compute_workspace(Design(a=a), WorkspaceSettings(voxel=H)).voxels
                                                  for a in (40.0, 60.0)]
    with pytest.raises(ParameterError, match="a parameter of preset '6-pups'"):
        sweep_preset("6-pups", "a", [1.0])


@pytest.mark.parametrize("name", ["paper", "gough-stewart", "6-pups", "slide-turn"])
def test_bracket_contains_the_volume_and_its_cubes_are_right(name) -> None:
    """volume_inner <= V <= volume_outer around the voxel estimate and a finer one (h/2, finer
    samples); points near the centre of an inside cube are reachable and points of outside cubes
    unreachable by the plain brute force (twice the engine's revolute samples, fine prismatic), at
    the cubes next to the boundary cubes."""
    from paraspace.kinematics.mechanism_workspace import general_bracket, kernel_tables

    mech = _table_mechanism("slide-turn") if name == "slide-turn" else preset(name)
    res = compute_general_workspace(mech, WorkspaceSettings(voxel=H, bracket=True))
    fine = compute_general_workspace(mech, WorkspaceSettings(voxel=H / 2, eta_step=0.25), length_step=0.5)
    assert 0 < res.volume_inner <= min(res.volume, fine.volume)
    assert max(res.volume, fine.volume) <= res.volume_outer < math.inf
    rot = platform_rotation(mech, (0.0, 0.0, 0.0))
    br = general_bracket(mech, kernel_tables(mech, rot), res.grid, 0.5, 1.0, 0.0, WorkspaceSettings().bracket_refine)
    assert (br.volume_inner, br.volume_outer) == (res.volume_inner, res.volume_outer)
    # each halving of the boundary cubes tightens the bracket and keeps it around the volumes
    levels = [general_bracket(mech, kernel_tables(mech, rot), res.grid, 0.5, 1.0, 0.0, k) for k in range(3)]
    for a, b in zip(levels, levels[1:]):
        assert a.volume_inner <= b.volume_inner <= min(res.volume, fine.volume)
        assert max(res.volume, fine.volume) <= b.volume_outer <= a.volume_outer
    assert levels[2].volume_outer - levels[2].volume_inner < levels[0].volume_outer - levels[0].volume_inner
    # the cubes' states on the bracket's grid: an inside cube's centre is a reachable voxel, an
    # outside cube's is not
    rng = np.random.default_rng(11)
    big = br.grid
    tabs = kernel_tables(mech, rot)
    inside_pts, outside_pts = [], []
    xs, ys, zs = big.axes()
    occ = compute_general_workspace(mech, WorkspaceSettings(voxel=H, bounds=(big.lo, big.hi))).occupancy
    state = _states(mech, tabs, big)
    assert not np.any((state == 1) & ~occ) and not np.any((state == 0) & occ)
    for want, bucket, spread in ((1, inside_pts, 0.25), (0, outside_pts, 0.5)):
        idx = np.argwhere(state == want)
        # the cubes nearest the workspace's boundary are the ones a wrong certificate would hit
        near = idx[ndi.binary_dilation(state == 2, iterations=1)[idx[:, 0], idx[:, 1], idx[:, 2]]]
        pick = near[rng.choice(len(near), min(25, len(near)), replace=False)]
        centres = np.stack([xs[pick[:, 0]], ys[pick[:, 1]], zs[pick[:, 2]]], axis=1)
        bucket.extend(centres + rng.uniform(-spread, spread, centres.shape) * H)
    # the engine's 61 revolute samples are among these 121; an inside cube's points near its centre
    # keep a length margin of more than 3 (half-diagonal 6.9, offset at most 3.5): 1001 prismatic
    # samples (spacing 0.05) find them
    samples = {"revolute": 121, "prismatic": 1001}
    assert np.all(reachable_brute_force(mech, np.array(inside_pts), rot, samples=samples))
    assert not np.any(reachable_brute_force(mech, np.array(outside_pts), rot, samples=samples))


def test_fixed_length_legs_get_inside_cubes_each_checked_by_a_crossing_of_the_length() -> None:
    """6-PSS (rods of fixed length 120 on vertical rails): the length test with the limits tightened by
    a cube's half-diagonal never passes (``l_min = l_max``), so the inner bound was 0 at every
    refinement. The one-leg test (the rail moves the rod's base along a line, so its length takes every
    value between its least and its greatest) certifies inside cubes; each is checked here without the
    engine, at points anywhere in the cube: along 2,001 positions of each rail the rod's length crosses
    120 (a sign change of ``length - 120`` between neighbours: a position of exactly 120 lies between
    them, by continuity). The bracket holds the voxel volumes at h and h / 2."""
    from paraspace.kinematics.mechanism_workspace import general_bracket

    mech = six_pss()
    rot = platform_rotation(mech, (0.0, 0.0, 0.0))
    tabs = kernel_tables(mech, rot)
    res = compute_general_workspace(mech, WorkspaceSettings(voxel=H, bracket=True))
    fine = compute_general_workspace(mech, WorkspaceSettings(voxel=H / 2))
    assert 0.5 * res.volume < res.volume_inner <= min(res.volume, fine.volume)
    assert max(res.volume, fine.volume) <= res.volume_outer < math.inf
    br = general_bracket(mech, tabs, res.grid, 0.5, 1.0, 0.0, 0)
    state = _states(mech, tabs, br.grid)
    xs, ys, zs = br.grid.axes()
    idx = np.argwhere(state == 1)
    rng = np.random.default_rng(5)
    pick = idx[rng.choice(len(idx), 60, replace=False)]
    pts = np.stack([xs[pick[:, 0]], ys[pick[:, 1]], zs[pick[:, 2]]], axis=1) + rng.uniform(-0.5, 0.5, (60, 3)) * H
    for chain in mech.chains:
        (leg,) = chain.legs
        _, bases, _ = carriage_samples(chain, {"prismatic": 2001})
        lengths = np.linalg.norm(pts[:, None, :] + (rot @ np.asarray(leg.platform))[None, None, :]
                                 - bases[None, :, 0, :], axis=2) - leg.length[0]
        assert np.all(np.any(lengths[:, :-1] * lengths[:, 1:] <= 0.0, axis=1))


def test_a_fixed_length_leg_beside_another_leg_has_no_inside_cube_and_says_so() -> None:
    """The caveat the explorer shows beside such a bracket is true: the paper's chains with their first
    leg fixed at 140 have a workspace (h = 8) and an inner bound of 0; the presets have no caveat."""
    d = paper().to_dict()
    for chain in d["chains"]:
        chain["legs"][0]["length"] = [140.0, 140.0]
    mech = parse_mechanism(d)
    res = compute_general_workspace(mech, WorkspaceSettings(voxel=H, bracket=True))
    assert res.volume > 0 and res.volume_inner == 0 and res.volume <= res.volume_outer < math.inf
    assert "inner bound 0" in bracket_caveat(mech)
    assert all(bracket_caveat(preset(n)) is None for n in ("gough-stewart", "6-pss", "6-pups", "paper"))


def _level_at_a_time(mech, tabs, big, refine):
    """The bracket's refinement as it was before it was chunked: every boundary cube of a level at
    once (``8^refine`` children of each held together), the volumes summed a level at a time."""
    from paraspace.kinematics.mechanism_workspace import _BOUND_EPS, _bracket_points_kernel, chain_slack

    lmin, lmax = np.sqrt(tabs.lmin2), np.sqrt(tabs.lmax2)
    eps = _BOUND_EPS * (1.0 + float(lmax.max()) + float(np.abs(tabs.base).max(initial=0.0)))
    slack = np.array([chain_slack(c, 0.5, 1.0) for c in mech.chains])
    e_leg_of = [c for c, _, _ in mech.legs]
    rows = (len(mech.chains), len(lmin))
    state = _states(mech, tabs, big)
    xs, ys, zs = big.axes()
    idx = np.argwhere(state == 2)
    centres = np.stack([xs[idx[:, 0]], ys[idx[:, 1]], zs[idx[:, 2]]], axis=1)
    v_in, edge = float(np.count_nonzero(state == 1)) * big.h ** 3, big.h
    offsets = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
    for _ in range(refine):
        edge *= 0.5
        kids = np.ascontiguousarray((centres[:, None, :] + 0.5 * edge * offsets[None]).reshape(-1, 3))
        delta = math.sqrt(3.0) * 0.5 * edge
        e_leg = (delta + slack + eps)[e_leg_of]
        st = np.zeros(len(kids), np.uint8)
        _bracket_points_kernel(kids, delta + eps, delta + slack + eps, (lmin + delta + eps) ** 2,
                               np.where(lmax - delta - eps > 0, (lmax - delta - eps) ** 2, -1.0),
                               np.ascontiguousarray(np.broadcast_to(np.where(lmin - e_leg > 0, lmin - e_leg, 0.0) ** 2,
                                                                    rows)),
                               np.ascontiguousarray(np.broadcast_to((lmax + e_leg) ** 2, rows)), *tabs.args(), st)
        v_in += int(np.count_nonzero(st == 1)) * edge ** 3
        centres = kids[st == 2]
    return v_in, v_in + len(centres) * edge ** 3


def test_the_general_bracket_works_in_bounded_launches_and_stops_between_them(monkeypatch) -> None:
    """A bracket is a background job's step (the explorer's, the API's): its work goes in launches of
    at most ``BRACKET_VOXELS_PER_CALL`` voxels and ``BRACKET_CUBES_PER_CALL`` half cubes, each holding
    the kernel lock on its own, with a progress report and a cancel check before each. Before, one
    launch classified the whole grid, every refinement level was cut at once (``8^refine`` children of
    each boundary cube in memory) and the caller held the kernel lock throughout: a REST request for
    6-pss at voxel 2, refine 3 held every kernel of the server for 79-173 s (2-core machine) and could
    not be cancelled.
    The bracket is that of the refinement a level at a time, in any launch size."""
    import threading

    from paraspace.kinematics import mechanism_workspace as mw
    from paraspace.kinematics.progress import Cancelled

    mech = gough_stewart()
    rot = platform_rotation(mech, (0.0, 0.0, 0.0))
    tabs = kernel_tables(mech, rot)
    grid = compute_general_workspace(mech, WorkspaceSettings(voxel=H)).grid
    default = mw.general_bracket(mech, tabs, grid, 0.5, 1.0, 0.0, 3)
    assert (default.volume_inner, default.volume_outer) == _level_at_a_time(mech, tabs, default.grid, 3)

    launches: list[tuple[str, int]] = []
    held = []

    class Lock:  # the kernel lock, counting: is it held, and for which launch
        def __enter__(self):
            held.append(True)

        def __exit__(self, *exc):
            held.pop()

    real_cubes, real_points = mw._bracket_kernel, mw._bracket_points_kernel
    monkeypatch.setattr(mw, "KERNEL_LOCK", Lock())
    monkeypatch.setattr(mw, "_bracket_kernel", lambda xs, ys, zs, *a: (
        launches.append(("cubes", len(xs) * len(ys) * len(zs))), real_cubes(xs, ys, zs, *a)))
    monkeypatch.setattr(mw, "_bracket_points_kernel", lambda kids, *a: (
        launches.append(("halves", len(kids))), real_points(kids, *a)))
    monkeypatch.setattr(mw, "BRACKET_VOXELS_PER_CALL", 4000)
    monkeypatch.setattr(mw, "BRACKET_CUBES_PER_CALL", 64)
    reports = []

    def progress(fraction, message):
        assert not held, "a progress report (and the cancel check after it) while a launch holds the lock"
        reports.append((fraction, message, len(launches)))

    small = mw.general_bracket(mech, tabs, grid, 0.5, 1.0, 0.0, 3, progress)
    assert small == default
    cubes = [n for kind, n in launches if kind == "cubes"]
    halves = [n for kind, n in launches if kind == "halves"]
    assert sum(cubes) == default.grid.size and max(cubes) <= 4000 < sum(cubes)
    assert max(halves) <= 64 and len(halves) > 100
    assert len(reports) == len(launches)  # one report before each launch
    assert [f for f, _, _ in reports] == sorted(f for f, _, _ in reports) and reports[-1][0] < 1.0
    assert "classifying the cubes" in reports[0][1]
    assert f"refining {default.boundary:,} boundary cubes" in reports[-1][1]

    # cancelled at a report half way through the refinement: no launch after it
    launches.clear()
    cancel = threading.Event()
    at = []

    def stop(fraction, message):
        if "refining" in message and fraction >= 0.5 and not cancel.is_set():
            cancel.set()
            at.append(len(launches))

    with pytest.raises(Cancelled):
        mw.general_bracket(mech, tabs, grid, 0.5, 1.0, 0.0, 3, stop, cancel)
    assert at and len(launches) == at[0]


def _states(mech, tabs, grid):
    from paraspace.kinematics.mechanism_workspace import _BOUND_EPS, _bracket_kernel, chain_slack

    lmin, lmax = np.sqrt(tabs.lmin2), np.sqrt(tabs.lmax2)
    eps = _BOUND_EPS * (1.0 + float(lmax.max()) + float(np.abs(tabs.base).max(initial=0.0)))
    delta = math.sqrt(3.0) * 0.5 * grid.h
    e_out = delta + np.array([chain_slack(c, 0.5, 1.0) for c in mech.chains]) + eps
    e_leg = e_out[[c for c, _, _ in mech.legs]]
    rows = (len(mech.chains), len(lmin))
    state = np.zeros(grid.shape, np.uint8)
    _bracket_kernel(*grid.axes(), delta + eps, e_out, (lmin + delta + eps) ** 2,
                    np.where(lmax - delta - eps > 0, (lmax - delta - eps) ** 2, -1.0),
                    np.ascontiguousarray(np.broadcast_to(np.where(lmin - e_leg > 0, lmin - e_leg, 0.0) ** 2, rows)),
                    np.ascontiguousarray(np.broadcast_to((lmax + e_leg) ** 2, rows)), *tabs.args(), state)
    return state
