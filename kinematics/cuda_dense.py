"""The dense voxel test on an NVIDIA GPU (CuPy): one GPU thread per voxel, the same decision and the
same floating-point operations as the CPU engines.

Definition (:mod:`kinematics.workspace`, :mod:`kinematics.feasibility`): a voxel centre ``P`` is
reachable when for every chain ``i`` SOME arc sample ``k`` passes the exact test in ``rho`` (F2):
with ``e_k = (cos_t[i, k], sin_t[i, k], 0)``, ``p_j = B_j . e_k``, ``m_j = B_j . t_k -+ b/2`` and
``q_j = B_jz^2 + m_j^2`` for the S joints ``B_j = P + (R u)_ij``, the sets

    ``|rho - p_j| <= sqrt(l_max^2 - q_j)``  and  ``|rho - p_j| >= sqrt(max(l_min^2 - q_j, 0))``

of both legs meet on the rail ``[rho_lo, rho_hi]`` (:func:`kinematics.feasibility.feasible_plain`).
The CPU engines reach the same decision through a whole-stroke bound that never contradicts a sample
(its limits are relaxed by the rounding margin) and a warm-started sample search; this kernel tests
the samples outward from the stroke's middle and stops at the first that passes, which decides the
same existence. Each product, sum and square root is the CPU's, in the same order: the source is
compiled with ``--fmad=false`` (no fused multiply-add, which would round differently from numba's
code) and CUDA's square root and division are correctly rounded by default, so the GPU decides the
same voxels bit for bit (``tests/test_cuda_dense.py``: the device functions of :data:`SOURCE`
compiled for the CPU by a C++ compiler decide every voxel of several designs as the CPU engine does;
on a machine with a GPU, the CUDA backend against the CPU engines).

Scope: the strokes-only model (the paper's, the default). Joint cones and leg interference stay on
the CPU (:func:`check_backend` names them). The mirror ``y -> -y`` is used as on the CPU: the kernel
decides the rows the CPU engines decide and :func:`kinematics.workspace._run_grid` fills the others.
With ``all_chains`` every chain's bit is computed (the diagnostics' chain mask); without it a voxel
stops at its first failing chain, and only ``mask == 7`` is read.

Selected with ``backend="cuda"`` (:func:`kinematics.workspace.compute_workspace`, the command
line's ``--backend cuda``); CuPy comes with the ``cuda`` extra (``pip install 'paraspace[cuda]'``).
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from .design import ParameterError
from .progress import CancelToken, Reporter, check

__all__ = ["BACKENDS", "SOURCE", "DEVICE_SOURCE", "cuda_unavailable", "check_backend", "dense_masks_cuda"]

#: Where the dense test runs: the CPU engines (numba) or the GPU (this module).
BACKENDS: tuple[str, ...] = ("cpu", "cuda")

#: The per-voxel test as device functions (also compiled for the CPU by the tests).
DEVICE_SOURCE = r"""
typedef unsigned char u8;

__device__ __forceinline__ double ps_mx(double a, double b) { return a > b ? a : b; }
__device__ __forceinline__ double ps_mn(double a, double b) { return a < b ? a : b; }

