"""Dexterity field with the resolver's exact carriage poses: the bounded full search at every
reachable voxel, and ``1/kappa`` computed in the same compiled pass.

Definition
----------
:mod:`kinematics.dexterity` defines the resolved carriage pose of chain ``i`` at a position ``P``
as the result of the resolver's **full search** over ``(eta, rho)`` for the largest chain margin
``m(P; eta, rho) = min_j min(l_j - l_min, l_max - l_j)``: the first maximiser (in scan order) over a
73 x 61 grid on the strokes, then over two 21 x 21 grids ("zooms") each centred on the previous
maximiser; about 5,300 margins per chain and voxel. This field finds the **same** maximisers (bit
for bit) by the bounded search of :mod:`kinematics.carriage_search` (the margin at each block's
centre bounds its block's points; about a fifth of the margins). (Until issue 24's last round it
pruned each grid with the margins found at the voxel before it, by the margin's 1-Lipschitz bound
in the platform position; at ``h = 2`` that took 20 s, the bounded search about 7 s.)

``1/kappa = sigma_min(J) / sigma_max(J)`` of ``J = J_h^{-1} J_q`` (eq. (26)) is computed in the same
kernel without forming ``J``. ``J_q = [I | a | b]`` (a leg's rate, and the rail and arc columns,
nonzero only on the two rows of the chain they move), so ``M = J_q J_q^T`` is block diagonal with a
2 x 2 block per chain, ``M = L L^T`` (Cholesky, block by block) and ``J J^T = J_h^{-1} L L^T
J_h^{-T}``: the singular values of ``J`` are those of ``J_h^{-1} L``, the inverses of those of
``Q = L^{-1} J_h``, so ``kappa(J) = kappa(Q)`` and ``1/kappa = sqrt(lambda_min / lambda_max)`` of
the 6 x 6 ``G = Q^T Q``. Only its two extreme eigenvalues are needed: a Householder reduction to
tridiagonal form ``T``, then Laguerre's iteration on ``det(x I - T)`` from outside the spectrum at
each end (:func:`_tridiagonal_eigen_range`; about 3.7 steps each, where the former implicit QL of
all six took about half the time of the whole ``1/kappa``). They are accurate to about ``1e-16
lambda_max``, i.e. ``1/kappa`` to about ``1e-16 kappa`` absolute (at most ``0.85 x 2.2e-16 kappa``
measured at every voxel of the default design at h = 2; 0.9 with QL), so where ``1/kappa <
3.2e-4`` (``lambda_min < JACOBI_BELOW lambda_max``; about 6 % of the default design's voxels) the
eigenvalues are taken again by cyclic Jacobi rotations, accurate relative to each eigenvalue on this
positive definite ``G``. 0 where ``G`` is singular. (The whole was about 1.7 times faster than the
former Gauss-Jordan elimination of ``[J_h | J_q]`` and Jacobi rotations on ``J J^T`` at every voxel
with QL, before Laguerre.)

**Tolerance** (checked by the tests against the full search, the slow path
``dexterity_field(..., search="full")``): the carriage poses are identical to the full search's,
and ``|1/kappa - 1/kappa_full| <= TOL_REL x 1/kappa_full + TOL_ABS`` (:data:`TOL_REL` = 1e-9,
:data:`TOL_ABS` = 1e-12: the eigenvalues of ``J J^T`` against numpy's SVD of ``J``, both accurate to
about ``kappa x 1e-16`` absolute) at every voxel.

Cost: see ``benchmarks/bench_workspace.py --throughput`` (target 3). The Jacobian's constants are
defined here and shared with :mod:`kinematics.dexterity` (which imports this module, not the other
way round); the chain margin with its search is :mod:`kinematics.carriage_search`'s.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence

import numba
import numpy as np
from numba import njit, prange

from .carriage_search import best_carriage, work_arrays
from .design import Design
from .geometry import LEG_SIGN, platform_points_local
from .parallel import dealt_launch, kernel_launch
from .progress import CancelToken, Reporter, check
from .rotation import euler_rate_matrix, euler_zyx_deg

#: x planes per thread of a kernel launch (cancellation and progress are checked between launches).
PLANES = 4
#: A plane's first voxel's cost in reachable voxels' (:func:`plane_costs`: the full search of three
#: chains, about 65 us, against about 2.7 us a voxel on one core at h = 2).
FIRST_VOXEL_COST = 25.0
#: Stated tolerance on 1/kappa against the full search's: relative and absolute (module docstring).
TOL_REL, TOL_ABS = 1e-9, 1e-12
#: ``1/kappa^2`` below which :func:`_inverse_condition` takes the Jacobi eigenvalues instead of the
#: tridiagonal ones (about 6 % of the voxels of the default design: ``1/kappa < 3.2e-4``).
JACOBI_BELOW = 1e-7


def _constants(design: Design, orientation_deg: Sequence[float]):
    psi, theta, phi = (float(v) for v in orientation_deg)
    rot = euler_zyx_deg(psi, theta, phi)
    u = np.ascontiguousarray(platform_points_local(design) @ rot.T)
    R2 = np.ascontiguousarray(euler_rate_matrix(math.radians(psi), math.radians(theta)))
    return u, R2, 0.5 * design.b * LEG_SIGN[0], 1.0 / design.characteristic_length


@njit(cache=True, forceinline=True)
def _laguerre_step(A, x):
    """Laguerre's step at ``x`` for ``p(x) = det(x I - T)`` of the tridiagonal ``T`` (diagonal
    ``A[:, 8]``, off-diagonal ``A[:5, 9]``): with ``g = p'/p = sum 1/(x - lambda)`` and ``h = sum
    1/(x - lambda)^2`` from the pivots ``q_i`` of ``T - x I = L D L^T`` and their derivatives in ``x``
    (``q_0 = d_0 - x``, ``q_i = d_i - x - e_{i-1}^2 / q_{i-1}``; ``g = sum q_i'/q_i``, ``h = sum
    (q_i'/q_i)^2 - q_i''/q_i``), the step ``-6 / (g + sign(g) sqrt(5 (6 h - g^2)))``."""
    # a pivot 0 makes x an eigenvalue of a leading block of T - x I; outside the spectrum (where
    # the iterates start and, but for rounding, stay) every pivot has the same sign, so x is then an
    # eigenvalue to rounding: the step is 0
    q = A[0, 8] - x
    if q == 0.0:
        return 0.0
    qp = -1.0
    qpp = 0.0
    r = 1.0 / q
    t = qp * r
    g = t
    h = t * t - qpp * r
    for i in range(1, 6):
        e2 = A[i - 1, 9] * A[i - 1, 9]
        # r = 1/q_{i-1}, t = q'_{i-1}/q_{i-1}
        qpp = e2 * r * (qpp * r - 2.0 * t * t)
        qp = -1.0 + e2 * t * r
        q = A[i, 8] - x - e2 * r
        if q == 0.0:
            return 0.0
        r = 1.0 / q
        t = qp * r
        g += t
        h += t * t - qpp * r
    root = math.sqrt(max(5.0 * (6.0 * h - g * g), 0.0))
    den = g + root if g >= 0.0 else g - root
    return -6.0 / den if den != 0.0 else 0.0


@njit(cache=True, forceinline=True)
def _tridiagonal_eigen_range(G, A):
    """``(lo, hi, ok)``: the smallest and largest eigenvalue of the symmetric positive semidefinite
    6 x 6 ``G`` (overwritten) by a Householder reduction to tridiagonal form ``T`` (EISPACK
    ``tred1``) and Laguerre's iteration on ``det(x I - T)`` (:func:`_laguerre_step`), from below
    all eigenvalues (``x = -1e-12 B``, ``B`` Gershgorin's bound: ``T`` is similar to ``G`` plus
    about ``1e-15 |G|``, so its eigenvalues are above that) for the smallest, and from above
    ``min(B, |T|_F)`` for the largest. On a polynomial with real roots Laguerre's iterates from
    outside the roots move monotonically to the nearest one, cubically near a simple root; each is
    stopped once its step is below ``2 eps B`` (the accuracy of the reduction). ``ok`` False where either did
    not stop in 40 steps. ``A[:, 8]`` and ``A[:, 9]`` hold the diagonal and the off-diagonal."""
    n = 6
    for i in range(n - 1, 0, -1):
        lm = i - 1
        h = 0.0
        if lm > 0:
            scale = 0.0
            for k in range(lm + 1):
                scale += abs(G[i, k])
            if scale == 0.0:
                A[i, 9] = G[i, lm]
            else:
                for k in range(lm + 1):
                    G[i, k] /= scale
                    h += G[i, k] * G[i, k]
                f = G[i, lm]
                g = -math.sqrt(h) if f >= 0.0 else math.sqrt(h)
                A[i, 9] = scale * g
                h -= f * g
                G[i, lm] = f - g
                f = 0.0
                for j in range(lm + 1):
                    g = 0.0
                    for k in range(j + 1):
                        g += G[j, k] * G[i, k]
                    for k in range(j + 1, lm + 1):
                        g += G[k, j] * G[i, k]
                    A[j, 9] = g / h
                    f += A[j, 9] * G[i, j]
                hh = f / (h + h)
                for j in range(lm + 1):
                    f = G[i, j]
                    g = A[j, 9] - hh * f
                    A[j, 9] = g
                    for k in range(j + 1):
                        G[j, k] -= f * A[k, 9] + g * G[i, k]
        else:
            A[i, 9] = G[i, lm]
    for i in range(n):
        A[i, 8] = G[i, i]
    # A[i, 9] is the coupling of rows i - 1 and i: shift it to i - 1
    for i in range(1, n):
        A[i - 1, 9] = A[i, 9]
    A[n - 1, 9] = 0.0
    bound = 0.0
    frob = 0.0
    for i in range(n):
        off = abs(A[i, 9]) + (abs(A[i - 1, 9]) if i > 0 else 0.0)
        bound = max(bound, abs(A[i, 8]) + off)
        frob += A[i, 8] * A[i, 8] + 2.0 * A[i, 9] * A[i, 9]
    if not (bound > 0.0) or not math.isfinite(bound):
        return 0.0, 0.0, False
    tol = 2.220446049250313e-16 * 2.0 * bound
    hi = min(bound, math.sqrt(frob)) * (1.0 + 1e-12)
    lo = -1e-12 * bound
    done_hi = False
    done_lo = False
    for _it in range(40):
        if not done_hi:
            s = _laguerre_step(A, hi)
            hi += s
            done_hi = not (abs(s) > tol)
        if not done_lo:
            s = _laguerre_step(A, lo)
            lo += s
            done_lo = not (abs(s) > tol)
        if done_hi and done_lo:
            break
    if not (done_hi and done_lo and math.isfinite(lo) and math.isfinite(hi)):
        return 0.0, 0.0, False
    return lo, hi, True


@njit(cache=True, forceinline=True)
def plane_index(occ, i, ny, first):
    """The index of each reachable voxel ``(i, j, k)``, ``j < ny``, of plane ``i`` of ``occ`` in the C
    order of the reachable voxels (``first``: that of the plane's first one); (ny, nz) array."""
    index = np.empty((ny, occ.shape[2]), np.int64)
    n = first
    for j in range(ny):
        for k in range(occ.shape[2]):
            if occ[i, j, k]:
                index[j, k] = n
                n += 1
    return index


@njit(cache=True, forceinline=True)
def _gram(A, G):
    """``G = Q^T Q`` of the 6 x 6 ``Q`` in ``A[:, :6]``."""
    for a in range(6):
        for b in range(a, 6):
            acc = 0.0
            for k in range(6):
                acc += A[k, a] * A[k, b]
            G[a, b] = acc
            G[b, a] = acc


@njit(cache=True, forceinline=True)
def _carriage_trig(eta, CSV):
    """``CSV[i] = (cos, sin)`` of chain ``i``'s carriage angle ``varpi_i = 2 pi i / 3 + eta_i``, as
    :func:`_inverse_condition` takes them."""
    for i in range(3):
        varpi = 2.0 * math.pi * i / 3.0 + eta[i]
        CSV[i, 0], CSV[i, 1] = math.cos(varpi), math.sin(varpi)


@njit(cache=True, forceinline=True)
def _inverse_condition(px, py, pz, u, R2, rho, CSV, hb, inv_L, A, G):
    """``1/kappa`` of ``J_h^{-1} J_q`` at one position and carriage pose (module docstring; the
    matrices of :func:`kinematics.dexterity._assemble_kernel`), the carriage angles given by their
    cosines and sines ``CSV`` (3, 2; :func:`_carriage_trig`, or the neighbour search's climb's own,
    which saves three sines and cosines a voxel). Work arrays: ``A`` (6, 18) (columns
    0-5 ``J_h`` then ``Q``, 6-7 the rail and arc entries of ``J_q``, 8-9 the tridiagonal form), ``G``
    (6, 6). Inlined into the kernels (once per voxel; numba takes two atomic reference counts per
    array argument of a call whose body loops): with :func:`kinematics.dexterity_neighbour.
    _coarse_best_bounded` inlined too, the neighbour field at h = 2 takes 0.91-0.94 of its time, for
    about 10 s more of the dexterity kernels' one cold compile (14 -> 24 s)."""
    # J = J_h^{-1} J_q with J_q = [I | a | b] (a, b: the rail and arc columns, nonzero only on a
    # chain's own two rows), so J J^T = J_h^{-1} M J_h^{-T} with M = J_q J_q^T block diagonal (2 x 2
    # per chain) = L L^T (Cholesky). J's singular values are those of J_h^{-1} L, the inverses of
    # those of Q = L^{-1} J_h: kappa(J) = kappa(Q), from the eigenvalues of G = Q^T Q (6 x 6).
    for i in range(3):
        c, s = CSV[i, 0], CSV[i, 1]
        for j in range(2):
            row = 2 * i + j
            lat = hb if j == 0 else -hb
            ux, uy, uz = u[i, j, 0], u[i, j, 1], u[i, j, 2]
            vx = px + ux - (c * rho[i] - s * lat)
            vy = py + uy - (s * rho[i] + c * lat)
            vz = pz + uz
            inv_n = 1.0 / math.sqrt(vx * vx + vy * vy + vz * vz)
            sx, sy, sz = vx * inv_n, vy * inv_n, vz * inv_n
            cx = uy * sz - uz * sy
            cy = uz * sx - ux * sz
            cz = ux * sy - uy * sx
            A[row, 0] = sx
            A[row, 1] = sy
            A[row, 2] = sz
            for k in range(3):
                A[row, 3 + k] = (cx * R2[0, k] + cy * R2[1, k] + cz * R2[2, k]) * inv_L
            A[row, 6] = -(sx * c + sy * s)
            A[row, 7] = sx * (-rho[i] * s - lat * c) + sy * (rho[i] * c - lat * s)
        r0, r1 = 2 * i, 2 * i + 1
        m00 = 1.0 + A[r0, 6] * A[r0, 6] + A[r0, 7] * A[r0, 7]
        m10 = A[r0, 6] * A[r1, 6] + A[r0, 7] * A[r1, 7]
        m11 = 1.0 + A[r1, 6] * A[r1, 6] + A[r1, 7] * A[r1, 7]
        l00 = math.sqrt(m00)
        l10 = m10 / l00
        l11 = math.sqrt(m11 - l10 * l10)
        i00, i11 = 1.0 / l00, 1.0 / l11
        for k in range(6):
            A[r0, k] *= i00
            A[r1, k] = (A[r1, k] - l10 * A[r0, k]) * i11
    _gram(A, G)
    # the eigenvalues of the tridiagonal form lose about eps kappa(G) of the largest, i.e. ~eps kappa in
    # 1/kappa (at most 0.9 eps kappa measured): where 1/kappa^2 < JACOBI_BELOW the Jacobi rotations
    # (relative accuracy on this positive definite G) keep 1/kappa within TOL_REL and TOL_ABS
    lo, hi, ok = _tridiagonal_eigen_range(G, A)
    if ok and hi > 0.0 and lo > JACOBI_BELOW * hi:
        return math.sqrt(lo / hi)
    _gram(A, G)  # again: the reduction overwrote G, and Q is still in A's first columns
    for _sweep in range(50):
        off = 0.0
        diag = 0.0
        for a in range(6):
            diag += G[a, a] * G[a, a]
            for b in range(a + 1, 6):
                off += G[a, b] * G[a, b]
        if off <= 1e-36 * diag:
            break
        # a pair whose square is below the stopping bound's share (1e-36 diag over the 15 pairs) is
        # not rotated: were every pair so, the sweep would have stopped, and the bound on the final
        # off-diagonal sum is the same
        small = 1e-36 * diag / 15.0
        for a in range(5):
            for b in range(a + 1, 6):
                gab = G[a, b]
                if gab * gab <= small:
                    continue
                theta = 0.5 * (G[b, b] - G[a, a]) / gab
                t = (1.0 if theta >= 0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                cs = 1.0 / math.sqrt(t * t + 1.0)
                sn = t * cs
                tau = sn / (1.0 + cs)
                # the rotation G <- R^T G R on the symmetric matrix: only rows/columns a and b
                # change, (a, b) becomes zero and the diagonal moves by t g_ab (Rutishauser's form)
                G[a, a] -= t * gab
                G[b, b] += t * gab
                G[a, b] = 0.0
                G[b, a] = 0.0
                for k in range(6):
                    if k == a or k == b:
                        continue
                    gka, gkb = G[k, a], G[k, b]
                    nka = gka - sn * (gkb + tau * gka)
                    nkb = gkb + sn * (gka - tau * gkb)
                    G[k, a] = nka
                    G[a, k] = nka
                    G[k, b] = nkb
                    G[b, k] = nkb
    lo = G[0, 0]
    hi = G[0, 0]
    for a in range(1, 6):
        lo = min(lo, G[a, a])
        hi = max(hi, G[a, a])
    if not (hi > 0.0) or lo <= 0.0:
        return 0.0
    return math.sqrt(lo / hi)


@njit(cache=True, nogil=True)
def _inverse_condition_call(px, py, pz, u, R2, rho, CSV, hb, inv_L, A, G):
    """:func:`_inverse_condition` as a call of its own, for the kernels where a voxel's other work
    dwarfs the call (the sweep's carriage search) or that take a sample of poses. Inlined into both,
    it took 34 s of their first compile; as a call, 21 s with the call's own 7 s (one core, a fresh
    cache; the sweep at h = 4 / 2 took 0.96 / 1.03 of its time, the same values)."""
    return _inverse_condition(px, py, pz, u, R2, rho, CSV, hb, inv_L, A, G)


@njit(parallel=True, cache=True, nogil=True)
def _sweep_kernel(occ, planes, offset, xs, ys, zs, u, R2, e_lo, e_hi, r_lo, r_hi, hb, inv_L, lmin, lmax,
                  out, rho_out, eta_out):
    """The exact field (module docstring) over the ``x`` planes ``planes`` (``-1``: none): ``out`` gets
    ``1/kappa`` and ``rho_out``/``eta_out`` (N, 3; ``rho = r - d``, ``eta`` in radians) the resolved
    carriage of the reachable voxels in C order (``offset[i]``: the index of plane ``i``'s first)."""
    ny, nz = occ.shape[1], occ.shape[2]
    for t in prange(planes.shape[0]):
        i = planes[t]
        if i < 0:
            continue
        CS, UB = work_arrays()
        rho = np.zeros(3)
        eta = np.zeros(3)
        A = np.empty((6, 18))
        G = np.empty((6, 6))
        CSV = np.empty((3, 2))
        index = plane_index(occ, i, ny, offset[i])
        px = xs[i]
        for j in range(ny):
            py = ys[j]
            for k in range(nz):
                if not occ[i, j, k]:
                    continue
                pz = zs[k]
                for c in range(3):
                    r, e = best_carriage(px + u[c, 0, 0], py + u[c, 0, 1], pz + u[c, 0, 2],
                                         px + u[c, 1, 0], py + u[c, 1, 1], pz + u[c, 1, 2],
                                         2.0 * math.pi * c / 3.0, e_lo, e_hi, r_lo, r_hi, hb, lmin, lmax,
                                         CS, UB, True)
                    rho[c] = r
                    eta[c] = e
                m = index[j, k]
                for c in range(3):
                    rho_out[m, c] = rho[c]
                    eta_out[m, c] = eta[c]
                _carriage_trig(eta, CSV)
                out[m] = _inverse_condition_call(px, py, pz, u, R2, rho, CSV, hb, inv_L, A, G)


@dataclasses.dataclass(frozen=True)
class FieldInputs:
    """What a per-voxel dexterity driver hands its kernel: the occupancy and axes as contiguous
    arrays, the kernel constants of :func:`_constants`, the carriage limits (eta in radians), and
    each x plane's offset into the C-ordered list of the ``n`` reachable voxels."""

    occ: np.ndarray
    xs: np.ndarray
    ys: np.ndarray
    zs: np.ndarray
    u: np.ndarray
    R2: np.ndarray
    hb: float
    inv_L: float
    e_lo: float
    e_hi: float
    r_lo: float
    r_hi: float
    offset: np.ndarray
    n: int


def field_inputs(design: Design, occupancy: np.ndarray, axes: Sequence[np.ndarray],
                 orientation: Sequence[float]) -> FieldInputs:
    """The :class:`FieldInputs` of ``occupancy`` (a grid of ``axes = (xs, ys, zs)``)."""
    occ = np.ascontiguousarray(np.asarray(occupancy, bool))
    xs, ys, zs = (np.ascontiguousarray(a, dtype=np.float64) for a in axes)
    u, R2, hb, inv_L = _constants(design, orientation)
    e_lo, e_hi = (math.radians(v) for v in design.eta_limits)
    r_lo, r_hi = design.rho_limits
    offset, n = plane_offsets(occ)
    return FieldInputs(occ, xs, ys, zs, u, R2, float(hb), float(inv_L), e_lo, e_hi, float(r_lo), float(r_hi),
                       offset, n)


def plane_offsets(occ: np.ndarray) -> tuple[np.ndarray, int]:
    """Each ``x`` plane's first reachable voxel's index in the C order of the reachable voxels of
    ``occ`` (int64), and their number."""
    counts = occ.reshape(occ.shape[0], -1).sum(axis=1)
    return np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64), int(counts.sum())


def plane_costs(occ: np.ndarray) -> np.ndarray:
    """Each ``x`` plane's estimated cost for :func:`by_planes`, in reachable voxels: its reachable
    voxels, plus :data:`FIRST_VOXEL_COST` for a plane that has one (the neighbour search's full
    search at a plane's first voxel)."""
    counts = occ.reshape(occ.shape[0], -1).sum(axis=1).astype(float)
    return counts + FIRST_VOXEL_COST * (counts > 0)


def by_planes(costs: np.ndarray, launch: Callable[[np.ndarray], None], progress: Reporter | None,
              cancel: CancelToken) -> None:
    """Call ``launch(planes)`` on the x planes in runs of ``PLANES`` per thread, checking ``cancel``
    before each run and reporting the share done after it. ``planes`` is the run's planes in
    :func:`kinematics.slices.dealt_order` for their ``costs`` (:func:`plane_costs`), ``-1`` where
    none: the threads' slices of a launch carry nearly equal work (numba hands a launch out in equal
    contiguous slices, so planes in grid order left the thread with the larger planes of a run of
    unequal ones working alone)."""
    nx = int(costs.size)
    run = PLANES * numba.get_num_threads()
    for i0 in range(0, nx, run):
        check(cancel)
        i1 = min(nx, i0 + run)
        with dealt_launch(costs[i0:i1]) as order:
            launch(np.where(order >= 0, order + i0, -1))
        if progress is not None:
            progress(i1 / nx, "dexterity")


@njit(parallel=True, cache=True, nogil=True)
def _at_poses_kernel(points, u, R2, rho, eta, hb, inv_L, out):
    """``out[p]``: :func:`_inverse_condition` at position ``points[p]`` with the chains' ``rho[p]`` and
    ``eta[p]`` (radians)."""
    for p in prange(points.shape[0]):
        A = np.empty((6, 18))
        G = np.empty((6, 6))
        CSV = np.empty((3, 2))
        _carriage_trig(eta[p], CSV)
        out[p] = _inverse_condition_call(points[p, 0], points[p, 1], points[p, 2], u, R2, rho[p], CSV, hb,
                                         inv_L, A, G)


def pose_inputs(design: Design, points: np.ndarray, d: np.ndarray, eta_deg: np.ndarray,
                orientation: Sequence[float]) -> tuple:
    """The kernels' inputs for positions ``points`` (N, 3) with per-point carriages ``d`` and
    ``eta_deg`` (N, 3 each): ``(points, rho, eta_rad, u, R2, hb, inv_L)``, contiguous float64."""
    pts = np.ascontiguousarray(np.asarray(points, float).reshape(-1, 3))
    n = pts.shape[0]
    rho = np.ascontiguousarray(design.r - np.asarray(d, float).reshape(n, 3))
    eta = np.ascontiguousarray(np.radians(np.asarray(eta_deg, float).reshape(n, 3)))
    u, R2, hb, inv_L = _constants(design, orientation)
    return pts, rho, eta, u, R2, hb, inv_L


def inverse_condition_at(design: Design, points: np.ndarray, d: np.ndarray, eta_deg: np.ndarray,
                         orientation: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """``1/kappa`` at positions ``points`` (N, 3) of one orientation with per-point carriages ``d``
    and ``eta_deg`` (N, 3 each), by the fields' compiled eigenvalues (:func:`_inverse_condition`; within
    :data:`TOL_REL` and :data:`TOL_ABS` of :func:`kinematics.dexterity.inverse_condition_batch`'s SVD,
    about 10x faster on 2,000 points)."""
    pts, rho, eta, u, R2, hb, inv_L = pose_inputs(design, points, d, eta_deg, orientation)
    n = pts.shape[0]
    out = np.zeros(n)
    if n:
        with kernel_launch(n):
            _at_poses_kernel(pts, u, R2, rho, eta, float(hb), float(inv_L), out)
    return out


def continuation_field(design: Design, occupancy: np.ndarray, axes: Sequence[np.ndarray],
                       orientation: Sequence[float] = (0.0, 0.0, 0.0), progress: Reporter | None = None,
                       cancel: CancelToken = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``1/kappa`` at the resolved carriage pose (module docstring) of every reachable voxel of
    ``occupancy`` (a grid of ``axes = (xs, ys, zs)``) in C order, with the carriage pose: returns
    ``(inverse_condition, d, eta_deg)`` as :func:`kinematics.dexterity.resolved_carriages` does."""
    f = field_inputs(design, occupancy, axes, orientation)
    out = np.zeros(f.n)
    rho = np.zeros((f.n, 3))
    eta = np.zeros((f.n, 3))
    by_planes(plane_costs(f.occ), lambda planes: _sweep_kernel(
        f.occ, planes, f.offset, f.xs, f.ys, f.zs, f.u, f.R2, f.e_lo, f.e_hi, f.r_lo, f.r_hi, f.hb, f.inv_L,
        float(design.l_min), float(design.l_max), out, rho, eta), progress, cancel)
    return out, design.r - rho, np.degrees(eta) + 0.0
