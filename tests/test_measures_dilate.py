"""Issue 24 target 1: the feature filter's dilation kernels against scipy.ndimage.

``ball_dilate`` (the grid packed 64 voxels to a word along z, mirrored half) and ``feature_filter`` (its
four dilations) are compared with ``scipy.ndimage``'s binary erosion and dilation by the digital
Euclidean ball ``{d in Z^3 : |d|^2 <= r^2}`` on random grids of odd and even sizes, empty and full
grids, mirror-symmetric grids and real workspaces at coarse voxels."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi

from paraspace.kinematics.design import Design
from paraspace.kinematics.morphology import ball_dilate, ball_dilate_reference, feature_filter, is_mirror_symmetric
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


def ball_structure(rv: float) -> np.ndarray:
    w = int(np.floor(rv + 1e-9))
    d = np.arange(-w, w + 1)
    x, y, z = np.meshgrid(d, d, d, indexing="ij")
    return x * x + y * y + z * z <= rv * rv + 1e-9


def scipy_dilate(m: np.ndarray, rv: float) -> np.ndarray:
    return ndi.binary_dilation(m, structure=ball_structure(rv))  # outside the array: not in m


def scipy_erode(m: np.ndarray, rv: float) -> np.ndarray:
    return ndi.binary_erosion(m, structure=ball_structure(rv), border_value=1)  # outside: in m


def scipy_feature_filter(occ: np.ndarray, rv: float) -> np.ndarray:
    w = int(np.floor(rv + 1e-9))
    if w <= 0:
        return occ.copy()
    p = w + 1
    o = np.pad(occ, p)
    closed = scipy_erode(scipy_dilate(scipy_dilate(scipy_erode(o, rv), rv), rv), rv)
    return closed[p:-p, p:-p, p:-p]


def grids() -> list[np.ndarray]:
    rng = np.random.default_rng(2024)
    out = [np.zeros((9, 8, 7), bool), np.ones((9, 8, 7), bool), np.zeros((1, 1, 1), bool), np.ones((3, 1, 5), bool)]
    for shape in ((17, 13, 11), (16, 15, 21), (5, 23, 9), (2, 3, 29)):
        for p in (0.05, 0.5, 0.93):
            m = rng.random(shape) < p
            out += [m, m | m[:, ::-1]]
    for design in (Design(), Design(a=10)):
        occ = compute_workspace(design, WorkspaceSettings(voxel=8.0)).occupancy
        out += [occ, occ[:, :-1]]  # the real (symmetric) grid and an odd cut of it
    return out


GRIDS = grids()


@pytest.mark.parametrize("rv", [0.9, 1.0, 1.5, 2.3, 3.7])
def test_ball_dilate_equals_scipy(rv):
    for m in GRIDS:
        sym = bool(np.array_equal(m, m[:, ::-1]))
        ref = scipy_dilate(m, rv) if rv >= 1 else m
        assert np.array_equal(ball_dilate(m, rv, symmetric=sym), ref), m.shape
        assert np.array_equal(ball_dilate(m, rv), ref), m.shape
        assert np.array_equal(ball_dilate_reference(m, rv), ref), m.shape
        ref_e = scipy_erode(m, rv) if rv >= 1 else m
        assert np.array_equal(ball_dilate(m, rv, complement=True, symmetric=sym), ref_e), m.shape


@pytest.mark.parametrize("rv", [1.0, 1.8, 3.2])
def test_feature_filter_equals_scipy_open_close(rv):
    changed = 0
    for m in GRIDS:
        got = feature_filter(m, rv)
        assert np.array_equal(got, scipy_feature_filter(m, rv)), m.shape
        changed += int((got != m).sum())
    assert changed > 0  # the filter did something on these grids


@pytest.mark.parametrize("rv", [2.3, 7.1])
def test_packed_rows_across_words_equal_scipy(rv):
    # ball_dilate packs 64 voxels to a word along z: rows just under, at and over one and two words,
    # with runs long enough to carry bits from one word to the next, against scipy
    rng = np.random.default_rng(64)
    for shape in ((6, 7, 63), (5, 6, 64), (7, 5, 65), (4, 9, 128), (5, 4, 130)):
        for p in (0.03, 0.5, 0.95):
            for m in (rng.random(shape) < p, (rng.random(shape) < p) | (rng.random(shape) < p)[:, ::-1]):
                sym = bool(np.array_equal(m, m[:, ::-1]))
                assert np.array_equal(ball_dilate(m, rv, symmetric=sym), scipy_dilate(m, rv)), (shape, p)
                eroded = ball_dilate(m, rv, complement=True, symmetric=sym)
                assert np.array_equal(eroded, scipy_erode(m, rv)), (shape, p)
    m = rng.random((9, 10, 70)) < 0.6
    assert np.array_equal(feature_filter(m, rv), scipy_feature_filter(m, rv))


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_the_dilation_does_not_depend_on_its_slabs(threads):
    """The dilation deals the x planes in slabs (two per thread) that build their own z dilations of
    the planes they read, ``w`` on either side: with 1, 2 and 3 threads (at most the machine's), on
    grids of fewer x planes than slabs and with a ball wider than a slab (every slab's halo reaching
    past the grid), the same voxels as scipy."""
    import numba

    rng = np.random.default_rng(threads)
    before = numba.get_num_threads()
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    try:
        for shape, rv in (((1, 9, 70), 2.3), ((3, 8, 65), 4.5), ((5, 11, 40), 6.2), ((13, 12, 130), 3.0)):
            for q in (0.05, 0.5):
                m = rng.random(shape) < q
                for g in (m, m | m[:, ::-1]):
                    sym = bool(np.array_equal(g, g[:, ::-1]))
                    assert np.array_equal(ball_dilate(g, rv, symmetric=sym), scipy_dilate(g, rv)), (shape, q)
                    assert np.array_equal(ball_dilate(g, rv, complement=True, symmetric=sym),
                                          scipy_erode(g, rv)), (shape, q)
    finally:
        numba.set_num_threads(before)


@pytest.mark.parametrize("rv", [1.4, 5.2])
def test_feature_filter_padded_across_words_equals_scipy(rv):
    # the filter pads the grid by floor(r) + 1 inside its pack pass: padded rows just under, at and
    # over one and two words, symmetric and not, against scipy on np.pad's grid
    rng = np.random.default_rng(7)
    p = int(np.floor(rv + 1e-9)) + 1
    for nz in (64 - 2 * p - 1, 64 - 2 * p, 64 - 2 * p + 1, 128 - 2 * p, 128 - 2 * p + 3):
        for q in (0.4, 0.8):
            m = rng.random((8, 9, nz)) < q
            for g in (m, m | m[:, ::-1]):
                assert np.array_equal(feature_filter(g, rv), scipy_feature_filter(g, rv)), (nz, q)


@pytest.mark.parametrize("rv", [1.4, 5.2])
def test_feature_filter_packed_from_runs_equals_the_grid(rv):
    """The filter packed from the set's runs (a word's range of bits per run: runs that start or end
    on a word's edge, span several words, fill a whole row, one voxel long) gives the words and the
    set that packing the grid gives, symmetric and not."""
    from paraspace.kinematics import morphology
    from paraspace.kinematics.run_components import RunComponents

    rng = np.random.default_rng(11)
    p = int(np.floor(rv + 1e-9)) + 1
    for nz in (1, 64 - 2 * p - 1, 64 - 2 * p, 64 - 2 * p + 1, 128 - 2 * p + 3, 200):
        for q in (0.1, 0.5, 0.95):
            m = rng.random((6, 7, nz)) < q
            m[0, 0, :] = True  # a run the length of the row
            for g in (m, m | m[:, ::-1]):
                runs = RunComponents(g).runs
                from_grid = morphology._Packed(g, rv, None, p)
                from_runs = morphology._Packed(g, rv, None, p, runs=runs)
                assert np.array_equal(from_grid.P, from_runs.P), (nz, q)
                assert from_grid.symmetric == from_runs.symmetric
                assert np.array_equal(feature_filter(g, rv, runs=runs), scipy_feature_filter(g, rv)), (nz, q)


def _runs_by_definition(g: np.ndarray) -> list[list[tuple[int, int]]]:
    """Each column's runs ``(first z, last z)``, column by column, by a plain Python scan."""
    out = []
    for i in range(g.shape[0]):
        for j in range(g.shape[1]):
            col, runs, k = g[i, j], [], 0
            while k < len(col):
                if col[k]:
                    a = k
                    while k + 1 < len(col) and col[k + 1]:
                        k += 1
                    runs.append((a, k))
                k += 1
            out.append(runs)
    return out


def _as_columns(runs) -> list[list[tuple[int, int]]]:
    offs, rs, re = runs
    return [[(int(rs[q]), int(re[q])) for q in range(offs[c], offs[c + 1])] for c in range(len(offs) - 1)]


@pytest.mark.parametrize("rv", [0.5, 1.4, 5.2])
def test_filtered_runs_read_from_the_packed_words_equal_the_grids(rv):
    """The filtered set's runs read from the packed words (``as_runs``: a run's start is a set bit over
    a clear one, its end one under a clear one, across word edges; the padding's bits dropped), and
    the reference's from its grid, are the runs of the filtered grid by a plain scan; the components
    built from them equal those of the grid."""
    from paraspace.kinematics.morphology import feature_filter_reference
    from paraspace.kinematics.run_components import RunComponents

    rng = np.random.default_rng(13)
    p = int(np.floor(rv + 1e-9)) + 1
    for nz in (1, 2, 64 - 2 * p - 1, 64 - 2 * p, 64 - 2 * p + 1, 64, 128 - 2 * p + 3, 130):
        for q in (0.3, 0.7, 0.97):
            m = rng.random((6, 7, nz)) < q
            m[0, 0, :] = True  # a run the length of the row
            m[1, 1, :] = False
            for g in (m, m | m[:, ::-1]):
                runs = RunComponents(g).runs
                grid = feature_filter(g, rv, runs=runs)
                want = _runs_by_definition(grid)
                for got in (feature_filter(g, rv, runs=runs, as_runs=True), feature_filter(g, rv, as_runs=True),
                            feature_filter_reference(g, rv, as_runs=True)):
                    assert _as_columns(got) == want, (nz, q)
                comps = RunComponents.of_runs(feature_filter(g, rv, as_runs=True), g.shape)
                ref = RunComponents(grid)
                assert comps.count == ref.count and sorted(comps.sizes) == sorted(ref.sizes)
                assert comps.euler_characteristic() == ref.euler_characteristic()


def test_mirror_test_equals_array_equal():
    rng = np.random.default_rng(3)
    for shape in ((5, 1, 3), (6, 2, 4), (7, 9, 5), (4, 10, 66)):
        m = rng.random(shape) < 0.5
        s = m | m[:, ::-1]
        assert is_mirror_symmetric(s) and np.array_equal(s, s[:, ::-1])
        assert is_mirror_symmetric(m) == np.array_equal(m, m[:, ::-1])
        if shape[1] > 1:
            t = s.copy()
            t[shape[0] - 1, 0, shape[2] - 1] ^= True  # one voxel off the mirror, in the last slice
            assert not is_mirror_symmetric(t)
    assert is_mirror_symmetric(np.zeros((0, 3, 3), bool))
