"""Leg interference decided block by block (kinematics/interference_blocks.py) against the per-voxel
witness search of kinematics/interference.py at every voxel, and the own-leg distance bounds against
brute-force sampled moves."""

from __future__ import annotations

import numpy as np
import pytest

from paraspace.kinematics.design import Design
from paraspace.kinematics.feasibility import default_n_eta
from paraspace.kinematics.interference import interference_free, segment_distance
from paraspace.kinematics.interference_blocks import _own_bounds, interference_free_grid
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.rotation import euler_zyx_deg
from paraspace.kinematics.workspace import INTERFERENCE, WorkspaceSettings, compute_workspace


def _tables_without_cones():
    """``(design, tables, u, jc)`` of the default design with 61 arc samples, its platform points at
    zero orientation and a cone table that sets no cone (checked)."""
    from paraspace.kinematics.feasibility import ChainTables
    from paraspace.kinematics.geometry import platform_points_local
    from paraspace.kinematics.joints import cone_table

    design = Design()
    tab = ChainTables(design, 61)
    u = np.ascontiguousarray(platform_points_local(design))
    jc = np.ascontiguousarray(cone_table(design, Joints(), np.eye(3)))
    assert (jc[:, :, 6:8] == -1.0).all()  # no cone set
    return design, tab, u, jc


@pytest.mark.parametrize("design,joints,orient,h", [
    (Design(), Joints(leg_diameter=10.0), (0.0, 0.0, 0.0), 3.0),
    (Design(), Joints(leg_diameter=6.0, clearance=1.0), (0.0, 0.0, 0.0), 3.5),
    (Design(), Joints(leg_diameter=30.0, clearance=5.0), (0.0, 0.0, 0.0), 4.0),
    (Design(a=30.0), Joints(theta_u=45.0, leg_diameter=10.0, clearance=2.0), (5.0, 0.0, 10.0), 3.0),
    (Design(b=30.0, eta_s=60.0, eta_range="from-zero"), Joints(leg_diameter=12.0), (0.0, 8.0, 0.0), 5.0),
])
def test_blocks_decide_the_voxels_of_the_per_voxel_search(design, joints, orient, h):
    plain = compute_workspace(design, WorkspaceSettings(voxel=h, orientation=orient, joints=Joints(
        theta_u=joints.theta_u, theta_s=joints.theta_s, cone_axis=joints.cone_axis)))
    occ = plain.occupancy
    xs, ys, zs = plain.grid.axes()
    rot = euler_zyx_deg(*orient)
    idx = np.argwhere(occ)
    pts = np.stack([xs[idx[:, 0]], ys[idx[:, 1]], zs[idx[:, 2]]], axis=1)
    old = interference_free(design, joints, pts, rot[None], plain.n_eta)[:, 0]
    new = interference_free_grid(design, joints, (xs, ys, zs), h, rot, plain.n_eta, occ)
    assert not np.any(new & ~occ)  # only the voxels asked about
    assert np.array_equal(new[idx[:, 0], idx[:, 1], idx[:, 2]], old)
    if joints.min_distance < 30.0:
        assert 0 < old.sum() < old.size  # both answers occur: the test can tell them apart
    # the engine uses it: its voxels are the plain ones less the interfering ones, flagged
    full = compute_workspace(design, WorkspaceSettings(voxel=h, orientation=orient, joints=joints,
                                                       bounds=(plain.grid.lo, plain.grid.hi)))
    assert np.array_equal(full.occupancy, new)


def test_own_leg_bounds_hold_for_sampled_moves():
    """``_own_bounds(rho, ..., shift)`` brackets the two legs' distance after every move of the platform
    and the carriage that shifts leg 1's vector by at most ``shift`` (random moves, closed-form
    distance)."""
    design = Design()
    rng = np.random.default_rng(5)
    hb = 0.5 * design.b
    checked = 0
    for _ in range(300):
        eta = rng.uniform(-0.3, 0.3)
        c, s = np.cos(eta), np.sin(eta)
        rho = rng.uniform(50.0, 100.0)
        b = np.array([[rng.uniform(-40, 40), rng.uniform(-40, 40), rng.uniform(80, 200)] for _ in range(2)])
        b[1] = b[0] + rng.normal(size=3) * 15.0
        shift = rng.uniform(0.0, 6.0)
        lo, hi, d0 = _own_bounds(rho, c, s, hb, b[0, 0], b[0, 1], b[0, 2], b[1, 0], b[1, 1], b[1, 2], shift)
        at = (rho * c - hb * s, rho * s + hb * c, 0.0), (rho * c + hb * s, rho * s - hb * c, 0.0)
        assert d0 == pytest.approx(segment_distance(*at[0], *b[0], *at[1], *b[1]), abs=1e-9)
        for _ in range(40):
            v = rng.normal(size=3)
            v *= rng.uniform(0, 1) * shift / np.linalg.norm(v)
            dr = rng.uniform(-1, 1) * (shift - np.linalg.norm(v))  # rail move: the rest of the budget
            r = rho + dr
            d1 = (r * c - hb * s, r * s + hb * c, 0.0)
            d2 = (r * c + hb * s, r * s - hb * c, 0.0)
            dist = segment_distance(*d1, *(b[0] + v), *d2, *(b[1] + v))
            assert lo - 1e-9 <= dist <= hi + 1e-9
            checked += 1
    assert checked == 12000


