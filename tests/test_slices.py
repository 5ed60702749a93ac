"""kinematics.slices: the dealt order balances the threads' slices of a launch, the strided order
visits every item once and gives each slice an even sample of the range."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from paraspace.kinematics.slices import dealt_order, strided


@pytest.mark.parametrize("n, threads", [(0, 2), (1, 3), (7, 2), (8, 2), (13, 4), (64, 16), (150, 2), (5, 1)])
def test_dealt_order_is_a_padded_permutation_with_slices_within_one_item(n: int, threads: int) -> None:
    rng = np.random.default_rng(n * 31 + threads)
    for costs in (rng.random(n), np.arange(n, dtype=float), np.r_[np.zeros(n // 2), np.full(n - n // 2, 5.0)]):
        order = dealt_order(costs, threads)
        q = -(-n // threads)
        assert order.size == threads * q and order.dtype == np.int64
        assert sorted(order[order >= 0].tolist()) == list(range(n))
        slices = order.reshape(threads, q) if n else np.zeros((threads, 0), np.int64)
        for row in slices:  # pads only at the end of a slice
            assert not np.any(np.diff((row < 0).astype(int)) < 0)
        sums = np.array([costs[row[row >= 0]].sum() for row in slices])
        # dealt back and forth from the largest, two slices differ by at most the largest item
        assert sums.max() - sums.min() <= (costs.max() if n else 0.0) + 1e-9
    # a ramp (the dexterity field's planes at the edge of the workspace): the grid order's equal
    # slices are unbalanced, the dealt ones are not
    ramp = np.arange(16, dtype=float)
    grid = ramp.reshape(2, 8).sum(axis=1)
    dealt = [ramp[row].sum() for row in dealt_order(ramp, 2).reshape(2, 8)]
    assert grid[1] - grid[0] == 64.0 and dealt[0] == dealt[1]


@numba.njit
def _strided_all(n, threads):
    per = (n + threads - 1) // threads
    out = np.full(threads * per, -1, np.int64)
    for pos in range(threads * per):
        out[pos] = strided(pos, per, threads)
    return out, per


@pytest.mark.parametrize("n, threads", [(1, 1), (1, 4), (7, 2), (16, 2), (17, 4), (100, 16), (5, 8)])
def test_strided_order_visits_each_item_once_and_each_slice_samples_the_range(n: int, threads: int) -> None:
    items, per = _strided_all(n, threads)
    real = items[items < n]
    assert sorted(real.tolist()) == list(range(n))  # each item once, the rest past the end
    for t in range(threads):  # slice t (numba's static split) visits t, t + T, t + 2T, ...
        sl = items[t * per:(t + 1) * per]
        sl = sl[sl < n]
        assert np.array_equal(sl, np.arange(t, n, threads))
    # items whose cost sits in the first half: the strided slices share it, grid order does not
    if n >= 2 * threads and threads > 1:
        cost = (np.arange(n) < n // 2).astype(float)
        per_slice = [cost[s[s < n]].sum() for s in items.reshape(threads, per)]
        assert max(per_slice) - min(per_slice) <= 1.0
