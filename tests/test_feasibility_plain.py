"""The per-sample reachability test (kinematics.feasibility): the test without joint cones that the
engine runs (feasible_plain, and the branch-free _passes of the bracket's parents) against the
interval sets of its definition (_feasible_sets), and _feasible_at choosing between them."""

from __future__ import annotations

import math

import numpy as np

from paraspace.kinematics.design import Design
from paraspace.kinematics.feasibility import (
    _feasible_at,
    _feasible_sets,
    _leg_intervals,
    _passes,
    cones_set,
    feasible_plain,
    sets_meet,
)
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.kernel_args import kernel_args


def test_branch_free_test_as_the_interval_test():
    """The branch-free test (feasibility._passes: the bracket's parents' SIMD loop) answers as the
    per-sample interval test (_leg_intervals + sets_meet), also at the exact edges of its cases."""

    rng = np.random.default_rng(7)
    lo2, hi2, rho_lo, rho_hi = 90.0 ** 2, 130.0 ** 2, -40.0, 0.0
    n = 40000
    p = rng.uniform(-200.0, 200.0, (n, 2))
    q = rng.uniform(0.0, 1.3 * hi2, (n, 2))
    q[::7, 0] = lo2  # the edges: one interval or two, empty or not
    q[::11, 1] = hi2
    q[::13, 0] = 0.0
    for k in range(n):
        p1, p2, q1, q2 = p[k, 0], p[k, 1], q[k, 0], q[k, 1]
        n1, a0, a1, a2, a3 = _leg_intervals(p1, q1, lo2, hi2)
        n2, c0, c1, c2, c3 = _leg_intervals(p2, q2, lo2, hi2)
        ref = n1 > 0 and n2 > 0 and sets_meet(n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, rho_lo, rho_hi)
        assert bool(_passes(p1, q1, p2, q2, lo2, hi2, rho_lo, rho_hi)) == ref, (p1, q1, p2, q2)


def test_the_test_with_early_exits_as_the_interval_sets():
    """The one-at-a-time test without joint cones (feasibility.feasible_plain: a leg too long at every
    rho, or the legs' outer intervals apart on the rail, answered before the full test; what
    _feasible_at and the engine's decide_chain run for such a chain, and the bracket's children)
    answers as the interval sets of the definition (feasibility._feasible_sets): random poses, and
    poses whose outer intervals touch exactly (one common rho), end at the rail's ends, or miss by a
    hair."""

    jc = kernel_args(Design(), (0.0, 0.0, 0.0), 11)[9][0]  # no joint cones
    hb, rho_lo, rho_hi = 12.0, -40.0, 60.0
    rng = np.random.default_rng(11)
    cases = []
    for _ in range(30000):
        b = rng.uniform(-150.0, 150.0, 6)
        th = rng.uniform(-1.0, 1.0)
        lo, hi = sorted(rng.uniform(0.0, 180.0, 2))
        cases.append((*b, math.cos(th), math.sin(th), lo * lo, hi * hi))
    # exact edges with c = 1, s = 0 and b_y = +-hb: p = b_x, q = b_z^2; q = 120^2, hi = 130: ro = 50
    for p1, gap in [(0.0, 100.0), (0.0, 100.0 + 1e-9), (-90.0, 100.0), (10.0, 100.0), (-140.0, 100.0),
                    (0.0, 0.0), (60.0, -100.0), (60.0, -100.0 - 1e-9)]:
        for lo2 in (0.0, 110.0 ** 2, 125.0 ** 2):
            cases.append((p1, hb, 120.0, p1 + gap, -hb, 120.0, 1.0, 0.0, lo2, 130.0 ** 2))
    cases.append((-90.0, hb, 131.0, 10.0, -hb, 120.0, 1.0, 0.0, 0.0, 130.0 ** 2))  # leg 1 too long
    answers = set()
    for b1x, b1y, b1z, b2x, b2y, b2z, c, s, lo2, hi2 in cases:
        ref = _feasible_sets(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo2, hi2, jc, 0.0)
        got = feasible_plain(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo2, hi2)
        assert bool(got) == bool(ref), (b1x, b1y, b1z, b2x, b2y, b2z, c, s, lo2, hi2)
        answers.add(bool(ref))
    assert answers == {True, False}
    # the touching pair passes (one common rho), the pair a hair apart does not
    assert feasible_plain(0.0, hb, 120.0, 100.0, -hb, 120.0, 1.0, 0.0, hb, rho_lo, rho_hi, 0.0, 130.0 ** 2)
    assert not feasible_plain(0.0, hb, 120.0, 100.0 + 1e-9, -hb, 120.0, 1.0, 0.0, hb, rho_lo, rho_hi, 0.0,
                              130.0 ** 2)


def test_feasible_at_is_the_interval_sets_with_and_without_cones():
    """_feasible_at answers as the interval sets on random poses, for a chain without joint cones
    (where it runs feasible_plain) and for one with them (where it runs the sets themselves), with
    both signs of the cones' relaxation, and with crossed limits (l_min > l_max: no pose passes);
    the cones change some answers (they are really applied)."""
    plain = kernel_args(Design(), (0.0, 0.0, 0.0), 11)[9][0]
    coned = kernel_args(Design(), (0.0, 0.0, 0.0), 11, Joints(theta_u=30.0, theta_s=30.0))[9][0]
    assert not cones_set(plain) and cones_set(coned)
    hb, rho_lo, rho_hi = 12.0, -40.0, 60.0
    rng = np.random.default_rng(5)
    changed = passed = 0
    for t in range(20000):
        b = rng.uniform(-150.0, 150.0, 6)
        th = rng.uniform(-1.0, 1.0)
        lo, hi = sorted(rng.uniform(0.0, 180.0, 2))
        if t % 10 == 0:
            lo, hi = hi, lo
        args = (*b, math.cos(th), math.sin(th), hb, rho_lo, rho_hi, lo * lo, hi * hi)
        for jc in (plain, coned):
            for cone_e in (0.0, 0.5, -0.5):
                assert _feasible_at(*args, jc, cone_e) == _feasible_sets(*args, jc, cone_e), (args, cone_e)
        passed += bool(_feasible_sets(*args, plain, 0.0))
        changed += _feasible_sets(*args, plain, 0.0) != _feasible_sets(*args, coned, 0.0)
    assert passed > 0 and changed > 0