def test_own_legs_bisection_holds_for_sampled_rho_and_moves():
    """``_own_legs`` (the bisection over a rail range, walked by the indices of its pieces): where it
    says the two legs clear ``thr`` (or stay below it) over ``[r0, r1]`` after every move of at most
    ``e``, sampled rails and moves agree (closed-form distance); both answers and "cannot tell" occur,
    and a range it proves clear is also proved clear on either half."""
    from paraspace.kinematics.interference_blocks import _own_legs

    design = Design()
    rng = np.random.default_rng(17)
    hb = 0.5 * design.b
    said = {True: 0, False: 0, None: 0}
    for _ in range(600):
        eta = rng.uniform(-0.3, 0.3)
        c, s = np.cos(eta), np.sin(eta)
        r0 = rng.uniform(40.0, 100.0)
        r1 = r0 + rng.uniform(0.0, 20.0)
        b = np.array([[rng.uniform(-40, 40), rng.uniform(-40, 40), rng.uniform(80, 200)] for _ in range(2)])
        b[1] = b[0] + rng.normal(size=3) * 15.0
        e = rng.uniform(0.0, 3.0)
        rm = 0.5 * (r0 + r1)  # a threshold near the legs' distance at the range's middle: all three answers
        thr = max(segment_distance(rm * c - hb * s, rm * s + hb * c, 0.0, *b[0], rm * c + hb * s, rm * s - hb * c,
                                   0.0, *b[1]) + rng.uniform(-4.0, 4.0), 0.5)
        clear = bool(_own_legs(*b[0], *b[1], c, s, hb, r0, r1, e, thr, True))
        below = bool(_own_legs(*b[0], *b[1], c, s, hb, r0, r1, e, thr, False))
        assert not (clear and below)
        said[True if clear else (False if below else None)] += 1
        if clear:
            m = 0.5 * (r0 + r1)
            assert _own_legs(*b[0], *b[1], c, s, hb, r0, m, e, thr, True)
            assert _own_legs(*b[0], *b[1], c, s, hb, m, r1, e, thr, True)
        if not (clear or below):
            continue
        for _ in range(30):
            v = rng.normal(size=3)
            v *= rng.uniform(0, 1) * e / np.linalg.norm(v)
            r = rng.uniform(r0, r1)
            d1 = (r * c - hb * s, r * s + hb * c, 0.0)
            d2 = (r * c + hb * s, r * s - hb * c, 0.0)
            dist = segment_distance(*d1, *(b[0] + v), *d2, *(b[1] + v))
            assert dist >= thr - 1e-9 if clear else dist <= thr + 1e-9
    assert min(said.values()) > 20  # every answer is exercised


def test_own_upper_bound_alone_is_the_one_of_both_bounds():
    """``_own_upper`` (the upper bound alone, for the test that a sample's own legs always collide) gives
    the very ``(hi, d0)`` of ``_own_bounds`` at random carriages, S joints and shifts."""
    from paraspace.kinematics.interference_blocks import _own_upper

    design = Design()
    rng = np.random.default_rng(29)
    hb = 0.5 * design.b
    for _ in range(2000):
        eta = rng.uniform(-0.5, 0.5)
        c, s = np.cos(eta), np.sin(eta)
        rho = rng.uniform(30.0, 110.0)
        b = np.array([[rng.uniform(-60, 60), rng.uniform(-60, 60), rng.uniform(40, 220)] for _ in range(2)])
        b[1] = b[0] + rng.normal(size=3) * rng.uniform(0.5, 30.0)
        shift = rng.uniform(0.0, 8.0)
        lo, hi, d0 = _own_bounds(rho, c, s, hb, *b[0], *b[1], shift)
        assert _own_upper(rho, c, s, hb, *b[0], *b[1], shift) == (hi, d0)


