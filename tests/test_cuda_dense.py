"""The CUDA backend's dense test (kinematics/cuda_dense.py).

Everywhere: the device functions of its CUDA source, compiled for this CPU by the C++ compiler (with
CUDA's qualifiers defined away and a loop over the voxels in place of the GPU's threads), decide every
voxel as the CPU engines do, through the same driver (`_run_grid`: the rows it decides, the mirror
fill, the chain masks); the whole kernel, its thread indexing included, compiled the same way and
launched by `dense_masks_cuda` itself with CuPy replaced by a stand-in (`_FakeCuPy`: the launcher's
arguments in the kernel's order and kinds, its slabs, the copy back, cancellation); and the backend
is refused by name where it cannot run. Where CuPy sees an NVIDIA GPU: the backend itself against the
CPU engines."""

from __future__ import annotations

import ctypes
import shutil
import subprocess

import numpy as np
import pytest

from paraspace.kinematics import cuda_dense, workspace
from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.feasibility import ChainTables, chain_points, default_n_eta, feasible_plain
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.kernel_args import kernel_args
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

# the whole source, kernel included, built for the CPU: CUDA's qualifiers defined away and its thread
# indices as globals that a loop over the launch's blocks and threads sets (host_launch: the emulated
# launch of the fake CuPy below); host_masks and host_feasible call the device functions directly
_HOST = r"""
#include <cmath>
using std::sqrt;
struct ps_dim3 { unsigned int x; };
static ps_dim3 blockIdx, blockDim, threadIdx;
#define __device__
#define __global__
#define __forceinline__ inline
""" + cuda_dense.SOURCE + r"""
extern "C" void host_masks(const double* xs, const double* ys, const double* zs, int nx, int ny, int ny_eval,
                           int nz, const double* u, const double* cos_t, const double* sin_t, int n, double hb,
                           double rho_lo, double rho_hi, double lo2, double hi2, int all_chains, u8* out) {
    for (int ix = 0; ix < nx; ix++)
        for (int iy = 0; iy < ny_eval; iy++)
            for (int iz = 0; iz < nz; iz++)
                out[((long long)ix * ny + iy) * nz + iz] = ps_voxel_mask(xs[ix], ys[iy], zs[iz], u, cos_t, sin_t, n,
                                                                         hb, rho_lo, rho_hi, lo2, hi2, all_chains);
}

extern "C" void host_feasible(int m, const double* v, u8* out) {  /* v: m rows of the 13 arguments */
    for (int j = 0; j < m; j++) {
        const double* a = v + 13 * j;
        out[j] = ps_feasible_plain(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11], a[12]);
    }
}

extern "C" void host_launch(unsigned int grid, unsigned int block, const double* xs, const double* ys,
                            const double* zs, int x0, int nxc, int ny, int ny_eval, int nz, const double* u,
                            const double* cos_t, const double* sin_t, int n, double hb, double rho_lo, double rho_hi,
                            double lo2, double hi2, int all_chains, u8* out) {
    blockDim.x = block;
    for (unsigned int b = 0; b < grid; b++) {
        blockIdx.x = b;
        for (unsigned int t = 0; t < block; t++) {
            threadIdx.x = t;
            ps_dense_masks(xs, ys, zs, x0, nxc, ny, ny_eval, nz, u, cos_t, sin_t, n, hb, rho_lo, rho_hi, lo2, hi2,
                           all_chains, out);
        }
    }
}
"""
#: the kernel's parameters after (grid, block): p a device array, i an int32, d a float64
_KINDS = "ppp" + "iiiii" + "ppp" + "i" + "ddddd" + "i" + "p"


