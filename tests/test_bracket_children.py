"""The bracket's per-parent refinement (kinematics.bracket_children) against the per-child path it
replaces (``method="cubes"``: every child decided on its own by kinematics.blocks.decide_chain):
the same class, chains proven inside and sample windows for every child, level after level, and
the same bracket, on several designs, orientations and refinement levels."""

from __future__ import annotations

import math

import numpy as np
import pytest

from paraspace.kinematics.blocks import initial_windows
from paraspace.kinematics.bracket import (
    _CHILDREN,
    BOUNDARY,
    INSIDE,
    OUTSIDE,
    _arc,
    _rescale_windows,
    _subcube_kernel,
    cube_classes,
    volume_bracket,
)
from paraspace.kinematics.blocks import _segment_open, sub_arcs
from paraspace.kinematics.bracket_children import _limits2, _parent_flags, children_kernel, has_cones
from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.feasibility import ChainTables, chain_points, feasible_plain
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.kernel_args import kernel_args
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

CASES = [
    (Design(), (0.0, 0.0, 0.0), 0.0),
    (Design(a=10), (8.0, -5.0, 12.0), 0.0),
    (Design(eta_range="from-zero", l_s=80), (0.0, 0.0, 0.0), 20.0),
]


def _setup(design: Design, orientation: tuple[float, float, float], voxel: float):
    res = compute_workspace(design, WorkspaceSettings(voxel=voxel, orientation=orientation))
    args = kernel_args(design, orientation, res.n_eta)
    return res, args