def test_witness_without_cones_is_the_general_one():
    """``_plain_witness`` (numbers only, for chains without joint cones) returns the very ``rho`` of
    ``_sample_witness`` (``feasible_rho``'s intervals, then each one's probes) with a cone table that
    sets no cone, at random poses, samples and clearances: no witness because the sample does not
    serve, no witness because every probe collides, and a witness at an interval's low end and at its
    high end all occur. (An interval's middle never was the first probe to clear in these samples, nor
    in 200,000 more: the own legs' distance had no maximum inside a feasible interval. Both functions
    probe it with the same code, :func:`_piece_witness`.)"""
    from paraspace.kinematics.feasibility import chain_points, feasible_rho
    from paraspace.kinematics.interference import _plain_witness, _sample_witness

    design, tab, u, jc = _tables_without_cones()
    rng = np.random.default_rng(31)
    pieces = np.empty((4, 2))
    seen = {"does not serve": 0, "every probe collides": 0, "low end": 0, "high end": 0}
    for _ in range(6000):
        p = rng.uniform((-150, -150, 60), (150, 150, 260))
        i, k = int(rng.integers(3)), int(rng.integers(61))
        pts = chain_points(*p, u, i)
        if rng.uniform() < 0.5:  # the second S joint moved about: own legs that cross, at some rho
            pts = (*pts[:3], *(np.array(pts[:3]) + rng.normal(size=3) * 20.0))
        c, s = tab.cos_t[i, k], tab.sin_t[i, k]
        args = (*pts, c, s, tab.hb, tab.rho_lo, tab.rho_hi, tab.lmin2, tab.lmax2)
        npc = feasible_rho(*args, jc[i], pieces)
        # a clearance about the own legs' distances at the first interval's probes: every outcome occurs
        probes = [pieces[0, 0], pieces[0, 1], 0.5 * (pieces[0, 0] + pieces[0, 1])] if npc else [100.0]
        dist = [segment_distance(r * c - tab.hb * s, r * s + tab.hb * c, 0.0, *pts[:3],
                                 r * c + tab.hb * s, r * s - tab.hb * c, 0.0, *pts[3:]) for r in probes]
        dmin = rng.uniform(0.0, 1.3 * max(dist))
        a = _sample_witness(*args, jc[i], dmin, pieces)
        b = _plain_witness(*args, dmin)
        assert (np.isnan(a) and np.isnan(b)) or a == b
        npc = feasible_rho(*args, jc[i], pieces)
        if npc == 0:
            seen["does not serve"] += 1
        elif np.isnan(a):
            seen["every probe collides"] += 1
        else:
            ends = [(lo, hi) for lo, hi in pieces[:npc] if lo <= a <= hi][0]
            kind = "low end" if a == ends[0] else ("high end" if a == ends[1] else "middle")
            seen[kind] = seen.get(kind, 0) + 1
    assert min(seen.values()) > 10, seen


def test_relaxed_hull_without_cones_is_the_general_one():
    """``_relaxed_hull_plain`` (numbers only, for chains without joint cones) gives the very numbers of
    ``_relaxed_hull`` with a cone table that sets no cone, at random poses, samples and limits."""
    from paraspace.kinematics.feasibility import chain_points
    from paraspace.kinematics.interference_blocks import _relaxed_hull, _relaxed_hull_plain

    design, tab, u, jc = _tables_without_cones()
    rng = np.random.default_rng(23)
    oks = 0
    for _ in range(3000):
        p = rng.uniform((-150, -150, 60), (150, 150, 260))
        i, k = int(rng.integers(3)), int(rng.integers(61))
        e = rng.uniform(-3.0, 3.0)
        lo2, hi2 = max(design.l_min - e, 0.0) ** 2, (design.l_max + e) ** 2
        pts = chain_points(*p, u, i)
        a = _relaxed_hull(*pts, tab.cos_t[i, k], tab.sin_t[i, k], tab.hb, tab.rho_lo, tab.rho_hi, lo2, hi2,
                          jc[i], e)
        b = _relaxed_hull_plain(*pts, tab.cos_t[i, k], tab.sin_t[i, k], tab.hb, tab.rho_lo, tab.rho_hi, lo2, hi2)
        assert a == b
        oks += a[0]
    assert 100 < oks < 2900  # both answers occur