@pytest.fixture(scope="module")
def host_lib(tmp_path_factory: pytest.TempPathFactory) -> ctypes.CDLL:
    """``_HOST`` compiled for the CPU: no fused multiply-add (as ``--fmad=false`` on the GPU)."""
    cxx = shutil.which("g++") or shutil.which("c++")
    assert cxx, "a C++ compiler (scripts/test.sh installs g++)"
    folder = tmp_path_factory.mktemp("cuda_host")
    (folder / "host.cpp").write_text(_HOST)
    subprocess.run([cxx, "-O2", "-ffp-contract=off", "-fno-fast-math", "-shared", "-fPIC", "-o",
                    str(folder / "host.so"), str(folder / "host.cpp")], check=True, capture_output=True)
    lib = ctypes.CDLL(str(folder / "host.so"))
    dp = np.ctypeslib.ndpointer(np.float64, flags="C_CONTIGUOUS")
    lib.host_masks.argtypes = [dp, dp, dp] + [ctypes.c_int] * 4 + [dp, dp, dp, ctypes.c_int] + \
        [ctypes.c_double] * 5 + [ctypes.c_int, np.ctypeslib.ndpointer(np.uint8, flags="C_CONTIGUOUS")]
    lib.host_masks.restype = None
    lib.host_feasible.argtypes = [ctypes.c_int, dp, np.ctypeslib.ndpointer(np.uint8, flags="C_CONTIGUOUS")]
    lib.host_feasible.restype = None
    lib.host_launch.restype = None
    return lib


def host_masks(lib: ctypes.CDLL, axes, ny_eval: int, args: tuple, all_chains: bool, progress=None,
               cancel=None) -> np.ndarray:
    """:func:`cuda_dense.dense_masks_cuda` with the CPU build of the device functions."""
    xs, ys, zs = (np.ascontiguousarray(a, dtype=np.float64) for a in axes)
    u, cos_t, sin_t, _arc, hb, rho_lo, rho_hi, lmin2, lmax2, _jc = args
    out = np.zeros((xs.size, ys.size, zs.size), np.uint8)
    lib.host_masks(xs, ys, zs, xs.size, ys.size, ny_eval, zs.size, np.ascontiguousarray(u, dtype=np.float64),
                   np.ascontiguousarray(cos_t), np.ascontiguousarray(sin_t), cos_t.shape[1], hb, rho_lo, rho_hi,
                   lmin2, lmax2, int(all_chains), out)
    return out


CASES = [
    (Design(), (0.0, 0.0, 0.0), 6.0, 0.5),  # the paper's default, the mirror used
    (Design(a=30.0, eta_s=60.0), (0.0, 0.0, 0.0), 5.0, 0.5),
    (Design(), (10.0, 15.0, -5.0), 6.0, 0.5),  # tilted: no mirror, every row decided
    (Design(l_s=30.0, d_s=20.0, eta_range="from-zero"), (0.0, 0.0, 0.0), 5.0, 0.5),  # no mirror
    (Design(eta_s=4.0), (0.0, 0.0, 0.0), 5.0, 2.0),  # 3 arc samples (odd)
    (Design(eta_s=6.0), (0.0, 0.0, 0.0), 5.0, 2.0),  # 4 arc samples (even): the search's last step is k = 0
]


@pytest.mark.parametrize("design, orientation, h, eta_step", CASES)
def test_device_functions_decide_every_voxel_as_the_cpu_engine(host_lib, monkeypatch, design, orientation, h,
                                                               eta_step) -> None:
    cpu = compute_workspace(design, WorkspaceSettings(voxel=h, orientation=orientation, eta_step=eta_step,
                                                      method="dense", diagnostics=True))
    assert 0 < cpu.voxels < cpu.occupancy.size
    monkeypatch.setattr(workspace, "dense_masks_cuda", lambda *a: host_masks(host_lib, *a))
    for all_chains in (True, False):
        settings = WorkspaceSettings(voxel=h, orientation=orientation, eta_step=eta_step,
                                     diagnostics=all_chains)
        mask, n_eta, occ = workspace._run_grid(design, settings, cpu.grid, None, None, all_chains=all_chains,
                                               backend="cuda")
        assert n_eta == cpu.n_eta
        np.testing.assert_array_equal(occ, cpu.occupancy)
        if all_chains:  # every chain's bit, the diagnostics' mask
            np.testing.assert_array_equal(mask, cpu.chain_mask)


