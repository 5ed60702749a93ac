"""Joint cones and leg interference (kinematics/joints.py, kinematics/interference.py), and the
atan2-free whole-stroke bound, each against an independent computation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.feasibility import ChainTables, _leg_excluded, cone_interval, default_n_eta
from paraspace.kinematics.geometry import base_points, platform_points
from paraspace.kinematics.interference import clear_configuration, segment_distance
from paraspace.kinematics.joints import Joints, cone_angles, home_height, home_leg_directions
from paraspace.kinematics.rotation import euler_zyx_deg
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace, reachable

# ---------------------------------------------------------------------------------------------
# reference: the whole-stroke bound as it was written with atan2 (before the dot/cross version)

def _ref_contains_angle(d0, d1, target):
    """Whether ``[d0, d1]`` (d1 - d0 < 2 pi) contains ``target + 2 k pi`` for some integer k."""
    k = math.ceil((d0 - target) / (2.0 * math.pi))
    return target + 2.0 * math.pi * k <= d1


def _ref_leg_excluded(bx, by, bz, sigma_hb, v0, v1, rho_lo, rho_hi, lmin2, lmax2):
    """Conservative rho-set of one leg over the whole arc stroke ``varpi in [v0, v1]``.

    Returns (empty, lo, hi, gap_lo, gap_hi): the leg's feasible rho for ANY varpi in the stroke lie in
    ``[lo, hi]`` minus the open gap ``(gap_lo, gap_hi)``.
    """
    rb = math.sqrt(bx * bx + by * by)
    beta = math.atan2(by, bx)
    d0 = beta - v1
    d1 = beta - v0
    ca, cb = math.cos(d0), math.cos(d1)
    sa, sb = math.sin(d0), math.sin(d1)
    cmax = 1.0 if _ref_contains_angle(d0, d1, 0.0) else max(ca, cb)
    cmin = -1.0 if _ref_contains_angle(d0, d1, math.pi) else min(ca, cb)
    smax = 1.0 if _ref_contains_angle(d0, d1, 0.5 * math.pi) else max(sa, sb)
    smin = -1.0 if _ref_contains_angle(d0, d1, -0.5 * math.pi) else min(sa, sb)
    p_lo, p_hi = rb * cmin, rb * cmax
    m_lo, m_hi = rb * smin - sigma_hb, rb * smax - sigma_hb
    if m_lo <= 0.0 <= m_hi:
        m2min = 0.0
    else:
        m2min = min(m_lo * m_lo, m_hi * m_hi)
    m2max = max(m_lo * m_lo, m_hi * m_hi)
    qmin = bz * bz + m2min
    qmax = bz * bz + m2max
    if qmin > lmax2:
        return True, 0.0, 0.0, 0.0, 0.0
    ro = math.sqrt(lmax2 - qmin)
    lo, hi = max(p_lo - ro, rho_lo), min(p_hi + ro, rho_hi)
    if lo > hi:
        return True, 0.0, 0.0, 0.0, 0.0
    g_lo, g_hi = 1.0, 0.0
    if lmin2 > qmax:
        ri = math.sqrt(lmin2 - qmax)
        g_lo, g_hi = p_hi - ri, p_lo + ri
        if g_lo <= lo and hi <= g_hi:
            return True, 0.0, 0.0, 0.0, 0.0
    return False, lo, hi, g_lo, g_hi




def test_whole_stroke_bound_without_atan2_matches_the_polar_form():
    rng = np.random.default_rng(3)
    for design in (Design(), Design(eta_s=180.0), Design(eta_s=0.0), Design(eta_s=100.0, eta_range="from-zero")):
        tab = ChainTables(design, default_n_eta(design))
        lo, hi = design.eta_limits
        for i in range(3):
            v0 = math.atan2(tab.arc[i, 1], tab.arc[i, 0])
            v1 = v0 + math.radians(hi - lo)
            for _ in range(400):
                bx, by = rng.uniform(-250, 250, 2)
                bz = rng.uniform(0, 200)
                lims = (tab.rho_lo, tab.rho_hi, tab.lmin2, tab.lmax2)
                new = _leg_excluded(bx, by, bz, 7.0, *tab.arc[i], *lims)
                old = _ref_leg_excluded(bx, by, bz, 7.0, v0, v1, *lims)
                assert new[0] == old[0]
                if not new[0]:
                    assert np.allclose(new[1:3], old[1:3], atol=1e-9)
                    if old[3] <= old[4]:
                        assert np.allclose(new[3:], old[3:], atol=1e-9)
                    else:
                        assert new[3] > new[4]


# ---------------------------------------------------------------------------------------------
# cone interval (J1) against a fine scan of rho

@pytest.mark.parametrize("seed", range(6))
def test_cone_interval_matches_a_scan(seed):
    rng = np.random.default_rng(seed)
    for _ in range(300):
        alpha, beta = rng.uniform(-150, 150), rng.uniform(-1.2, 1.2)
        k = rng.choice([0.0, rng.uniform(0.05, 0.99), abs(beta)])
        p, q = rng.uniform(-100, 100), rng.uniform(0, 150) ** 2
        lo, hi = cone_interval(alpha, beta, k, p, q)
        rho = np.linspace(-400, 400, 8001)
        holds = alpha + beta * rho >= k * np.sqrt((rho - p) ** 2 + q)
        inside = (rho >= lo) & (rho <= hi)
        # agreement except within one scan step of the ends
        near = (np.abs(rho - lo) < 0.2) | (np.abs(rho - hi) < 0.2)
        assert np.array_equal(holds[~near], inside[~near]), (alpha, beta, k, p, q, lo, hi)


# ---------------------------------------------------------------------------------------------
# cones: the engine against a brute force over (eta samples, fine d) with the acos form of (J1)

def _rot_z(angle_deg):
    c, s_ = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    return np.array([[c, -s_, 0.0], [s_, c, 0.0], [0.0, 0.0, 1.0]])


_BASE_TABLES: dict = {}


def _base_table(design, eta_samples, n_d):
    """The base joints at every (eta sample, d of the fine grid): (eta, d, chain, leg, xyz), built once
    per design and grid from eq. (11) (``geometry.base_points``)."""
    key = (design, eta_samples, n_d)
    if key not in _BASE_TABLES:
        ds = np.linspace(0.0, design.d_s, n_d)
        _BASE_TABLES[key] = np.array([[base_points(design, np.full(3, d), np.full(3, eta)) for d in ds]
                                      for eta in eta_samples])
    return _BASE_TABLES[key]


def _brute_chain_ok(design, joints, rot, pos, eta_samples, n_d=801):
    """Per chain: does some (eta sample, d on a fine grid) satisfy the strokes and both cones? The
    mount axes are built here from their definition: z and R z, or the home leg direction turned
    with the carriage about z (U) and with the platform (S); angles by arccos."""
    b = platform_points(design, pos, rot)
    table = _base_table(design, tuple(eta_samples), n_d)
    home = home_leg_directions(design)
    lo, hi = design.eta_limits
    ok = np.zeros(3, bool)
    for i in range(3):
        for e, eta in enumerate(eta_samples):
            dp = table[e][:, i]  # (n_d, 2, 3)
            leg = b[i][None] - dp
            length = np.linalg.norm(leg, axis=2)
            good = np.all((length >= design.l_min) & (length <= design.l_max), axis=1)
            for j in range(2):
                if joints.cone_axis == "normal":
                    au, as_ = np.array([0.0, 0.0, 1.0]), rot @ np.array([0.0, 0.0, 1.0])
                else:
                    au, as_ = _rot_z(eta - 0.5 * (lo + hi)) @ home[i, j], rot @ home[i, j]
                cu = np.degrees(np.arccos(np.clip(leg[:, j] @ au / length[:, j], -1, 1)))
                cs = np.degrees(np.arccos(np.clip(leg[:, j] @ as_ / length[:, j], -1, 1)))
                if joints.theta_u is not None:
                    good &= cu <= joints.theta_u
                if joints.theta_s is not None:
                    good &= cs <= joints.theta_s
            if good.any():
                ok[i] = True
                break
    return ok


@pytest.mark.slow
@pytest.mark.parametrize("axis", ["normal", "home"])
def test_cones_against_brute_force(axis):
    design = Design()
    joints = Joints(theta_u=40.0, theta_s=35.0, cone_axis=axis)
    orient = (8.0, -6.0, 12.0)
    rot = euler_zyx_deg(*orient)
    step = design.eta_s / 12
    eta_samples = np.linspace(*design.eta_limits, 13)
    rng = np.random.default_rng(11)
    cand = np.column_stack([rng.uniform(-90, 90, 3000), rng.uniform(-90, 90, 3000), rng.uniform(60, 200, 3000)])
    pts = cand[reachable(design, cand, orient, eta_step=step)][:60]  # poses the strokes allow
    eng = reachable(design, pts, orient, eta_step=step, joints=joints)
    brute = np.array([_brute_chain_ok(design, joints, rot, p, eta_samples).all() for p in pts])
    assert np.all(eng[brute])  # exact in d: whatever the fine grid finds, the engine finds
    assert eng.sum() - brute.sum() <= 2  # and it finds little that the grid misses
    assert 5 <= brute.sum() < len(pts)  # the cones bind on some of these poses, not all


def test_cone_with_normal_axes_at_zero_orientation_is_an_upper_leg_length_bound():
    """theta with z axes and R = I: (J1) reads B_z >= L cos(theta), i.e. L <= B_z / cos(theta): the
    cone workspace equals the plain workspace of a mechanism whose legs are capped per pose."""
    design = Design()
    theta = 30.0
    rng = np.random.default_rng(5)
    pts = np.column_stack([rng.uniform(-100, 100, 150), rng.uniform(-100, 100, 150), rng.uniform(60, 180, 150)])
    with_cone = reachable(design, pts, eta_step=design.eta_s / 6, joints=Joints(theta_u=theta))
    tab = ChainTables(design, 7)
    ds = np.linspace(0.0, design.d_s, 301)
    cap = 1.0 / math.cos(math.radians(theta))
    table = _base_table(design, tuple(tab.eta_deg), len(ds))  # every (eta, d) of the fine grid at once
    brute = np.ones(len(pts), bool)
    for n, p in enumerate(pts):
        b = platform_points(design, p, np.eye(3))
        for i in range(3):
            lengths = np.linalg.norm(b[i] - table[:, :, i], axis=-1)  # (eta, d, leg)
            ok = (lengths.min(axis=-1) >= design.l_min) & \
                np.all(lengths <= np.minimum(design.l_max, b[i, :, 2] * cap), axis=-1)
            brute[n] &= bool(ok.any())
    assert np.all(with_cone[brute])  # exact in d: the fine grid never finds more
    assert with_cone.sum() - brute.sum() <= 2  # nor much less
    assert 0 < with_cone.sum() < reachable(design, pts, eta_step=design.eta_s / 6).sum()


def test_ninety_degree_normal_cones_change_nothing_above_the_base():
    design = Design()
    plain = compute_workspace(design, WorkspaceSettings(voxel=4.0))
    wide = compute_workspace(design, WorkspaceSettings(voxel=4.0, joints=Joints(theta_u=90.0, theta_s=90.0)))
    assert np.array_equal(plain.occupancy, wide.occupancy)


@pytest.mark.parametrize("joints,orient,design", [
    (Joints(theta_u=45.0, theta_s=45.0), (0.0, 0.0, 0.0), Design()),
    (Joints(theta_u=30.0), (10.0, 5.0, -20.0), Design()),
    (Joints(theta_s=40.0, cone_axis="home"), (0.0, 0.0, 0.0), Design()),
    (Joints(theta_u=50.0, theta_s=45.0, cone_axis="home"), (-15.0, 10.0, 5.0), Design(eta_s=60.0, eta_range="from-zero")),
    (Joints(theta_u=45.0, leg_diameter=8.0, clearance=2.0), (0.0, 0.0, 0.0), Design(a=30.0)),
    (Joints(leg_diameter=10.0), (5.0, 0.0, 10.0), Design()),
])
def test_blocks_engine_equals_dense_engine_with_joint_options(joints, orient, design):
    runs = {m: compute_workspace(design, WorkspaceSettings(voxel=4.0, orientation=orient, joints=joints, method=m))
            for m in ("dense", "blocks")}
    assert runs["dense"].grid.shape == runs["blocks"].grid.shape
    assert np.array_equal(runs["dense"].occupancy, runs["blocks"].occupancy)
    diag = {m: compute_workspace(design, WorkspaceSettings(voxel=6.0, orientation=orient, joints=joints, method=m,
                                                           diagnostics=True)) for m in ("dense", "blocks")}
    assert np.array_equal(diag["dense"].chain_mask, diag["blocks"].chain_mask)
    assert runs["dense"].voxels > 0


def test_cones_shrink_the_workspace_monotonically():
    design = Design()
    vols = [compute_workspace(design, WorkspaceSettings(voxel=4.0, joints=Joints(theta_u=t, theta_s=t))).voxels
            for t in (60.0, 45.0, 30.0)]
    assert vols[0] > vols[1] > vols[2] > 0
    tight = compute_workspace(design, WorkspaceSettings(voxel=4.0, joints=Joints(theta_u=30.0, theta_s=30.0)))
    loose = compute_workspace(design, WorkspaceSettings(voxel=4.0, bounds=(tight.grid.lo, tight.grid.hi),
                                                        joints=Joints(theta_u=60.0, theta_s=60.0)))
    assert not np.any(tight.occupancy & ~loose.occupancy)


def test_bracket_with_cones_contains_the_estimates():
    design = Design()
    j = Joints(theta_u=45.0, theta_s=45.0, cone_axis="home")
    coarse = compute_workspace(design, WorkspaceSettings(voxel=4.0, joints=j, bracket=True))
    fine = compute_workspace(design, WorkspaceSettings(voxel=2.0, joints=j))
    assert coarse.volume_inner <= coarse.volume <= coarse.volume_outer
    assert coarse.volume_inner <= fine.volume <= coarse.volume_outer


def test_home_pose_has_mid_length_legs_and_zero_angles_on_home_axes():
    design = Design()
    z = home_height(design)
    b = platform_points(design, np.array([0.0, 0.0, z]), np.eye(3))
    dp = base_points(design, np.full(3, design.d_s / 2), np.zeros(3))
    lengths = np.linalg.norm(b - dp, axis=2)
    assert np.allclose(lengths, 0.5 * (design.l_min + design.l_max))
    ang = cone_angles(design, Joints(theta_u=10.0, theta_s=10.0, cone_axis="home"), np.eye(3), b, dp, np.zeros(3))
    assert np.allclose(ang, 0.0, atol=1e-6)
    dirs = home_leg_directions(design)
    assert np.allclose(np.linalg.norm(dirs, axis=2), 1.0)


@pytest.mark.parametrize("bad", [dict(theta_u=0.0), dict(theta_s=91.0), dict(theta_u="x"), dict(cone_axis="up"),
                                 dict(leg_diameter=-1.0), dict(clearance=2.0)])
def test_bad_joint_values_name_the_field(bad):
    with pytest.raises(ParameterError) as err:
        Joints(**bad)
    assert next(iter(bad)) in str(err.value)


# ---------------------------------------------------------------------------------------------
# interference

def _sampled_distance(a, b, c, d, n=400):
    s = np.linspace(0, 1, n)[:, None]
    p = a + s * (b - a)
    q = c + s * (d - c)
    return float(np.min(np.linalg.norm(p[:, None, :] - q[None, :, :], axis=2)))


def test_segment_distance_against_sampling():
    rng = np.random.default_rng(2)
    for _ in range(200):
        a, b, c, d = rng.normal(size=(4, 3)) * 10
        exact = segment_distance(*a, *b, *c, *d)
        approx = _sampled_distance(a, b, c, d)
        # sampled points are on the segments: never below the exact distance, and close to it
        assert exact <= approx + 1e-9
        assert approx - exact < 0.1
    # parallel and degenerate segments
    assert segment_distance(0, 0, 0, 1, 0, 0, 0, 2, 0, 1, 2, 0) == pytest.approx(2.0)
    assert segment_distance(0, 0, 0, 0, 0, 0, 3, 4, 0, 3, 4, 0) == pytest.approx(5.0)


@pytest.mark.slow
def test_interference_witness_is_a_real_clear_configuration():
    """Every pose the engine keeps comes with a carriage configuration that satisfies strokes, cones
    and every clearance, checked here with numpy geometry and sampled segment distances."""
    design = Design()
    joints = Joints(theta_u=60.0, leg_diameter=10.0, clearance=2.0)
    rng = np.random.default_rng(8)
    pts = np.column_stack([rng.uniform(-140, 140, 400), rng.uniform(-140, 140, 400), rng.uniform(0, 200, 400)])
    n_eta = default_n_eta(design)
    keep = reachable(design, pts, joints=joints)
    plain = reachable(design, pts, joints=Joints(theta_u=60.0))
    assert keep.sum() > 20 and keep.sum() < plain.sum()  # interference binds on some poses
    assert not np.any(keep & ~plain)
    for p in pts[keep][:60]:
        conf = clear_configuration(design, joints, p, np.eye(3), n_eta)
        assert conf is not None
        d, eta = conf
        assert np.all(d >= -1e-9) and np.all(d <= design.d_s + 1e-9)
        lo, hi = design.eta_limits
        assert np.all(eta >= lo - 1e-9) and np.all(eta <= hi + 1e-9)
        b = platform_points(design, p, np.eye(3))
        dp = base_points(design, d, eta)
        lengths = np.linalg.norm(b - dp, axis=2)
        assert lengths.min() >= design.l_min - 1e-6 and lengths.max() <= design.l_max + 1e-6
        assert cone_angles(design, joints, np.eye(3), b, dp, eta)[:, :, 0].max() <= 60.0 + 1e-6
        legs = [(dp[i, j], b[i, j]) for i in range(3) for j in range(2)]
        for x in range(6):
            for y in range(x + 1, 6):
                assert _sampled_distance(*legs[x], *legs[y], n=120) >= joints.min_distance - 1e-6


# ---------------------------------------------------------------------------------------------
# the redundancy resolver agrees with the engine, also with joint options

def _near_boundary_points(design, n, seed=0):
    from paraspace.kinematics.diagnostics import surface_layer

    r = compute_workspace(design, WorkspaceSettings(voxel=4.0))
    layer = surface_layer(r.occupancy) | surface_layer(~r.occupancy)
    idx = np.argwhere(layer)
    rng = np.random.default_rng(seed)
    idx = idx[rng.choice(len(idx), n, replace=False)]
    return np.asarray(r.grid.origin) + r.grid.h * idx + rng.uniform(-2, 2, (n, 3))


@pytest.mark.slow
def test_ik_never_contradicts_the_engine_and_is_near_the_best_margin():
    """At 600 poses near the workspace surface (1,800 chain tests): a chain the engine serves is
    feasible in ``ik``; the resolver's margin is within 0.25 (length units) of the best margin on a
    201 x 201 brute-force grid over the strokes (measured worst: 0.19 on 7,500 tests)."""
    from paraspace.kinematics.geometry import GAMMA
    from paraspace.kinematics.pose import Pose
    from paraspace.kinematics.redundancy import _chain_margins, resolve_redundancy
    from paraspace.kinematics.workspace import chain_masks_at

    design = Design()
    pts = _near_boundary_points(design, 600)
    masks = chain_masks_at(design, pts)
    eta = np.radians(np.linspace(*design.eta_limits, 201))
    rho = np.linspace(*design.rho_limits, 201)
    for p, m in zip(pts, masks):
        res = resolve_redundancy(design, Pose(*p))
        b = platform_points(design, p, np.eye(3))
        for i in range(3):
            if (m >> i) & 1:
                assert res.chains[i].feasible, (p, i)
            best = _chain_margins(design, b[i], GAMMA[i] + eta, rho).max()
            assert res.chains[i].margin >= best - 0.25, (p, i)


def test_ik_with_joints_agrees_with_the_engine():
    from paraspace.kinematics.pose import Pose
    from paraspace.kinematics.redundancy import resolve_redundancy

    design = Design()
    joints = Joints(theta_u=45.0, theta_s=45.0, leg_diameter=10.0)
    rng = np.random.default_rng(4)
    pts = np.column_stack([rng.uniform(-120, 120, 150), rng.uniform(-120, 120, 150), rng.uniform(10, 190, 150)])
    eng = reachable(design, pts, joints=joints)
    assert 10 < eng.sum() < len(pts)
    for p, e in zip(pts, eng):
        res = resolve_redundancy(design, Pose(*p), joints=joints)
        if e:
            assert res.feasible, (p, res.message)
            assert res.cone_angles.max() <= 45.0 + 1e-6
            assert res.min_leg_distance >= 10.0 - 1e-6
        elif not res.feasible:
            assert "unreachable" in res.message


def test_diagnostics_name_the_cones():
    from paraspace.kinematics.diagnostics import limit_binding

    res = compute_workspace(Design(), WorkspaceSettings(voxel=5.0, joints=Joints(theta_u=35.0, theta_s=35.0)))
    lb = limit_binding(res, max_samples=300)
    assert lb.fractions["u_cone"] + lb.fractions["s_cone"] + lb.fractions["cones"] > 0.3
    assert "cone" in lb.summary