def test_interference_bit_is_set_where_the_legs_interfere():
    design = Design()
    joints = Joints(leg_diameter=10.0)
    res = compute_workspace(design, WorkspaceSettings(voxel=6.0, joints=joints, diagnostics=True))
    plain = compute_workspace(design, WorkspaceSettings(voxel=6.0, diagnostics=True, bounds=(res.grid.lo,
                                                                                              res.grid.hi)))
    flagged = (res.chain_mask & INTERFERENCE) > 0
    assert np.array_equal(flagged, plain.occupancy & ~res.occupancy)
    assert flagged.any()
    assert default_n_eta(design) == res.n_eta


def test_cancel_stops_the_block_search():
    from paraspace.kinematics.progress import Cancelled

    design = Design()
    plain = compute_workspace(design, WorkspaceSettings(voxel=8.0))
    calls = []

    def cancel() -> bool:  # set after the first check: the search stops between launches
        calls.append(1)
        return len(calls) > 1

    with pytest.raises(Cancelled):
        interference_free_grid(design, Joints(leg_diameter=10.0), plain.grid.axes(), 8.0, np.eye(3), plain.n_eta,
                               plain.occupancy, cancel)


def test_samples_marked_for_a_block_are_no_witness_at_any_of_its_voxels():
    """``_exclude`` marks the arc samples children and voxels then pass over: at every voxel centre of
    the block, the per-voxel witness search restricted to one marked sample finds no witness there
    (brute force over every voxel, chain and marked sample), and a block it calls blocked interferes
    at every voxel."""
    import math

    from paraspace.kinematics.blocks import rounding_margin
    from paraspace.kinematics.feasibility import ChainTables, chain_points
    from paraspace.kinematics.geometry import platform_points_local
    from paraspace.kinematics.interference import _witnesses
    from paraspace.kinematics.interference_blocks import _exclude
    from paraspace.kinematics.joints import cone_table

    design, joints, h, m = Design(), Joints(leg_diameter=10.0), 4.0, 3
    plain = compute_workspace(design, WorkspaceSettings(voxel=h))
    occ = plain.occupancy
    xs, ys, zs = plain.grid.axes()
    tab = ChainTables(design, plain.n_eta)
    rot = np.eye(3)
    u = np.ascontiguousarray(platform_points_local(design) @ rot.T)
    jc = np.ascontiguousarray(cone_table(design, joints, rot))
    eps = rounding_margin(math.sqrt(tab.lmax2), (xs, ys, zs))
    n = tab.cos_t.shape[1]
    ok = interference_free_grid(design, joints, (xs, ys, zs), h, rot, plain.n_eta, occ)
    marked = blocked = 0
    rng = np.random.default_rng(3)
    starts = np.argwhere(occ[:-m, :-m, :-m])
    for x0, y0, z0 in starts[rng.choice(len(starts), 60, replace=False)]:
        cx, cy, cz = (0.5 * (a[i] + a[i + m - 1]) for a, i in ((xs, x0), (ys, y0), (zs, z0)))
        e = 0.5 * h * math.sqrt(3.0) * (m - 1) + eps
        skip = np.zeros((1, 3, n), np.bool_)
        bx, by, bz = np.empty((3, 2)), np.empty((3, 2)), np.empty((3, 2))
        is_blocked = _exclude(cx, cy, cz, e, u, tab.cos_t, tab.sin_t, tab.hb, tab.rho_lo, tab.rho_hi,
                              math.sqrt(tab.lmin2), math.sqrt(tab.lmax2), jc, joints.min_distance, 100.0 * eps, skip,
                              0, bx, by, bz)
        block = occ[x0:x0 + m, y0:y0 + m, z0:z0 + m]
        if is_blocked:
            blocked += 1
            assert not ok[x0:x0 + m, y0:y0 + m, z0:z0 + m][block].any()
        w = np.empty((3, n, 6))
        for ix, iy, iz in np.argwhere(block) + (x0, y0, z0):
            for i in range(3):
                pts = chain_points(xs[ix], ys[iy], zs[iz], u, i)
                for k in np.nonzero(skip[0, i])[0]:
                    solo = np.ones((1, 3, n), np.bool_)
                    solo[0, i, k] = False
                    assert _witnesses(*pts, tab.cos_t, tab.sin_t, i, tab.hb, tab.rho_lo, tab.rho_hi, tab.lmin2,
                                      tab.lmax2, jc, joints.min_distance, 1, w, solo, 0, np.empty((4, 2)),
                                      ys[iy] < 0.0, 0, 0)[0] == 0
                    marked += 1
    assert marked > 100 and blocked > 0  # the check has samples and blocked blocks to look at