def test_each_chain_bit_is_some_sample_passing(host_lib) -> None:
    """Voxel by voxel against the definition: bit i iff some arc sample of chain i passes
    ``feasible_plain``, for strokes of 1 to 6 samples and centres on random axes near the workspace."""
    rng = np.random.default_rng(7)
    for eta_s, n_eta in ((0.0, 1), (3.0, 2), (4.0, 3), (6.0, 4), (8.0, 5), (10.0, 6)):
        design = Design(eta_s=eta_s)
        step = eta_s / (n_eta - 1) if n_eta > 1 else 0.5
        assert default_n_eta(design, step) == n_eta
        args = kernel_args(design, (0.0, 0.0, 0.0), n_eta)
        u, cos_t, sin_t, _arc, hb, rho_lo, rho_hi, lmin2, lmax2, _jc = args
        assert ChainTables(design, n_eta).cos_t.shape == cos_t.shape == (3, n_eta)
        axes = tuple(np.sort(rng.uniform(lo, hi, m)) for lo, hi, m in ((-70, 70, 9), (-70, 70, 8), (80, 180, 7)))
        got = host_masks(host_lib, axes, axes[1].size, args, True)
        seen = set()
        for (ix, iy, iz), bits in np.ndenumerate(got):
            want = 0
            for i in range(3):
                b = chain_points(axes[0][ix], axes[1][iy], axes[2][iz], u, i)
                if any(feasible_plain(*b, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi, lmin2, lmax2)
                       for k in range(n_eta)):
                    want |= 1 << i
            assert bits == want, (eta_s, ix, iy, iz)
            seen.add(want)
        assert 0 in seen and 7 in seen and len(seen) > 2, seen


def test_rounding_is_the_cpus_on_the_decisions_edge(host_lib) -> None:
    """Cases decided by the last bit: the rail's upper end set to exactly the CPU's lower end of leg 1's
    outer interval (``p1 - ro1`` as numba rounds it), the legs' other ends well inside. Equal ends
    meet, so both builds answer True only if every product and sum is rounded as on the CPU (a fused
    multiply-add, as NVRTC emits without ``--fmad=false``, moves ``p1`` by an ulp in many of them)."""
    rng = np.random.default_rng(11)
    m = 4000
    b = rng.uniform((-80, -80, 60, -80, -80, 60), (80, 80, 170, 80, 80, 170), (m, 6))
    ang = rng.uniform(0, 2 * np.pi, m)
    c, s, hb = np.cos(ang), np.sin(ang), 0.0
    lo2, hi2 = 114.5 ** 2, 164.5 ** 2
    rows, want = [], []
    for j in range(m):
        b1x, b1y, b1z, b2x, b2y, b2z = (float(x) for x in b[j])
        p1 = b1x * c[j] + b1y * s[j]
        m1 = -b1x * s[j] + b1y * c[j] - hb
        q1 = b1z * b1z + m1 * m1
        if q1 >= hi2:
            continue
        edge = p1 - np.sqrt(hi2 - q1)  # numpy's double ops: numba's, one rounding each
        args = (b1x, b1y, b1z, b1x, b1y, b1z - 1e-3, c[j], s[j], hb, edge - 500.0, float(edge), lo2, hi2)
        rows.append(args)
        want.append(feasible_plain(*args))
    v = np.ascontiguousarray(rows, dtype=np.float64)
    got = np.zeros(len(rows), np.uint8)
    host_lib.host_feasible(len(rows), v, got)
    assert len(rows) > 1000 and sum(want) > 0.9 * len(rows)
    np.testing.assert_array_equal(got.astype(bool), np.array(want))


