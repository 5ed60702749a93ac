"""Orientation scans, TI, total orientation and dexterity of any mechanism description
(kinematics/mechanism_orientation.py, kinematics/mechanism_dexterity.py).

Checked against independent computations: the description's plain brute force
(kinematics/mechanism.reachable_brute_force: every carriage joint on a fine grid, lengths and cones
from the description's own forward model) at every (position, angle) sample of a coarse scan and at
every voxel x orientation of a total-orientation workspace; the paper's own path
(kinematics/orientation.py, dexterous.py, dexterity.py) for the paper preset; the symmetry the
mechanism has (a 3-fold axis maps the y' line's tau scan onto the x line's psi scan mirrored);
1/kappa from Jacobians by central differences of the leg lengths. Coarse scans and voxels throughout.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.dexterity import dexterity_field
from paraspace.kinematics.dexterous import orientation_samples, total_orientation_workspace
from paraspace.kinematics.mechanism import parse_mechanism, reachable_brute_force
from paraspace.kinematics.mechanism_dexterity import mechanism_dexterity_field
from paraspace.kinematics.mechanism_orientation import (
    general_orientation_workspace,
    line_azimuth,
    mechanism_orientation_workspace,
    mechanism_total_orientation,
    rotation_axis,
    scan_points,
    symmetry_order,
)
from paraspace.kinematics.mechanism_workspace import compute_mechanism_workspace, mechanism_ik, platform_rotation
from paraspace.kinematics.orientation import LINES, ROTATIONS, OrientationSettings, orientation_workspace
from paraspace.kinematics.presets import preset
from paraspace.kinematics.rotation import axis_angle
from paraspace.kinematics.tilt_torsion import tt_rotations
from paraspace.kinematics.workspace import WorkspaceSettings

#: a coarse scan: 13 angles, positions every 12
SCAN = OrientationSettings(angle_range=60.0, angle_step=10.0, position_step=12.0, z0=150.0)
#: the prismatic joints finely (the engine is exact in one); no revolute joint in these presets
BRUTE = {"revolute": 61, "prismatic": 2001}


def _with_cones(mech, u_axis, u_angle, s_axis, s_angle):
    data = mech.to_dict()
    for chain in data["chains"]:
        for leg in chain["legs"]:
            leg["u_cone"] = {"axis": u_axis, "angle": u_angle}
            leg["s_cone"] = {"axis": s_axis, "angle": s_angle}
    return parse_mechanism(data)


def _asymmetric():
    """A Gough-Stewart platform with one base joint moved: no rotation about z maps it onto itself."""
    data = preset("6-pups").to_dict()
    data["chains"][0]["legs"][0]["base"] = [95.0, 20.0, 0.0]
    return parse_mechanism(data)


def _witness(mech, point, rot) -> bool:
    """The IK's carriage values put every leg in range by the description's own forward model."""
    sol = mechanism_ik(mech, point, rot)
    lengths = mech.leg_lengths([c.q for c in sol], point, platform_rotation(mech, rot))
    lo = np.array([leg.length[0] for _, _, leg in mech.legs])
    hi = np.array([leg.length[1] for _, _, leg in mech.legs])
    return bool(np.all((lengths >= lo - 1e-6) & (lengths <= hi + 1e-6)))


def test_symmetry_order_and_the_lines_it_gives() -> None:
    """The presets are 3-fold about z (the paper's lines, b = 60); a moved joint leaves order 1 and
    the base axes (b = 90); a 6-fold hexagon of single-leg chains gets b = 30."""
    for name in ("paper", "gough-stewart", "6-pups", "6-pss"):
        assert symmetry_order(preset(name)) == 3
    assert line_azimuth(3) == 60.0
    assert symmetry_order(_asymmetric()) == 1 and line_azimuth(1) == 90.0
    np.testing.assert_allclose(rotation_axis("tau_yprime", 90.0), [0.0, 1.0, 0.0], atol=1e-15)
    # a regular hexagon on both sides: legs base at 60k, platform at 60k + 30 -> 6-fold
    legs = [{"base": [100 * math.cos(math.radians(60 * k)), 100 * math.sin(math.radians(60 * k)), 0.0],
             "platform": [50 * math.cos(math.radians(60 * k + 30)), 50 * math.sin(math.radians(60 * k + 30)), 0.0],
             "length": [110.0, 170.0]} for k in range(6)]
    hexa = parse_mechanism({"chains": [{"legs": [leg]} for leg in legs]})
    assert symmetry_order(hexa) == 6 and line_azimuth(6) == 30.0
    pts = scan_points("y_prime", np.array([2.0]), 140.0, 30.0)
    np.testing.assert_allclose(pts, [[math.sqrt(3.0), 1.0, 140.0]])


CASES = [
    ("6-pups", None),
    ("gough-stewart", None),
    ("6-pups", ([-0.2, 0.1, 1.0], 40.0, [0.1, 0.0, 1.0], 50.0)),
    ("asymmetric", None),
]


@pytest.mark.parametrize("name, cones", CASES)
def test_scan_equals_the_brute_force_per_sample(name, cones) -> None:
    """Every (position, angle) sample of the nine maps against the plain brute force at that pose
    (the line's point, the rotation about the line's axis): a brute-force pass is an engine pass
    (the brute force's carriage values are among those the engine's exact joint covers), and the
    engine finds at most a few thin intervals the brute force's samples miss, each with a witness."""
    mech = _asymmetric() if name == "asymmetric" else preset(name)
    if cones is not None:
        mech = _with_cones(mech, *cones)
    res = general_orientation_workspace(mech, SCAN)
    assert res.engine == "general"
    b = line_azimuth(symmetry_order(mech))
    assert res.azimuth == b
    missed = 0
    for (ln, rt), reg in res.regions.items():
        pts = scan_points(ln, reg.positions, SCAN.z0, b)
        assert reg.feasible.any() or ln != "z"
        for m, alpha in enumerate(reg.angles):
            rot = axis_angle(rotation_axis(rt, b), math.radians(alpha))
            brute = reachable_brute_force(mech, pts, rot, samples=BRUTE)
            engine = reg.feasible[:, m]
            assert not np.any(brute & ~engine), (ln, rt, alpha, pts[brute & ~engine])
            for i in np.flatnonzero(engine & ~brute):
                missed += 1
                if cones is None:
                    assert _witness(mech, pts[i], rot), (ln, rt, alpha, pts[i])
    assert missed <= 6
    assert sum(int(r.feasible.sum()) for r in res.regions.values()) > 50


def test_three_fold_axis_maps_the_y_prime_scans_onto_the_x_scans() -> None:
    """Rz(120) maps the y' line (60 deg) onto the x line with s -> -s and a rotation about y' by
    alpha onto one about x by -alpha, and commutes with phi about z: the maps are mirror images (an
    independent check of (S2))."""
    res = general_orientation_workspace(preset("6-pups"), SCAN)
    for a, b in (("tau_yprime", "psi_x"), ("phi_z", "phi_z")):
        yp, x = res.regions[("y_prime", a)], res.regions[("x", b)]
        np.testing.assert_allclose(yp.positions, -x.positions[::-1], atol=1e-9)
        sign = 1 if a == "phi_z" else -1
        expect = x.feasible[::-1, ::sign]
        assert np.count_nonzero(yp.feasible != expect) <= 2  # rounding at a limit
        assert yp.feasible.any()


def test_paper_preset_routes_and_the_general_path_agrees() -> None:
    """The paper preset gives the paper path's result exactly; run through the general path (other
    default ranges, the same lines and rotations) it agrees where the samples coincide."""
    design = Design()
    mech = preset("paper")
    paper = orientation_workspace(design, SCAN)
    routed = mechanism_orientation_workspace(mech, SCAN)
    assert routed.engine == "paper" and routed.order == 3
    assert (routed.ti1, routed.ti2) == (paper.ti1, paper.ti2)
    for key, reg in paper.regions.items():
        np.testing.assert_array_equal(routed.regions[key].feasible, reg.feasible)
    general = general_orientation_workspace(mech, SCAN)
    assert general.engine == "general"
    differ = total = 0
    for key, reg in paper.regions.items():
        greg = general.regions[key]
        common, ip, ig = np.intersect1d(np.round(reg.positions, 9), np.round(greg.positions, 9),
                                        return_indices=True)
        assert common.size > 5
        np.testing.assert_array_equal(reg.angles, greg.angles)
        differ += int(np.count_nonzero(reg.feasible[ip] != greg.feasible[ig]))
        total += int(reg.feasible[ip].sum())
        # the general path's rigorous ranges (S3) hold every feasible sample of the paper path
        outside = np.setdiff1d(np.arange(reg.positions.size), ip)
        assert not reg.feasible[outside].any(), key
    assert total > 100 and differ <= 3  # rounding at a leg limit (the two engines' arithmetic differs)


def test_refusals_name_the_field() -> None:
    from paraspace.kinematics.joints import Joints

    with pytest.raises(ParameterError, match="joints"):
        mechanism_orientation_workspace(preset("6-pups"), OrientationSettings(joints=Joints(theta_u=30.0)))
    with pytest.raises(ParameterError, match="length_step"):
        mechanism_orientation_workspace(preset("6-pups"), SCAN, length_step=0.0)
    res = compute_mechanism_workspace(preset("6-pups"), WorkspaceSettings(voxel=24.0))
    with pytest.raises(ParameterError, match="dexterity_mode"):
        mechanism_dexterity_field(res, 0.01, "best")
    with pytest.raises(ParameterError, match="kappa_min"):
        mechanism_dexterity_field(res, 2.0)
    with pytest.raises(ParameterError, match="tilt"):
        mechanism_total_orientation(preset("6-pups"), 120.0, 0.0, 10.0, WorkspaceSettings(voxel=24.0))


@pytest.mark.parametrize("name", ["6-pups", "gough-stewart-cones"])
def test_total_orientation_equals_the_brute_force(name) -> None:
    """A voxel is in the total-orientation workspace iff its centre passes at every sample
    orientation: against the brute force at each voxel and orientation (a brute-force pass is an
    engine pass; at most a few thin intervals the brute force misses)."""
    mech = preset("6-pups") if name == "6-pups" else _with_cones(preset("gough-stewart"), [0, 0, 1], 60.0,
                                                                   [0, 0, 1], 65.0)
    settings = WorkspaceSettings(voxel=16.0 if name == "6-pups" else 10.0)
    tilt, torsion, step = 10.0, (0.0 if name == "6-pups" else 10.0), 10.0
    dx = mechanism_total_orientation(mech, tilt, torsion, step, settings)
    pos = dx.position
    assert 10 < dx.voxels < pos.voxels
    assert not np.any(dx.occupancy & ~pos.occupancy)
    occ = np.asarray(pos.occupancy, bool)
    pts = pos.grid.points()[occ]
    samples = orientation_samples(tilt, torsion, step)
    rots = tt_rotations(samples[:, 0], samples[:, 1], samples[:, 2])
    brute = np.ones(len(pts), bool)
    for rot in rots:
        brute &= reachable_brute_force(mech, pts, rot, samples=BRUTE)
    engine = dx.occupancy[occ]
    assert not np.any(brute & ~engine)
    assert np.count_nonzero(engine & ~brute) <= 3
    assert brute.sum() > 10


def test_total_orientation_of_the_paper_preset_is_the_papers() -> None:
    settings = WorkspaceSettings(voxel=12.0)
    mine = mechanism_total_orientation(preset("paper"), 8.0, 5.0, 10.0, settings)
    paper = total_orientation_workspace(Design(), 8.0, 5.0, 10.0, settings)
    np.testing.assert_array_equal(mine.occupancy, paper.occupancy)
    assert mine.voxels > 0


def _inverse_condition_fd(mech, point, orientation, q) -> float:
    """1/kappa from J_x and J_q by central differences of the leg lengths (x = [P, phi, theta, psi]
    in radians, revolute joints per radian) and J_h with the mean platform-joint radius."""
    def lengths(pos, ang, qq):
        return mech.leg_lengths(qq, pos, platform_rotation(mech, ang))

    eps = 1e-6
    point, ang = np.asarray(point, float), np.asarray(orientation, float)
    fd_x = np.zeros((6, 6))
    for k in range(3):
        dp = np.zeros(3)
        dp[k] = eps
        fd_x[:, k] = (lengths(point + dp, ang, q) - lengths(point - dp, ang, q)) / (2 * eps)
    for k, idx in enumerate((2, 1, 0)):
        da = np.zeros(3)
        da[idx] = np.degrees(eps)
        fd_x[:, 3 + k] = (lengths(point, ang + da, q) - lengths(point, ang - da, q)) / (2 * eps)
    cols = []
    for c, chain in enumerate(mech.chains):
        for m, joint in enumerate(chain.carriage):
            step = np.degrees(eps) if joint.type == "revolute" else eps
            qp = [list(x) for x in q]
            qm = [list(x) for x in q]
            qp[c][m] += step
            qm[c][m] -= step
            cols.append(-(lengths(point, ang, qp) - lengths(point, ang, qm)) / (2 * eps))
    j_q = np.concatenate([np.eye(6), np.array(cols).T.reshape(6, -1)], axis=1)
    radius = np.mean([np.linalg.norm(leg.platform) for _, _, leg in mech.legs])
    j_h = np.concatenate([fd_x[:, :3], fd_x[:, 3:] / radius], axis=1)
    sv = np.linalg.svd(np.linalg.solve(j_h, j_q), compute_uv=False)
    return float(sv[-1] / sv[0])


@pytest.mark.parametrize("name, orientation, h", [("6-pups", (0.0, 0.0, 0.0), 20.0),
                                                  ("gough-stewart", (8.0, -5.0, 4.0), 10.0)])
def test_dexterity_field_equals_finite_differences(name, orientation, h) -> None:
    """The field at sampled voxels equals 1/kappa of Jacobians built by finite differences at the
    resolved carriage; NaN outside; GCI the mean; the well-conditioned set the threshold."""
    mech = preset(name)
    res = compute_mechanism_workspace(mech, WorkspaceSettings(voxel=h, orientation=orientation))
    assert res.engine == "general" and res.voxels > 20
    field = mechanism_dexterity_field(res, kappa_min=0.05)
    occ = np.asarray(res.occupancy, bool)
    assert np.all(np.isnan(field.inverse_condition[~occ]))
    vals = field.inverse_condition[occ]
    assert np.all((vals >= 0) & (vals <= 1))
    assert field.gci == pytest.approx(vals.mean())
    np.testing.assert_array_equal(field.well_conditioned, occ & (np.nan_to_num(field.inverse_condition) >= 0.05))
    pts = res.grid.points()[occ]
    rng = np.random.default_rng(3)
    for i in rng.choice(len(pts), 8, replace=False):
        q = [c.q for c in mechanism_ik(mech, pts[i], orientation)]
        assert vals[i] == pytest.approx(_inverse_condition_fd(mech, pts[i], orientation, q), rel=1e-5)


def test_dexterity_of_the_paper_preset_is_the_papers() -> None:
    settings = WorkspaceSettings(voxel=12.0)
    res = compute_mechanism_workspace(preset("paper"), settings)
    assert res.engine == "paper"
    mine = mechanism_dexterity_field(res, 0.005)
    from paraspace.kinematics.workspace import compute_workspace

    paper = dexterity_field(compute_workspace(Design(), settings), 0.005)
    np.testing.assert_array_equal(mine.inverse_condition, paper.inverse_condition)
    assert mine.gci == paper.gci


def test_lines_and_rotations_are_all_scanned() -> None:
    res = general_orientation_workspace(_asymmetric(), SCAN)
    assert set(res.regions) == {(ln, rt) for ln in LINES for rt in ROTATIONS}
    d = res.to_dict()
    assert d["symmetry_order"] == 1 and d["second_line_azimuth"] == 90.0
    np.testing.assert_allclose(d["lines"]["y_prime"]["direction"], [0.0, 1.0, 0.0], atol=1e-15)


def test_one_launch_over_rotations_equals_the_per_rotation_test() -> None:
    """The scan kernel (every rotation in one launch, a warm start along the line) answers as the
    general engine's point test run once per rotation (reachable_general)."""
    from paraspace.kinematics.mechanism_orientation import _unrotated, reachable_rotations
    from paraspace.kinematics.mechanism_workspace import reachable_general

    mech = _with_cones(preset("6-pups"), [-0.2, 0.1, 1.0], 45.0, [0.1, 0.0, 1.0], 55.0)
    rng = np.random.default_rng(5)
    pts = np.column_stack([np.linspace(-90, 90, 40), rng.uniform(-30, 30, 40), rng.uniform(120, 200, 40)])
    angles = rng.uniform(-25, 25, (12, 3))
    rots = np.stack([platform_rotation(mech, a) for a in angles])
    tables, plat0, s_axis0 = _unrotated(mech, 0.5, 1.0)
    many = reachable_rotations(tables, plat0, s_axis0, rots, pts)
    for m, a in enumerate(angles):
        np.testing.assert_array_equal(many[:, m], reachable_general(mech, pts, a))
    assert many.any() and not many.all()


@pytest.mark.parametrize("name", ["paper", "6-pups", "reference"])
def test_batched_resolver_and_jacobians_equal_the_per_point_ones(name) -> None:
    """The field's batches (resolved_carriages, inverse_condition_batch) give mechanism_ik's carriage
    values and mechanism_jacobians' 1/kappa at each point (a revolute carriage, a lift, a reference)."""
    from paraspace.kinematics.mechanism_dexterity import (
        inverse_condition_at,
        inverse_condition_batch,
        resolved_carriages,
    )

    if name == "reference":
        data = preset("6-pups").to_dict()
        data["reference"] = [10.0, -5.0, 3.0]
        mech = parse_mechanism(data)
    else:
        mech = preset(name)
    rng = np.random.default_rng(11)
    pts = np.column_stack([rng.uniform(-40, 40, 6), rng.uniform(-40, 40, 6), rng.uniform(120, 180, 6)])
    orientation = (5.0, -3.0, 2.0)
    q = resolved_carriages(mech, pts, orientation)
    vals = inverse_condition_batch(mech, pts, orientation, q)
    for i, p in enumerate(pts):
        for c, sol in enumerate(mechanism_ik(mech, p, orientation)):
            np.testing.assert_allclose(q[c][i], sol.q, rtol=0, atol=1e-12)
        assert vals[i] == pytest.approx(inverse_condition_at(mech, p, orientation), rel=1e-9, abs=1e-15)


def _slide_turn():
    """Three chains: a tilted slide (the exact joint), then a turntable about a tilted axis that is the
    same in every chain (so no rotation about z maps the description onto itself: order 1)."""
    chains = []
    for gamma in (0.0, 120.0, 240.0):
        c, s = math.cos(math.radians(gamma)), math.sin(math.radians(gamma))
        legs = [{"base": [c * 90.0 - s * sg * 10.0, s * 90.0 + c * sg * 10.0, 0.0],
                 "platform": [c * 40.0 - s * sg * 20.0, s * 40.0 + c * sg * 20.0, 0.0], "length": [110.0, 160.0]}
                for sg in (1.0, -1.0)]
        chains.append({"carriage": [{"type": "prismatic", "axis": [-c, -s, 0.3], "range": [0.0, 30.0]},
                                    {"type": "revolute", "axis": [0.1, 0.0, 1.0], "range": [-10.0, 10.0]}],
                       "legs": legs})
    return parse_mechanism({"name": "slide-turn", "chains": chains})


def test_scan_of_a_revolute_carriage_equals_the_brute_force() -> None:
    """A sampled revolute joint after the exact one: the brute force takes the engine's turntable
    samples (21 over 20 deg at eta_step 1) and 301 slide values; the lines are the base axes."""
    mech = _slide_turn()
    assert symmetry_order(mech) == 1
    scan = OrientationSettings(angle_range=40.0, angle_step=10.0, position_step=10.0, z0=140.0, eta_step=1.0)
    res = general_orientation_workspace(mech, scan)
    assert res.azimuth == 90.0
    n_feasible = 0
    for (ln, rt), reg in res.regions.items():
        pts = scan_points(ln, reg.positions, scan.z0, 90.0)
        for m, alpha in enumerate(reg.angles):
            rot = axis_angle(rotation_axis(rt, 90.0), math.radians(alpha))
            brute = reachable_brute_force(mech, pts, rot, samples={"revolute": 21, "prismatic": 301})
            engine = reg.feasible[:, m]
            assert not np.any(brute & ~engine), (ln, rt, alpha)
            for i in np.flatnonzero(engine & ~brute):
                assert _witness_steps(mech, pts[i], rot), (ln, rt, alpha, pts[i])
            n_feasible += int(engine.sum())
    assert n_feasible > 30


def _witness_steps(mech, point, rot) -> bool:
    sol = mechanism_ik(mech, point, rot, eta_step=1.0)
    lengths = mech.leg_lengths([c.q for c in sol], point, platform_rotation(mech, rot))
    return bool(np.all((lengths >= 110.0 - 1e-6) & (lengths <= 160.0 + 1e-6)))
