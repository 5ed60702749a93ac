"""Benchmark of the position-workspace engine (prints; asserts nothing).

In one run, on the issue's reference box [-180,180]^2 x [0,165] and the paper's default design:
  1. the compiled engine at h = 2 (target <= 0.5 s) and the coarse preview h = 6 (target <= 50 ms),
     best of several runs after compilation;
  2. the plain vectorised-numpy brute force (kinematics.reference) on the same grid as a baseline,
     at --voxel (default 4; h = 2 takes about 6 minutes), with the time ratio and both volumes;
  3. the volume error of the default settings against a converged reference (h = 1, eta step 0.125).

Usage: python benchmarks/bench_workspace.py [--voxel H] [--skip-converged]
"""

from __future__ import annotations

import argparse
import time

from paraspace.kinematics.design import Design
from paraspace.kinematics.grid import GridSpec
from paraspace.kinematics.reference import reference_reachable
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace, warm_up

BOX = ((-180.0, -180.0, 0.0), (180.0, 180.0, 165.0))


def best_of(n: int, fn):
    best, out = float("inf"), None
    for _ in range(n):
        out = fn()
        best = min(best, out.compute_seconds)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--voxel", type=float, default=4.0, help="grid of the engine-vs-numpy comparison")
    ap.add_argument("--skip-converged", action="store_true")
    ns = ap.parse_args()
    design = Design()
    print(f"compile/warm-up: {warm_up():.2f} s (numba cache on disk makes later starts fast)")

    for h, target in ((2.0, 0.5), (6.0, 0.05)):
        t, res = best_of(5, lambda: compute_workspace(design, WorkspaceSettings(voxel=h, bounds=BOX)))
        print(f"engine  h={h:g}: {t * 1e3:8.1f} ms  voxels={res.grid.size:>9,}  volume={res.volume:.6g}  "
              f"(target <= {target * 1e3:g} ms: {'met' if t <= target else 'MISSED'})")
    t, res = best_of(3, lambda: compute_workspace(design, WorkspaceSettings(voxel=2.0)))
    print(f"engine  h=2 with derived bounds {res.grid.shape}: {t * 1e3:.1f} ms")

    h = ns.voxel
    grid = GridSpec.from_bounds(*BOX, h)
    t_eng, eng = best_of(3, lambda: compute_workspace(design, WorkspaceSettings(voxel=h, bounds=BOX)))
    t0 = time.perf_counter()
    ref = reference_reachable(design, grid.points().reshape(-1, 3))
    t_ref = time.perf_counter() - t0
    v_ref = ref.sum() * h ** 3
    print(f"\nbaseline on the same grid h={h:g} ({grid.size:,} voxels):")
    print(f"  numpy brute force: {t_ref:8.3f} s   volume={v_ref:.6g}")
    print(f"  engine           : {t_eng:8.3f} s   volume={eng.volume:.6g}")
    print(f"  speed-up ratio   : {t_ref / t_eng:8.0f}x   identical voxels: {bool((ref.reshape(grid.shape) == eng.occupancy).all())}")

    if not ns.skip_converged:
        conv = compute_workspace(design, WorkspaceSettings(voxel=1.0, eta_step=0.125, bounds=BOX))
        v2 = compute_workspace(design, WorkspaceSettings(voxel=2.0, bounds=BOX)).volume
        print(f"\nconverged reference (h=1, eta step 0.125 deg): volume={conv.volume:.6g} in {conv.compute_seconds:.2f} s")
        print(f"  default h=2, eta step 0.5: relative error {abs(v2 - conv.volume) / conv.volume * 100:.3f} % (target <= 0.3 %)")


if __name__ == "__main__":
    main()