def test_the_backend_is_refused_by_name_where_it_cannot_run() -> None:
    with pytest.raises(ParameterError, match="backend = 'gpu' is invalid: expected cpu or cuda"):
        compute_workspace(Design(), WorkspaceSettings(voxel=8.0), backend="gpu")
    with pytest.raises(ParameterError, match="cpu with joint cones or leg interference"):
        compute_workspace(Design(), WorkspaceSettings(voxel=8.0, joints=Joints(leg_diameter=10.0)), backend="cuda")
    with pytest.raises(ParameterError, match="cpu with joint cones or leg interference"):
        compute_workspace(Design(), WorkspaceSettings(voxel=8.0, joints=Joints(theta_s=40.0)), backend="cuda")
    why = cuda_dense.cuda_unavailable()
    if why is not None:  # no GPU here: the reason, in the user's words
        with pytest.raises(ParameterError, match="expected cpu on this machine: " + why.split(" (")[0]):
            compute_workspace(Design(), WorkspaceSettings(voxel=8.0), backend="cuda")


def test_the_command_line_names_the_backend_and_what_is_valid() -> None:
    from cli_inprocess import run_cli

    for args, valid in ((("--backend", "gpu"), "expected cpu or cuda"),
                        (("--backend", "cuda", "--leg-diameter", "10"),
                         "expected cpu with joint cones or leg interference"),
                        (("--backend", "cuda", "--mechanism", "6-pss"), "expected cpu for '6-PSS")):
        r = run_cli("workspace", "--voxel", "8", *args)
        assert r.returncode == 2 and r.stdout == "", r
        assert r.stderr.startswith("paraspace: error: backend = ") and valid in r.stderr, r.stderr
        assert "Traceback" not in r.stderr
    if cuda_dense.cuda_unavailable() is not None:
        r = run_cli("workspace", "--voxel", "8", "--backend", "cuda")
        assert r.returncode == 2 and "expected cpu on this machine" in r.stderr, r.stderr
    r = run_cli("workspace", "--voxel", "8", "--backend", "cpu", "--json")
    assert r.returncode == 0 and '"voxels": 10016' in r.stdout


class _DeviceArray(np.ndarray):
    """A fake CuPy array: a numpy array with CuPy's ``get()``."""

    def get(self) -> np.ndarray:
        return np.array(self)


class _FakeCuPy:
    """The part of CuPy that :mod:`kinematics.cuda_dense` uses, on the CPU: arrays are numpy arrays, and
    ``RawModule`` checks the source and the options it is given and launches the CPU build of that
    source (``_HOST``'s ``host_launch``), checking each argument's kind against the kernel's parameter list."""

    uint8 = np.uint8

    def __init__(self, lib: ctypes.CDLL) -> None:
        self.lib, self.launches, self.built = lib, [], []
        self.cuda = type("cuda", (), {"runtime": type("runtime", (), {"getDeviceCount": staticmethod(lambda: 1)})})

    @staticmethod
    def asarray(a) -> _DeviceArray:
        return np.array(a, copy=True, order="C").view(_DeviceArray)

    @staticmethod
    def zeros(shape, dtype) -> _DeviceArray:
        return np.zeros(shape, dtype).view(_DeviceArray)

    def RawModule(self, code: str, options: tuple):  # noqa: N802 - CuPy's name
        self.built.append((code, options))
        fake = self

        class Module:
            def get_function(self, name: str):
                assert name == "ps_dense_masks"
                return fake.launch

        return Module()

    def launch(self, grid: tuple, block: tuple, args: tuple) -> None:
        assert len(args) == len(_KINDS), len(args)
        conv = []
        for kind, a in zip(_KINDS, args):
            if kind == "p":
                assert isinstance(a, _DeviceArray) and a.flags.c_contiguous, type(a)
                conv.append(ctypes.c_void_p(a.ctypes.data))
            elif kind == "i":
                assert isinstance(a, np.int32), type(a)
                conv.append(ctypes.c_int(int(a)))
            else:
                assert isinstance(a, np.float64), type(a)
                conv.append(ctypes.c_double(float(a)))
        self.launches.append((grid, block, int(args[3]), int(args[4])))
        self.lib.host_launch(ctypes.c_uint(grid[0]), ctypes.c_uint(block[0]), *conv)