def test_blocks_decide_only_the_voxels_asked_about():
    """On a sparse ``where`` (every third voxel the chains reach, so most blocks, down to two voxels
    across, hold voxels left out) the answer is the per-voxel search's at the voxels asked about and
    False elsewhere: a block with voxels left out is never decided clear as a whole, and a block with
    nothing to test is skipped."""
    design, joints, h = Design(), Joints(leg_diameter=10.0), 4.0
    plain = compute_workspace(design, WorkspaceSettings(voxel=h))
    xs, ys, zs = plain.grid.axes()
    where = plain.occupancy.copy()
    idx = np.argwhere(where)
    where[tuple(idx[np.arange(len(idx)) % 3 != 0].T)] = False
    idx = np.argwhere(where)
    pts = np.stack([xs[idx[:, 0]], ys[idx[:, 1]], zs[idx[:, 2]]], axis=1)
    old = interference_free(design, joints, pts, np.eye(3)[None], plain.n_eta)[:, 0]
    new = interference_free_grid(design, joints, (xs, ys, zs), h, np.eye(3), plain.n_eta, where)
    assert not np.any(new & ~where)
    assert np.array_equal(new[idx[:, 0], idx[:, 1], idx[:, 2]], old)
    assert 0 < old.sum() < old.size


def test_one_interval_rule_holds_at_every_centre_of_the_block():
    """``_no_split``: where it says a leg's gap leaves the relaxed hull in one piece at every centre of a
    block, the per-voxel feasible set (:func:`kinematics.feasibility.feasible_rho`) is one interval at
    random points within the block's half-diagonal of its centre (brute force); and the rule's second
    case (the relaxed gap reaches past an end of the hull, as at the lower end of a rail where the legs
    are short) fires on blocks where the first (the tightened gap misses the hull) does not."""
    import math

    from paraspace.kinematics.blocks import rounding_margin
    from paraspace.kinematics.feasibility import ChainTables, chain_points, feasible_rho
    from paraspace.kinematics.geometry import platform_points_local
    from paraspace.kinematics.interference_blocks import _no_split, _relaxed_hull
    from paraspace.kinematics.joints import cone_table

    design, joints, h = Design(), Joints(leg_diameter=10.0), 4.0
    plain = compute_workspace(design, WorkspaceSettings(voxel=h))
    xs, ys, zs = plain.grid.axes()
    tab = ChainTables(design, plain.n_eta)
    u = np.ascontiguousarray(platform_points_local(design))
    jc = np.ascontiguousarray(cone_table(design, joints, np.eye(3)))
    eps = rounding_margin(math.sqrt(tab.lmax2), (xs, ys, zs))
    lmin, lmax = math.sqrt(tab.lmin2), math.sqrt(tab.lmax2)
    n = tab.cos_t.shape[1]
    rng = np.random.default_rng(11)
    idx = np.argwhere(plain.occupancy)
    pieces = np.empty((4, 2))
    # 400 random (voxel, chain, sample) draws and every draw of 6000 where a gap splits the feasible set at
    # the block centre itself (rare: where a rule that ignored where the gap lies would go wrong)
    draws = [(v, int(rng.integers(3)), int(rng.integers(n))) for v in idx[rng.choice(len(idx), 6000)]]
    split = [(v, i, k) for v, i, k in draws
             if feasible_rho(*chain_points(xs[v[0]], ys[v[1]], zs[v[2]], u, i), tab.cos_t[i, k], tab.sin_t[i, k],
                             tab.hb, tab.rho_lo, tab.rho_hi, tab.lmin2, tab.lmax2, jc[i], pieces) > 1]
    one_blocks = second_case = 0
    for (ix, iy, iz), i, k in draws[:400] + split:
        pc = np.array([xs[ix], ys[iy], zs[iz]])
        e = rng.uniform(0.5, 12.0) + eps
        c, s = tab.cos_t[i, k], tab.sin_t[i, k]
        pts = chain_points(*pc, u, i)
        ok, r0, r1, h1a, h1b, h2a, h2b = _relaxed_hull(*pts, c, s, tab.hb, tab.rho_lo, tab.rho_hi,
                                                       max(lmin - e, 0.0) ** 2, (lmax + e) ** 2, jc[i], e)
        if not ok:
            continue
        _, _, _, g1a, g1b, g2a, g2b = _relaxed_hull(*pts, c, s, tab.hb, tab.rho_lo, tab.rho_hi, (lmin + e) ** 2,
                                                    (lmax - e) ** 2, jc[i], -e)
        if not (_no_split(g1a, g1b, h1a, h1b, r0, r1) and _no_split(g2a, g2b, h2a, h2b, r0, r1)):
            continue
        one_blocks += 1
        first = all(ga > gb or gb <= r0 or ga >= r1 for ga, gb in ((g1a, g1b), (g2a, g2b)))
        second_case += not first
        for q in range(40):
            v = rng.normal(size=3)
            p = pc + v / np.linalg.norm(v) * (e - eps) * rng.uniform(0.0, 1.0) ** (1 / 3) * (q > 0)
            cnt = feasible_rho(*chain_points(*p, u, i), c, s, tab.hb, tab.rho_lo, tab.rho_hi, tab.lmin2, tab.lmax2,
                               jc[i], pieces)
            assert cnt <= 1, (pc, e, i, k, p, pieces[:cnt])
            if cnt:
                assert r0 - 1e-9 <= pieces[0, 0] and pieces[0, 1] <= r1 + 1e-9  # inside the relaxed hull
    assert len(split) > 10 and one_blocks > 100 and second_case > 10  # every case is exercised


