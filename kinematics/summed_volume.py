"""The summed-volume table of a voxel grid: counts of nonzero voxels in any box in eight look-ups.

Definition. For a grid ``f`` of shape ``(n0, n1, n2)``, the table ``S`` of shape ``(n0 + 1, n1 + 1,
n2 + 1)`` is

    S[i, j, k] = #{(a, b, c) : a < i, b < j, c < k, f[a, b, c] != 0}

(zero on its three lower faces), and the number of nonzero voxels in the box ``[x0, x1) x [y0, y1)
x [z0, z1)`` is the inclusion-exclusion of its eight corners (:func:`box_count`). The table is
built in two parallel passes (:func:`_summed_volume_kernel`): running sums along ``k`` and ``j``
within each ``x`` slice, then along ``x`` for each ``j``. Its integers are int32 where every count
fits (fewer than 2^31 voxels) and int64 otherwise.

Used by the blocks that skip empty boxes (:mod:`kinematics.interference_blocks`,
:mod:`kinematics.orientation_blocks`) and by the display shell's block means
(:mod:`kinematics.shell`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .parallel import KERNEL_LOCK

__all__ = ["summed_volume", "box_count"]


def summed_volume(field: np.ndarray) -> np.ndarray:
    """The table ``S`` of the module docstring for the 3-D array ``field`` (nonzero counts)."""
    f = np.ascontiguousarray(field)
    if f.ndim != 3:
        raise ValueError(f"field of shape {f.shape} is invalid: valid values a 3-D array")
    dtype = np.int32 if f.size < 2 ** 31 else np.int64
    s = np.zeros(tuple(n + 1 for n in f.shape), dtype)
    if f.size:
        with KERNEL_LOCK:
            _summed_volume_kernel(f, s)
    return s


@njit(parallel=True, cache=True, nogil=True)
def _summed_volume_kernel(field, s):
    """``s`` (zeros on entry) becomes the table of ``field`` (module docstring): 2-D sums per x slice
    in parallel, then the running sum along x in parallel over ``j``."""
    n0, n1, n2 = field.shape
    for i in prange(n0):
        for j in range(n1):
            run = 0
            for k in range(n2):
                if field[i, j, k] != 0:
                    run += 1
                s[i + 1, j + 1, k + 1] = s[i + 1, j, k + 1] + run
    for j in prange(n1 + 1):
        for i in range(n0):
            for k in range(n2 + 1):
                s[i + 1, j, k] += s[i, j, k]


@njit(cache=True, forceinline=True)
def box_count(s, x0, y0, z0, x1, y1, z1):
    """Nonzero voxels of the box ``[x0, x1) x [y0, y1) x [z0, z1)`` from its table ``s``."""
    return (s[x1, y1, z1] - s[x0, y1, z1] - s[x1, y0, z1] - s[x1, y1, z0]
            + s[x0, y0, z1] + s[x0, y1, z0] + s[x1, y0, z0] - s[x0, y0, z0])