/* kinematics.feasibility.feasible_plain: both legs' (F2) sets meet on the rail [rho_lo, rho_hi] */
__device__ __forceinline__ bool ps_feasible_plain(double b1x, double b1y, double b1z, double b2x, double b2y,
                                                  double b2z, double c, double s, double hb, double rho_lo,
                                                  double rho_hi, double lo2, double hi2) {
    double p1 = b1x * c + b1y * s;
    double m1 = -b1x * s + b1y * c - hb;
    double q1 = b1z * b1z + m1 * m1;
    double p2 = b2x * c + b2y * s;
    double m2 = -b2x * s + b2y * c + hb;
    double q2 = b2z * b2z + m2 * m2;
    if (q1 > hi2 || q2 > hi2) return false;
    double ro1 = sqrt(hi2 - q1);
    double ro2 = sqrt(hi2 - q2);
    if (ps_mx(ps_mx(p1 - ro1, p2 - ro2), rho_lo) > ps_mn(ps_mn(p1 + ro1, p2 + ro2), rho_hi)) return false;
    double ri1 = sqrt(ps_mx(lo2 - q1, 0.0));
    double ri2 = sqrt(ps_mx(lo2 - q2, 0.0));
    double a0 = p1 - ro1, a1 = p1 - ri1, a2 = p1 + ri1, a3 = p1 + ro1;
    double c0 = p2 - ro2, c1 = p2 - ri2, c2 = p2 + ri2, c3 = p2 + ro2;
    return (ps_mx(ps_mx(a0, c0), rho_lo) <= ps_mn(ps_mn(a1, c1), rho_hi))
        || (ps_mx(ps_mx(a0, c2), rho_lo) <= ps_mn(ps_mn(a1, c3), rho_hi))
        || (ps_mx(ps_mx(a2, c0), rho_lo) <= ps_mn(ps_mn(a3, c1), rho_hi))
        || (ps_mx(ps_mx(a2, c2), rho_lo) <= ps_mn(ps_mn(a3, c3), rho_hi));
}

/* the chain mask of one voxel centre: bit i when some arc sample of chain i passes (samples tried
   outward from the stroke's middle); without all_chains it stops at the first failing chain */
__device__ u8 ps_voxel_mask(double px, double py, double pz, const double* u, const double* cos_t,
                            const double* sin_t, int n, double hb, double rho_lo, double rho_hi, double lo2,
                            double hi2, int all_chains) {
    u8 mask = 0;
    int mid = n / 2;
    for (int i = 0; i < 3; i++) {
        const double* ui = u + 6 * i;
        double b1x = px + ui[0], b1y = py + ui[1], b1z = pz + ui[2];
        double b2x = px + ui[3], b2y = py + ui[4], b2z = pz + ui[5];
        bool ok = false;
        for (int step = 0; step < n + 1 && !ok; step++) {
            int off = (step + 1) / 2;
            int k = (step % 2 == 1) ? mid + off : mid - off;
            if (k < 0 || k >= n) continue;
            ok = ps_feasible_plain(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i * n + k], sin_t[i * n + k], hb,
                                   rho_lo, rho_hi, lo2, hi2);
        }
        if (ok) mask |= (u8)(1 << i);
        else if (!all_chains) break;
    }
    return mask;
}
"""

#: The kernel: the voxels ``(x0 + ix, iy, iz)`` of a slab of ``nxc`` x planes, rows ``iy < ny_eval``;
#: ``out`` is the slab, shape ``(nxc, ny, nz)``.
KERNEL_SOURCE = r"""
extern "C" __global__ void ps_dense_masks(const double* xs, const double* ys, const double* zs, int x0, int nxc,
                                          int ny, int ny_eval, int nz, const double* u, const double* cos_t,
                                          const double* sin_t, int n, double hb, double rho_lo, double rho_hi,
                                          double lo2, double hi2, int all_chains, u8* out) {
    long long t = (long long)blockIdx.x * blockDim.x + threadIdx.x;
    long long total = (long long)nxc * ny_eval * nz;
    if (t >= total) return;
    int iz = (int)(t % nz);
    long long r = t / nz;
    int iy = (int)(r % ny_eval);
    int ix = (int)(r / ny_eval);
    out[((long long)ix * ny + iy) * nz + iz] = ps_voxel_mask(xs[x0 + ix], ys[iy], zs[iz], u, cos_t, sin_t, n, hb,
                                                             rho_lo, rho_hi, lo2, hi2, all_chains);
}
"""

SOURCE = DEVICE_SOURCE + KERNEL_SOURCE

#: NVRTC options: no fused multiply-add (the CPU rounds each product and sum); the division and
#: square root are IEEE by default.
NVRTC_OPTIONS = ("--fmad=false",)
_THREADS = 256
_SLAB_VOXELS = 1 << 24  # voxels a launch (progress and cancellation between launches)


def cuda_unavailable() -> str | None:
    """Why the CUDA backend cannot run on this machine, in a user's words; ``None`` when it can."""
    try:
        import cupy
    except ImportError:
        return "CuPy is not installed (pip install 'paraspace[cuda]' on a machine with an NVIDIA GPU)"
    try:
        count = int(cupy.cuda.runtime.getDeviceCount())
    except Exception as err:  # noqa: BLE001 - CuPy's CUDA errors have no common public base
        return f"no usable NVIDIA GPU ({type(err).__name__}: {err})"
    return None if count > 0 else "no NVIDIA GPU is present"