@pytest.mark.parametrize("design, orientation, z_floor", CASES)
def test_every_child_as_the_per_child_kernel(design, orientation, z_floor):
    res, args = _setup(design, orientation, 8.0)
    grid, n_eta = res.grid, res.n_eta
    u, _, _, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc = args
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    bits = np.zeros(grid.shape, np.uint8)
    cls = cube_classes(design, grid, args, n_eta, z_floor, chain_bits=bits)
    centres = np.asarray(grid.origin, dtype=np.float64) + grid.h * np.argwhere(cls == BOUNDARY)
    pbits, pwin = bits[cls == BOUNDARY], initial_windows(centres.shape[0], n_eta)
    size, fine_before, levels = float(grid.h), 1, 3
    for level in range(levels):
        size *= 0.5
        fa = _arc(design, grid, args, n_eta, 0.5 * size * math.sqrt(3.0))
        pwin = _rescale_windows(pwin, fa.fine // fine_before, fa.cos_t.shape[1])
        fine_before = fa.fine
        kids = np.ascontiguousarray((centres[:, None, :] + size * _CHILDREN[None]).reshape(-1, 3))
        # the former path: each child on its own
        ref_bits = np.ascontiguousarray(np.repeat(pbits, 8))
        ref_win = np.ascontiguousarray(np.repeat(pwin, 8, axis=0))
        ref = np.empty(kids.shape[0], np.uint8)
        _subcube_kernel(kids, ref_bits, ref_win, size, fa.eps, fa.arc_slack, fa.cone_slack, z_floor, u, fa.cos_t,
                        fa.sin_t, arc, fa.seg_k, fa.seg_arc, hb, rho_lo, rho_hi, lmin, lmax, jc, ref)
        out = np.empty(kids.shape[0], np.uint8)
        kb = np.empty(kids.shape[0], np.uint8)
        kw = np.full((kids.shape[0], 3, 3), -7, np.int64)
        need_window = level < levels - 1
        children_kernel(np.ascontiguousarray(centres), pbits, np.ascontiguousarray(pwin), size, fa.eps, fa.arc_slack,
                        z_floor, u, fa.cos_t, fa.sin_t, arc, fa.seg_k, fa.seg_arc, hb, rho_lo, rho_hi,
                        lmin, lmax, _CHILDREN, need_window, out, kb, kw, np.zeros((0, 3)))
        assert {0, 1, 2} <= set(np.unique(ref).tolist())
        np.testing.assert_array_equal(out, ref)
        left = ref == BOUNDARY
        np.testing.assert_array_equal(kb[left], ref_bits[left])
        if need_window:  # the next level starts from them; the hint only orders the visit
            np.testing.assert_array_equal(kw[left][..., 1:], ref_win[left][..., 1:])
        else:  # the last level leaves the windows alone (the bracket passes an empty array there)
            assert (kw == -7).all()
        centres, pbits, pwin = kids[left], ref_bits[left], ref_win[left]


@pytest.mark.parametrize("n", [3, 7, 8, 9, 17, 61, 241])
def test_the_parent_flags_are_each_samples_own_tests(n):
    """The flag pass (runs of open sub-arcs widened to whole SIMD registers, so they reach past a
    window, or back from the stroke's end) against each sample's own three tests, one at a time
    with ``feasible_plain``: every sample of the window has exactly its tests' flags, or none where
    its sub-arc's bound rejects the chain; a sample outside the window is untouched or has its own
    flags too. Strokes of fewer samples than a register take the plain loop."""
    design = Design()
    res, args = _setup(design, (0.0, 0.0, 0.0), 8.0)
    u, _, _, _, hb, rho_lo, rho_hi, lmin2, lmax2, _ = args
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    tab = ChainTables(design, n)
    cos_t, sin_t = tab.cos_t, tab.sin_t
    seg_k, seg_arc = sub_arcs(cos_t, sin_t, 6)
    bits = np.zeros(res.grid.shape, np.uint8)
    cls = cube_classes(design, res.grid, args, res.n_eta, 0.0, chain_bits=bits)
    rng = np.random.default_rng(n)
    centres = np.asarray(res.grid.origin) + res.grid.h * np.argwhere(cls == BOUNDARY)
    centres = centres[rng.choice(centres.shape[0], 60, replace=False)] + rng.uniform(-2.0, 2.0, (60, 3))
    r1, r0, x = 3.0, 1.0, 0.5  # relaxations and tightening of the kernel's size, in units
    lims = [_limits2(lmin - r1, lmax + r1), _limits2(lmin - r0, lmax + r0), _limits2(lmin + x, lmax - x)]
    seen = {0: 0, 1: 0, 3: 0, 7: 0, "rejected": 0, "outside": 0}
    for c in centres:
        for i in range(3):
            klo, khi = sorted(rng.integers(0, n, 2).tolist())
            if rng.random() < 0.3:  # windows at the stroke's ends
                klo, khi = (0, min(khi, 5)) if rng.random() < 0.5 else (max(klo, n - 6), n - 1)
            flags = np.full((3, n), 99, np.uint8)
            _parent_flags(c[0], c[1], c[2], u, i, cos_t, sin_t, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax,
                          klo, khi, r1, r0, x, flags)
            b = chain_points(c[0], c[1], c[2], u, i)
            for k in range(n):
                tests = [lo2 <= hi2 and feasible_plain(*b, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi, lo2, hi2)
                         for lo2, hi2 in lims]
                own = int(tests[0]) | int(tests[0] and tests[1]) << 1 | int(tests[0] and tests[2]) << 2
                rejected = any(a <= k <= e and e - a >= 3 and not _segment_open(
                    *b, hb, seg_arc, i, g, rho_lo, rho_hi, max(lmin - r1, 0.0), lmax + r1)
                    for g, (a, e) in enumerate(seg_k))
                if klo <= k <= khi:
                    assert flags[i, k] == own or (flags[i, k] == 0 and rejected), (n, i, k, klo, khi)
                    seen[own] += 1
                    seen["rejected"] += int(rejected)
                else:
                    assert flags[i, k] in (99, own), (n, i, k, klo, khi)
                    seen["outside"] += int(flags[i, k] == own)
    if n >= 17:  # every kind of sample met
        assert min(seen.values()) > 0, seen


@pytest.mark.parametrize("design, orientation, z_floor", CASES)
def test_the_same_bracket_at_each_refinement(design, orientation, z_floor):
    res, args = _setup(design, orientation, 10.0)
    for refine in (1, 2, 3):
        new = volume_bracket(design, res.grid, args, res.n_eta, z_floor, refine=refine)
        old = volume_bracket(design, res.grid, args, res.n_eta, z_floor, refine=refine, method="cubes")
        assert new == old
        assert new.volume_inner < new.volume_outer


def test_joint_cones_take_the_per_child_path_and_a_bad_method_is_refused():
    joints = Joints(theta_u=60.0, theta_s=50.0)
    design = Design()
    res = compute_workspace(design, WorkspaceSettings(voxel=10.0, joints=joints))
    args = kernel_args(design, (0.0, 0.0, 0.0), res.n_eta, joints)
    assert has_cones(args[9]) and not has_cones(kernel_args(design, (0.0, 0.0, 0.0), res.n_eta)[9])
    a = volume_bracket(design, res.grid, args, res.n_eta, refine=1)
    assert a == volume_bracket(design, res.grid, args, res.n_eta, refine=1, method="cubes")
    with pytest.raises(ParameterError, match="method"):
        volume_bracket(design, res.grid, args, res.n_eta, refine=1, method="children")


@pytest.mark.parametrize("design, joints", [(Design(), Joints()), (Design(a=30.0), Joints(theta_u=45.0))])
def test_the_mirror_half_gives_an_equally_certified_bracket(design, joints):
    """``symmetric`` (module doc of kinematics.bracket, *Mirror*): the classes are mirror images of each
    other across y = 0 (chain bits 2 and 3 swapped), both refinement methods give the same bracket on
    the half, which holds the voxel estimate and overlaps the bracket with every cube classified (both
    enclose V; they differ only where the blocks' path differs, a block decided whole or cube by cube).
    A grid whose y centres are not exactly symmetric classifies every cube: the same as without."""
    from paraspace.kinematics.bracket import _half
    from paraspace.kinematics.grid import GridSpec

    res = compute_workspace(design, WorkspaceSettings(voxel=6.0, joints=joints))
    args = kernel_args(design, (0.0, 0.0, 0.0), res.n_eta, joints)
    grid = res.grid
    assert _half(grid, True) and grid.shape[1] % 2 == 0
    bits = np.zeros(grid.shape, np.uint8)
    cls = cube_classes(design, grid, args, res.n_eta, 0.0, chain_bits=bits, symmetric=True)
    np.testing.assert_array_equal(cls, cls[:, ::-1])
    swapped = (bits & 1) | ((bits & 2) << 1) | ((bits & 4) >> 1)
    np.testing.assert_array_equal(bits, swapped[:, ::-1])
    assert np.any((bits & 2) != ((bits & 4) >> 1))  # chains 2 and 3 differ somewhere: the swap is tested
    for refine in (1, 2):
        half = volume_bracket(design, grid, args, res.n_eta, refine=refine, symmetric=True)
        assert half == volume_bracket(design, grid, args, res.n_eta, refine=refine, method="cubes", symmetric=True)
        full = volume_bracket(design, grid, args, res.n_eta, refine=refine)
        assert half.volume_inner <= res.volume <= half.volume_outer
        assert max(half.volume_inner, full.volume_inner) <= min(half.volume_outer, full.volume_outer)
        assert abs(half.gap - full.gap) <= 0.02 * full.gap
    # an odd number of rows: the middle row (y = 0) is classified and refined once, its children counted once
    odd = GridSpec(origin=(grid.origin[0], grid.origin[1] - 0.5 * grid.h, grid.origin[2]), h=grid.h,
                   shape=(grid.shape[0], grid.shape[1] + 1, grid.shape[2]))
    assert _half(odd, True)
    half = volume_bracket(design, odd, args, res.n_eta, refine=1, symmetric=True)
    full = volume_bracket(design, odd, args, res.n_eta, refine=1)
    assert max(half.volume_inner, full.volume_inner) <= min(half.volume_outer, full.volume_outer)
    assert abs(half.gap - full.gap) <= 0.02 * full.gap
    # not exactly symmetric: every cube is classified
    off = GridSpec(origin=(grid.origin[0], grid.origin[1] + 1e-12, grid.origin[2]), h=grid.h, shape=grid.shape)
    assert not _half(off, True)
    assert volume_bracket(design, off, args, res.n_eta, refine=1, symmetric=True) == volume_bracket(
        design, off, args, res.n_eta, refine=1)


def _refine_in_numpy(design, grid, args, n_eta, z_floor, cls, bits, levels, half):
    """refine_boundary's bookkeeping written out in plain numpy (np.argwhere, np.repeat, masks, a
    weighted sum per class), each child decided on its own by the per-child kernel: the refinement
    as first written, before its bookkeeping was compiled (and the mirror half weighing 2)."""
    u, _, _, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc = args
    idx = np.argwhere(cls == BOUNDARY)
    weight = np.ones(idx.shape[0])
    if half:
        m = cls.shape[1] // 2
        idx = idx[idx[:, 1] < cls.shape[1] - m]
        weight = np.where(idx[:, 1] < m, 2.0, 1.0)
    centres = np.asarray(grid.origin, dtype=np.float64) + grid.h * idx
    pbits = bits[idx[:, 0], idx[:, 1], idx[:, 2]]
    pwin = initial_windows(centres.shape[0], n_eta)
    size, fine_before, inside, outside = float(grid.h), 1, 0.0, 0.0
    for _ in range(levels):
        size *= 0.5
        fa = _arc(design, grid, args, n_eta, 0.5 * size * math.sqrt(3.0))
        r, n = fa.fine // fine_before, fa.cos_t.shape[1]
        fine_before = fa.fine
        pwin = np.stack([pwin[..., 0] * r, np.maximum(pwin[..., 1] * r - r // 2, 0),
                         np.minimum(pwin[..., 2] * r + r // 2, n - 1)], axis=-1)
        kids = np.ascontiguousarray((centres[:, None, :] + size * _CHILDREN[None]).reshape(-1, 3))
        kb = np.ascontiguousarray(np.repeat(pbits, 8))
        kw = np.ascontiguousarray(np.repeat(pwin, 8, axis=0))
        kwt = np.repeat(weight, 8)
        out = np.empty(kids.shape[0], np.uint8)
        _subcube_kernel(kids, kb, kw, size, fa.eps, fa.arc_slack, fa.cone_slack, float(z_floor), u, fa.cos_t,
                        fa.sin_t, arc, fa.seg_k, fa.seg_arc, hb, rho_lo, rho_hi, math.sqrt(lmin2), math.sqrt(lmax2),
                        jc, out)
        inside += kwt[out == INSIDE].sum() * size ** 3
        outside += kwt[out == OUTSIDE].sum() * size ** 3
        keep = out == BOUNDARY
        centres, pbits, pwin, weight = kids[keep], kb[keep], kw[keep], kwt[keep]
    return inside, outside, round(weight.sum())


@pytest.mark.parametrize("design, orientation, z_floor, symmetric",
                         [(Design(), (0.0, 0.0, 0.0), 0.0, True)] + [(*c, False) for c in CASES])
def test_the_refinement_as_its_bookkeeping_in_plain_numpy(design, orientation, z_floor, symmetric):
    """refine_boundary (compiled bookkeeping: the boundary cubes listed, children counted by weight,
    boundary children kept) gives the same inner and outer volumes found and the same children left
    as the same steps in plain numpy, at 1 to 3 levels, with and without the mirror half."""
    from paraspace.kinematics.bracket import _half, refine_boundary

    res, args = _setup(design, orientation, 8.0)
    grid, n_eta = res.grid, res.n_eta
    bits = np.zeros(grid.shape, np.uint8)
    cls = cube_classes(design, grid, args, n_eta, z_floor, chain_bits=bits, symmetric=symmetric)
    assert _half(grid, symmetric) == symmetric
    for levels in (1, 2, 3):
        ref = _refine_in_numpy(design, grid, args, n_eta, z_floor, cls, bits, levels, symmetric)
        for method in ("parents", "cubes"):
            got = refine_boundary(design, grid, args, n_eta, z_floor, cls, bits, levels, method=method,
                                  symmetric=symmetric)
            assert got[2] == ref[2] and got[2] > 0
            assert got[0] == pytest.approx(ref[0], rel=1e-12) and got[1] == pytest.approx(ref[1], rel=1e-12)
            assert got[0] > 0 and got[1] > 0


@pytest.mark.parametrize("design, orientation, z_floor, symmetric",
                         [(Design(), (0.0, 0.0, 0.0), 0.0, True)] + [(*c, False) for c in CASES])
def test_cube_classes_by_parent_as_each_cube_alone(design, orientation, z_floor, symmetric):
    """cube_classes deciding the 8 cubes of each undecided 2 x 2 x 2 block together (the default)
    gives every cube the class and chain bits it gets on its own after its block is split (the path
    before), at two voxel sizes; more than 50 blocks of 8 cubes took the per-parent path."""
    from paraspace.kinematics import bracket as mod

    seen: list[int] = []
    real = mod._cubes_by_parent

    def spy(b0, bn, state, *rest):
        seen.append(int((np.all(bn == 2, axis=1) & np.any(state == 0, axis=1) & ~np.any(state == 2, axis=1)).sum()))
        return real(b0, bn, state, *rest)

    for voxel in (8.0, 5.0):
        res, args = _setup(design, orientation, voxel)
        grid, n_eta = res.grid, res.n_eta
        seen.clear()
        mod._cubes_by_parent = spy
        try:
            bits = np.zeros(grid.shape, np.uint8)
            cls = cube_classes(design, grid, args, n_eta, z_floor, chain_bits=bits, symmetric=symmetric)
        finally:
            mod._cubes_by_parent = real
        ref_bits = np.zeros(grid.shape, np.uint8)
        ref = cube_classes(design, grid, args, n_eta, z_floor, chain_bits=ref_bits, symmetric=symmetric,
                           per_parent=False)
        np.testing.assert_array_equal(cls, ref)
        np.testing.assert_array_equal(bits, ref_bits)
        assert {0, 1, 2} <= set(np.unique(cls).tolist())
        assert sum(seen) > 50  # blocks of 8 cubes took the per-parent path