def test_the_witness_search_commutes_with_the_mirror():
    """The per-voxel search turns its scan order with the sign of ``y`` (kinematics/interference.py,
    step 2), so on the default (mirror-symmetric) design a pose and its mirror image ``y -> -y`` get
    the same answer at every voxel the chains reach, and the engine's occupancy with leg interference
    is mirror-symmetric. With one order for both signs, 828 voxels at h = 2 had a mirror image with the
    other answer."""
    design, joints, h = Design(), Joints(leg_diameter=10.0), 2.0
    legs = compute_workspace(design, WorkspaceSettings(voxel=h, joints=joints))
    assert legs.occupancy.any() and np.array_equal(legs.occupancy, legs.occupancy[:, ::-1, :])
    plain = compute_workspace(design, WorkspaceSettings(voxel=h, bounds=(legs.grid.lo, legs.grid.hi)))
    xs, ys, zs = plain.grid.axes()
    idx = np.argwhere(plain.occupancy & (ys > 0.0)[None, :, None])
    pts = np.stack([xs[idx[:, 0]], ys[idx[:, 1]], zs[idx[:, 2]]], axis=1)
    up = interference_free(design, joints, pts, np.eye(3)[None], plain.n_eta)[:, 0]
    down = interference_free(design, joints, pts * np.array([1.0, -1.0, 1.0]), np.eye(3)[None], plain.n_eta)[:, 0]
    assert 0 < up.sum() < up.size
    assert np.array_equal(up, down)
    # the engine's voxels on the upper side are the per-voxel answers there
    assert np.array_equal(legs.occupancy[idx[:, 0], idx[:, 1], idx[:, 2]], up)


