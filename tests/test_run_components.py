"""Components from runs along z (kinematics/run_components.py) against scipy's labelling: the same
number of components, the same multiset of sizes and the same union of chosen components, for 6 and
26 neighbours, on random fields and on odd shapes (empty, full, zero-size and one-voxel grids,
diagonal chains that only 26 neighbours join)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi

from paraspace.kinematics.run_components import RunComponents, count_components


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


def test_invalid_arguments():
    with pytest.raises(ValueError, match="connectivity"):
        RunComponents(np.ones((2, 2, 2), bool), 2)
    with pytest.raises(ValueError, match="dimensions"):
        RunComponents(np.ones((2, 2), bool))