@pytest.mark.parametrize("orientation, diagnostics", [((0.0, 0.0, 0.0), False), ((10.0, 15.0, -5.0), True)])
def test_the_launcher_through_a_cpu_build_of_the_whole_kernel(host_lib, monkeypatch, orientation,
                                                              diagnostics) -> None:
    """``compute_workspace(..., backend="cuda")`` end to end with CuPy replaced by :class:`_FakeCuPy`:
    the kernel's own source and thread indexing, the launcher's arguments in the kernel's order and
    kinds, slabs of x planes with a short last one, the copy back, the progress lines and cancellation
    between slabs. What this cannot check is CuPy, NVRTC and the device themselves."""
    import sys

    from paraspace.kinematics.progress import Cancelled

    fake = _FakeCuPy(host_lib)
    monkeypatch.setitem(sys.modules, "cupy", fake)
    monkeypatch.setattr(cuda_dense, "_SLAB_VOXELS", 9000)  # several slabs, the last one short
    cuda_dense._kernel.cache_clear()
    try:
        assert cuda_dense.cuda_unavailable() is None
        s = WorkspaceSettings(voxel=6.0, orientation=orientation, diagnostics=diagnostics)
        cpu = compute_workspace(Design(), s)
        lines: list[str] = []
        gpu = compute_workspace(Design(), s, progress=lambda f, m: lines.append(m), backend="cuda")
        assert gpu.grid == cpu.grid and gpu.voxels == cpu.voxels > 0
        np.testing.assert_array_equal(gpu.occupancy, cpu.occupancy)
        if diagnostics:
            np.testing.assert_array_equal(gpu.chain_mask, cpu.chain_mask)
        assert fake.built and all(code == cuda_dense.SOURCE and "--fmad=false" in opts for code, opts in fake.built)
        # the final grid's launches: slabs of whole x planes, in order, the last one short, covering every plane
        nx, (ny, nz) = cpu.grid.shape[0], cpu.grid.shape[1:]
        planes = 9000 // (ny * nz)
        count = -(-nx // planes)
        last = [(x0, nxc) for _g, _b, x0, nxc in fake.launches][-count:]
        assert last == [(x0, min(planes, nx - x0)) for x0 in range(0, nx, planes)], last
        assert len(last) > 3 and last[-1][1] < planes, last
        assert all(g[0] * b[0] >= nxc * nz for g, b, _x0, nxc in fake.launches[-len(last):])
        assert any("on the GPU" in m for m in lines), lines
        # cancelled between slabs (30 x planes of 30 x 19 voxels: slabs of 15): the second never starts
        calls = iter(range(100))
        before = len(fake.launches)
        with pytest.raises(Cancelled):
            compute_workspace(Design(), WorkspaceSettings(voxel=6.0, orientation=orientation,
                                                          bounds=((-90, -90, 60), (90, 90, 170))),
                              cancel=lambda: next(calls) >= 1, backend="cuda")
        assert len(fake.launches) == before + 1
    finally:
        cuda_dense._kernel.cache_clear()


needs_gpu = pytest.mark.skipif(cuda_dense.cuda_unavailable() is not None,
                               reason=f"the CUDA backend: {cuda_dense.cuda_unavailable()}")


@needs_gpu
@pytest.mark.parametrize("orientation", [(0.0, 0.0, 0.0), (10.0, 15.0, -5.0)])
@pytest.mark.parametrize("h", [2.0, 1.0])
def test_cuda_backend_equals_the_cpu_engines(orientation, h) -> None:
    for design in (Design(), Design(a=30.0, eta_s=60.0)):
        for diagnostics in (False, True):
            s = WorkspaceSettings(voxel=h, orientation=orientation, diagnostics=diagnostics)
            cpu = compute_workspace(design, s)
            gpu = compute_workspace(design, s, backend="cuda")
            assert gpu.grid == cpu.grid
            np.testing.assert_array_equal(gpu.occupancy, cpu.occupancy)
            if diagnostics:
                np.testing.assert_array_equal(gpu.chain_mask, cpu.chain_mask)