def check_backend(backend: str, has_cones: bool = False, interference: bool = False) -> None:
    """Refuse a backend that cannot compute this request, naming the field and what is valid."""
    if backend not in BACKENDS:
        raise ParameterError("backend", backend, " or ".join(BACKENDS))
    if backend == "cpu":
        return
    if has_cones or interference:
        raise ParameterError("backend", backend, "cpu with joint cones or leg interference (the cuda backend "
                                                 "runs the strokes-only dense test)")
    why = cuda_unavailable()
    if why is not None:
        raise ParameterError("backend", backend, f"cpu on this machine: {why}")


@functools.lru_cache(maxsize=1)
def _kernel() -> Any:
    import cupy

    return cupy.RawModule(code=SOURCE, options=NVRTC_OPTIONS).get_function("ps_dense_masks")


def dense_masks_cuda(axes: tuple[np.ndarray, np.ndarray, np.ndarray], ny_eval: int, args: tuple, all_chains: bool,
                     progress: Reporter | None = None, cancel: CancelToken = None) -> np.ndarray:
    """The chain masks (uint8, the grid's shape) of the rows ``iy < ny_eval`` decided on the GPU (the
    other rows zero: the caller mirrors them). ``args``: :func:`kinematics.kernel_args.kernel_args`."""
    import cupy

    xs, ys, zs = (np.ascontiguousarray(a, dtype=np.float64) for a in axes)
    u, cos_t, sin_t, _arc, hb, rho_lo, rho_hi, lmin2, lmax2, _jc = args
    nx, ny, nz = xs.size, ys.size, zs.size
    out = np.zeros((nx, ny, nz), np.uint8)
    if not out.size or ny_eval <= 0:
        return out
    try:
        kernel = _kernel()
    except Exception as err:  # noqa: BLE001 - NVRTC's and the driver's errors have no common public base
        raise ParameterError("backend", "cuda", f"cpu on this machine: the CUDA kernel did not build here "
                                                f"({type(err).__name__}: {err})") from err
    d_xs, d_ys, d_zs = cupy.asarray(xs), cupy.asarray(ys), cupy.asarray(zs)
    d_u = cupy.asarray(np.ascontiguousarray(u, dtype=np.float64))
    d_cos, d_sin = cupy.asarray(np.ascontiguousarray(cos_t)), cupy.asarray(np.ascontiguousarray(sin_t))
    n = int(cos_t.shape[1])
    planes = max(1, min(nx, _SLAB_VOXELS // max(1, ny * nz)))
    d_out = cupy.zeros((planes, ny, nz), cupy.uint8)
    for x0 in range(0, nx, planes):
        check(cancel)
        nxc = min(planes, nx - x0)
        total = nxc * ny_eval * nz
        kernel((math.ceil(total / _THREADS),), (_THREADS,),
               (d_xs, d_ys, d_zs, np.int32(x0), np.int32(nxc), np.int32(ny), np.int32(ny_eval), np.int32(nz), d_u,
                d_cos, d_sin, np.int32(n), np.float64(hb), np.float64(rho_lo), np.float64(rho_hi),
                np.float64(lmin2), np.float64(lmax2), np.int32(bool(all_chains)), d_out))
        out[x0:x0 + nxc, :ny_eval] = d_out[:nxc, :ny_eval].get()
        if progress is not None:
            frac = (x0 + nxc) / nx
            progress(frac, f"computing the workspace on the GPU, {100 * frac:.0f} %")
    return out