@pytest.mark.parametrize("odd", [False, True])
def test_the_mirror_half_decides_the_whole_grid(odd):
    """``interference_free_grid(mirror=True)`` decides the rows ``j >= n_y // 2`` and copies the others
    from their mirror images: the same voxels as the whole grid and as the per-voxel search, on a grid
    with an even ``n_y`` and on one with a middle row at ``y = 0`` (odd ``n_y``)."""
    design, joints, h = Design(), Joints(leg_diameter=10.0), 3.0
    bounds = ((-180.0, -60.5 * h, 0.0), (180.0, 60.5 * h, 165.0)) if odd else None
    plain = compute_workspace(design, WorkspaceSettings(voxel=h, bounds=bounds))
    xs, ys, zs = plain.grid.axes()
    occ = plain.occupancy
    assert (ys.size % 2 == 1) == odd and np.array_equal(occ, occ[:, ::-1, :])
    if odd:
        assert ys[ys.size // 2] == 0.0 and occ[:, ys.size // 2].any()
    whole = interference_free_grid(design, joints, (xs, ys, zs), h, np.eye(3), plain.n_eta, occ)
    half = interference_free_grid(design, joints, (xs, ys, zs), h, np.eye(3), plain.n_eta, occ, mirror=True)
    assert np.array_equal(half, whole)
    idx = np.argwhere(occ)
    pts = np.stack([xs[idx[:, 0]], ys[idx[:, 1]], zs[idx[:, 2]]], axis=1)
    old = interference_free(design, joints, pts, np.eye(3)[None], plain.n_eta)[:, 0]
    assert 0 < old.sum() < old.size
    assert np.array_equal(whole[idx[:, 0], idx[:, 1], idx[:, 2]], old)


@pytest.mark.parametrize("ny,zero_at,mirror,tilt", [
    (37, 0, False, 0.0), (37, 37, False, 0.0), (37, 21, False, 0.0), (40, 9, False, 0.0),
    (37, 18, True, 0.0), (37, 18, True, -1e-16), (40, 20, True, 0.0), (1, 0, False, 0.0), (1, 0, True, 0.0),
    (1, 0, True, -1e-16)])
def test_top_blocks_tile_the_grid_without_a_block_across_y_0(ny, zero_at, mirror, tilt):
    """``_top_blocks``: every voxel lies in exactly one top block (with ``mirror``, every voxel of the
    rows ``j >= n_y // 2`` and none below), no block is wider than ``TOP`` or holds centres of both
    signs of ``y``, also where the middle row of a mirror grid lies below 0 by rounding (``tilt``)."""
    from paraspace.kinematics.interference_blocks import TOP, _top_blocks

    shape = (35, ny, 20)
    ys = np.arange(ny) - zero_at + 0.5  # the first centre with y >= 0 is row zero_at
    if mirror:
        ys = np.arange(ny) - 0.5 * (ny - 1) + tilt
    b0, bn = _top_blocks(shape, ys, mirror)
    assert (bn >= 1).all() and (bn <= TOP).all()
    seen = np.zeros(shape, np.int64)
    for (x, y, z), (a, b, c) in zip(b0, bn):
        seen[x:x + a, y:y + b, z:z + c] += 1
        assert (ys[y:y + b] >= 0.0).all() or (ys[y:y + b] < 0.0).all()
    want = np.ones(shape, np.int64)
    if mirror:
        want[:, :ny // 2] = 0
    assert np.array_equal(seen, want)


def test_blocks_decide_voxels_no_chain_reaches_as_the_screened_search():
    """The single voxels of the blocks skip the per-voxel search's whole-stroke screen (a shortcut that
    changes no answer): on a ``where`` that is the whole box, most of whose voxels some chain does not
    reach, the blocks give the screened per-voxel search's answer at every voxel."""
    design, joints, h = Design(), Joints(leg_diameter=10.0), 8.0
    plain = compute_workspace(design, WorkspaceSettings(voxel=h))
    xs, ys, zs = plain.grid.axes()
    where = np.ones(plain.grid.shape, bool)
    pts = np.stack(np.meshgrid(xs, ys, zs, indexing="ij"), axis=-1).reshape(-1, 3)
    old = interference_free(design, joints, pts, np.eye(3)[None], plain.n_eta)[:, 0].reshape(where.shape)
    new = interference_free_grid(design, joints, (xs, ys, zs), h, np.eye(3), plain.n_eta, where)
    assert np.array_equal(new, old)
    assert 0 < old.sum() < plain.occupancy.sum() < where.sum() // 2  # unreached voxels are most of the box


def test_the_spread_of_witnesses_is_the_first_combination_that_clears():
    """Step 3 of kinematics/interference.py where the first witnesses collide, against a plain reading
    of its definition: each chain's witnesses listed in the scan order (``_witnesses``), ``SPREAD`` of
    them picked evenly over the list, and the pose reachable when some combination of picks (chain 1's
    outermost, then 2's, then 3's) clears every pair of legs of different chains (segment distances
    here); the configuration ``clear_configuration`` reports is the first such combination's. The
    search answers False without the third chain's list where no pick of the first colliding pair of
    chains clears any pick of the other: poses of both kinds of False are among those checked."""
    import math

    from paraspace.kinematics.feasibility import ChainTables, chain_points
    from paraspace.kinematics.geometry import platform_points_local
    from paraspace.kinematics.interference import SPREAD, _witnesses, clear_configuration
    from paraspace.kinematics.joints import cone_table

    design, joints, h = Design(), Joints(leg_diameter=10.0), 4.0
    plain = compute_workspace(design, WorkspaceSettings(voxel=h))
    xs, ys, zs = plain.grid.axes()
    n = plain.n_eta
    tab = ChainTables(design, n)
    u = np.ascontiguousarray(platform_points_local(design))
    jc = np.ascontiguousarray(cone_table(design, joints, np.eye(3)))
    dmin = joints.min_distance
    skip = np.zeros((1, 3, n), np.bool_)

    def legs_clear(wi, bi, wj, bj):
        return all(segment_distance(*wi[3 * la:3 * la + 3], *bi[la], *wj[3 * lb:3 * lb + 3], *bj[lb]) >= dmin
                   for la in range(2) for lb in range(2))

    seen = {True: 0, False: 0}
    falses = {"no pick of the colliding pair clears": 0, "the third chain's picks collide": 0}
    rng = np.random.default_rng(5)
    idx = np.argwhere(plain.occupancy)
    for ix, iy, iz in idx[rng.permutation(len(idx))]:
        p = (xs[ix], ys[iy], zs[iz])
        wit = np.empty((3, n, 6))
        cnt, bs = [], []
        for i in range(3):
            pts = chain_points(*p, u, i)
            bs.append((pts[0:3], pts[3:6]))
            cnt.append(_witnesses(*pts, tab.cos_t, tab.sin_t, i, tab.hb, tab.rho_lo, tab.rho_hi, tab.lmin2, tab.lmax2,
                                  jc, dmin, n, wit, skip, 0, np.empty((4, 2)), p[1] < 0.0, 0, 0)[0])
        if min(cnt) == 0 or all(legs_clear(wit[i, 0], bs[i], wit[j, 0], bs[j]) for i, j in ((0, 1), (1, 2), (0, 2))):
            continue  # no witness, or the first witnesses clear: not the spread
        picks = [[0] if c == 1 else [int(round(q * (c - 1) / (min(SPREAD, c) - 1))) for q in range(min(SPREAD, c))]
                 for c in cnt]
        first = next(((a, b, c) for a in picks[0] for b in picks[1] for c in picks[2]
                      if legs_clear(wit[0, a], bs[0], wit[1, b], bs[1])
                      and legs_clear(wit[1, b], bs[1], wit[2, c], bs[2])
                      and legs_clear(wit[0, a], bs[0], wit[2, c], bs[2])), None)
        assert interference_free(design, joints, np.array([p]), np.eye(3)[None], n)[0, 0] == (first is not None)
        if first is None:
            a, b = next((i, j) for i, j in ((0, 1), (1, 2), (0, 2))
                        if not legs_clear(wit[i, 0], bs[i], wit[j, 0], bs[j]))
            some = any(legs_clear(wit[a, qa], bs[a], wit[b, qb], bs[b]) for qa in picks[a] for qb in picks[b])
            falses["the third chain's picks collide" if some else "no pick of the colliding pair clears"] += 1
        conf = clear_configuration(design, joints, p, np.eye(3), n)
        assert (conf is None) == (first is None)
        if first is not None:
            for i, q in enumerate(first):
                rho = math.hypot(*(0.5 * (wit[i, q, 0:2] + wit[i, q, 3:5])))
                assert conf[0][i] == pytest.approx(design.r - rho, abs=1e-9)
        seen[first is not None] += 1
        if min(seen.values()) >= 15 and sum(seen.values()) >= 60 and min(falses.values()) >= 3:
            break
    assert min(seen.values()) >= 15  # poses the spread clears and poses it does not
    assert min(falses.values()) >= 3, falses  # both ways of answering False


def test_box_count_counts_the_voxels_of_a_box():
    """``_box_count`` (the blocks' test for a block with no voxel to test, or with voxels left out)
    against numpy's count on random masks and boxes, the boxes touching every face of the grid."""
    from paraspace.kinematics.interference_blocks import _box_count

    rng = np.random.default_rng(11)
    for shape, p in (((17, 9, 23), 0.5), ((5, 31, 8), 0.05), ((12, 12, 12), 0.97)):
        mask = np.ascontiguousarray(rng.random(shape) < p)
        for _ in range(200):
            lo = [int(rng.integers(0, n)) for n in shape]
            size = [int(rng.integers(1, n - a + 1)) for a, n in zip(lo, shape)]
            want = int(mask[lo[0]:lo[0] + size[0], lo[1]:lo[1] + size[1], lo[2]:lo[2] + size[2]].sum())
            assert _box_count(mask, *lo, *size) == want
