"""The summed-volume table (kinematics/summed_volume.py) against numpy's cumulative sums, and its box
counts against counting the box directly."""

from __future__ import annotations

import numpy as np
import pytest

from paraspace.kinematics.summed_volume import box_count, summed_volume


@pytest.mark.parametrize("shape", [(1, 1, 1), (2, 3, 4), (17, 1, 9), (31, 40, 23), (0, 4, 5)])
def test_table_is_the_cumulative_count_and_boxes_count_their_voxels(shape):
    rng = np.random.default_rng(sum(shape))
    for field in (rng.random(shape) < 0.4, (rng.random(shape) < 0.5).astype(np.float32),
                  rng.integers(-2, 3, shape).astype(np.int8)):
        table = summed_volume(field)
        ref = np.zeros(tuple(n + 1 for n in shape), np.int64)
        ref[1:, 1:, 1:] = (field != 0).astype(np.int64).cumsum(0).cumsum(1).cumsum(2)
        assert table.dtype == np.int32 and np.array_equal(table, ref)
        if not field.size:
            continue
        for _ in range(50):
            lo = [int(rng.integers(0, n + 1)) for n in shape]
            hi = [int(rng.integers(a, n + 1)) for a, n in zip(lo, shape)]
            box = field[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]]
            assert box_count(table, *lo, *hi) == np.count_nonzero(box)
            assert box_count.py_func(table, *lo, *hi) == np.count_nonzero(box)


def test_a_field_that_is_not_3d_is_refused():
    with pytest.raises(ValueError, match="field"):
        summed_volume(np.zeros((3, 3), bool))
