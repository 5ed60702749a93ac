"""Components from runs along z (kinematics/run_components.py) against scipy's labelling: the same
number of components, the same multiset of sizes and the same union of chosen components, for 6 and
26 neighbours, on random fields and on odd shapes (empty, full, zero-size and one-voxel grids,
diagonal chains that only 26 neighbours join)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi

from paraspace.kinematics.run_components import RunComponents, count_components, grid_runs


def _scipy(occ, conn):
    lab, n = ndi.label(occ, structure=ndi.generate_binary_structure(3, conn))
    return lab, n, np.bincount(lab.ravel(), minlength=1)[1:]


def _check(occ, conn):
    lab, n, sizes = _scipy(occ, conn)
    rc = RunComponents(occ, conn)
    assert rc.count == n == count_components(occ, conn)
    assert np.array_equal(np.sort(rc.sizes), np.sort(sizes))
    if n:
        cut = int(np.median(sizes))
        assert np.array_equal(rc.mask(rc.sizes >= cut), np.concatenate([[False], sizes >= cut])[lab])
        assert np.array_equal(rc.mask(np.ones(n, bool)), occ)
    assert not rc.mask(np.zeros(n, bool)).any()


@pytest.mark.parametrize("conn", [1, 3])
def test_random_fields_equal_scipy_label(conn):
    rng = np.random.default_rng(7)
    for _ in range(150):
        occ = rng.random(tuple(rng.integers(1, 13, 3))) < rng.uniform(0.05, 0.95)
        _check(occ, conn)


@pytest.mark.parametrize("conn", [1, 3])
def test_odd_shapes_equal_scipy_label(conn):
    shapes = [np.zeros((0, 4, 5), bool), np.zeros((3, 0, 2), bool), np.ones((2, 3, 0), bool),
              np.zeros((1, 1, 1), bool), np.ones((1, 1, 1), bool), np.zeros((6, 7, 8), bool),
              np.ones((6, 7, 8), bool), np.ones((1, 1, 9), bool), np.ones((9, 1, 1), bool)]
    diag = np.zeros((6, 6, 6), bool)  # corner-to-corner chain: 1 piece for 26, 6 for 6
    diag[np.arange(6), np.arange(6), np.arange(6)] = True
    edge = np.zeros((5, 5, 5), bool)  # two voxels sharing an edge only, in the x-y plane and in x-z
    edge[1, 1, 2] = edge[2, 2, 2] = True
    edge[3, 0, 0] = edge[4, 0, 1] = True
    stripes = np.zeros((4, 5, 11), bool)  # columns of several runs, offset between neighbours
    stripes[:, :, ::2] = True
    stripes[1::2, :, :] = np.roll(stripes[1::2, :, :], 1, axis=2)
    for occ in shapes + [diag, edge, stripes, ~stripes]:
        _check(occ, conn)
    assert count_components(diag, 1) == 6 and count_components(diag, 3) == 1


def _scan(occ):
    """The runs of every column by a plain Python scan: ``(offs, rs, re)``."""
    offs, rs, re = [0], [], []
    for col in occ.reshape(-1, occ.shape[2]):
        k = 0
        while k < len(col):
            if col[k]:
                e = k
                while e + 1 < len(col) and col[e + 1]:
                    e += 1
                rs.append(k)
                re.append(e)
                k = e
            k += 1
        offs.append(len(rs))
    return np.array(offs), np.array(rs, dtype=np.int64), np.array(re, dtype=np.int64)


def test_grid_runs_equal_a_plain_scan():
    """The runs read eight bytes at a time where a column does not change (``_fill_runs_kernel``)
    and counted without branches equal a plain scan of each column, for column lengths around
    multiples of 8, sparse and dense fields, long runs, all-set and all-unset columns."""
    rng = np.random.default_rng(11)
    for nz in (1, 2, 7, 8, 9, 15, 16, 17, 23, 24, 25, 63, 64, 65, 130):
        for p in (0.02, 0.5, 0.97):
            occ = rng.random((3, 4, nz)) < p
            occ[0, 0] = True
            occ[0, 1] = False
            occ[1, 1, nz // 3:] = True  # one long run to the top
            got = grid_runs(occ)
            want = _scan(occ)
            for a, b in zip(got, want):
                assert np.array_equal(a, b), (nz, p)
    assert all(len(a) == 0 for a in grid_runs(np.zeros((2, 3, 0), bool))[1:])


def test_invalid_arguments():
    with pytest.raises(ValueError, match="connectivity"):
        RunComponents(np.ones((2, 2, 2), bool), 2)
    with pytest.raises(ValueError, match="dimensions"):
        RunComponents(np.ones((2, 2), bool))
