"""Benchmark of the position-workspace engine (prints; asserts nothing).

In one run, on the issue's reference box [-180,180]^2 x [0,165] and the paper's default design:
  1. the compiled engine at h = 2 (target <= 0.5 s) and the coarse preview h = 6 (target <= 50 ms),
     best of several runs after compilation;
  2. the plain vectorised-numpy brute force (kinematics.reference) on the same grid as a baseline,
     at --voxel (default 4; h = 2 takes about 6 minutes), with the time ratio and both volumes;
  3. the volume error of the default settings against a converged reference (h = 1, eta step 0.125).

  4. engine v2: the coarse-to-fine engine (method="blocks", the default) against the dense engine
     (method="dense") in the same run, at h = 2 and h = 1 with derived bounds: medians of several
     runs, the ratio, and whether the voxels are identical; idle, then with a second process busy
     on one core (``--no-load`` skips the loaded rows).

  5. the cost of each engine option relative to the plain model at h = 2 (joint cones with both
     axes, leg interference, diagnostics, the certified bracket at each refinement level with its
     gap), medians of alternating runs;
  6. one thread against two, idle and with a second process busy on one core, for numba's default
     equal split (with the orientation scan's former pair-by-pair kernel), for chunked launches
     (kinematics/parallel.py) with the line scan (kinematics/line_scan.py), and for today's default
     (chunks, and one thread while other tasks fill every core): medians of alternating runs, the
     1-thread/2-thread ratio of each and the 2-thread speed-up of today's default.

  7. a task (kinematics/task.py) against the plain workspace at h = 2 in the same run: a 50 x 50 x 40
     box centred at (0, 0, 130) with every tilt up to 15 degrees (all azimuths, 61 orientations) at
     h = 2 on the default design (fraction, margin with margin_range 10, certification; and without
     the certification, as the optimiser evaluates it), and a 1,000-pose trajectory (a helix with tilt and
     time stamps: reachability, continuous carriage motion, actuator values): medians, ratios.

  8. issue 24 (throughput): each step around the engine as a ratio to the plain engine on the same
     design, measured in the same run (medians of alternating runs), with the load average: every
     row that issue 24's work touched, the new path beside the old one it replaced (the dexterity
     field at h = 2 is one run of each: the full search takes over a minute). Target 1 also has a
     row for the feature filter alone (its four dilations) with 1 and 2 numba threads, against the
     former int32 whole-grid kernel, with whether both give the same solid. Target 4: the engine
     with leg interference, blocks decided by Lipschitz bounds against the per-voxel search.
     Target 10: the explorer's display shell at h = 2 (re-mesh and decimation to the display budget,
     against the re-mesh alone, with the GLB bytes). Target 8: an optimiser generation's time per
     design, serially, on a local cluster of 2 workers started by the run, and on the warm client
     reused by the next run (first and later generations). Target 6: the certified bracket alone at
     h = 2 with 0, 1, 2 refinements. Target 7 (also alone, ``--serial-tail``): each stage of the
     engine and of the measures at h = 0.5 with 1 and 2 threads, the single-threaded share by
     Amdahl's law and measured directly (the time outside numba's parallel kernels with 1 thread).
     Target 11: the CUDA backend against the CPU engine at h = 2, 1, 0.5 (a line saying why not where
     the machine has no NVIDIA GPU or no CuPy).
  9. a row per mechanism preset (kinematics/presets.py) at h = 2 with derived bounds, against the
     paper engine on the paper's default design in the same run (medians of alternating runs; its
     dense method too, which like the general engine evaluates every voxel, though it computes half the
     columns by the mirror y -> -y): the
     paper preset (routed to the paper engine: its ratio must stay 1.00), the general engine
     (kinematics/mechanism_workspace.py) on the paper preset's grid (with whether its voxels are the
     paper engine's; its blocks and dense methods), and the gough-stewart, 6-pups and 6-pss presets.

Usage: python benchmarks/bench_workspace.py [--voxel H] [--skip-converged] [--no-load] [--only-v2]
                                            [--options] [--threads] [--task] [--throughput] [--presets]
                                            [--total-orientation] [--measure-stages] [--serial-tail]
"""

from __future__ import annotations

import argparse
import contextlib
import multiprocessing
import os
import pathlib
import statistics
import sys
import time
from collections.abc import Sequence

# this checkout, not a copy of paraspace installed in the environment (python benchmarks/x.py puts
# benchmarks/ first on sys.path, not the repository root)
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from paraspace.kinematics import column_counts  # noqa: E402
from paraspace.kinematics import euler as euler_mod  # noqa: E402
from paraspace.kinematics import morphology as morph_mod  # noqa: E402
from paraspace.kinematics import voids as voids_mod  # noqa: E402
from paraspace.kinematics.design import Design  # noqa: E402
from paraspace.kinematics.grid import GridSpec  # noqa: E402
from paraspace.kinematics.reference import reference_reachable  # noqa: E402
from paraspace.kinematics.run_components import LabelledComponents  # noqa: E402
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace, warm_up  # noqa: E402

BOX = ((-180.0, -180.0, 0.0), (180.0, 180.0, 165.0))


def best_of(n: int, fn):
    best, out = float("inf"), None
    for _ in range(n):
        out = fn()
        best = min(best, out.compute_seconds)
    return best, out


def _spin(stop) -> None:
    """A second process busy on one core, in its own session like a program started from another
    terminal: with Linux's ``sched_autogroup`` (on by default) each session is scheduled as one
    group, and a busy child of the benchmark's own session would share our group's CPU time
    thread by thread instead (a different, milder load). The new session gets the benchmark's
    autogroup priority."""
    try:
        with open("/proc/self/autogroup") as fh:
            nice = fh.read().split()[-1]
        os.setsid()
        with open("/proc/self/autogroup", "w") as fh:
            fh.write(nice)
    except (OSError, AttributeError, IndexError):
        pass  # no autogroup: the plain child process is the load
    x = 0
    while not stop.is_set():
        x += 1


def engine_v2_rows(design: Design, runs: int = 5) -> None:
    """Median compute time of dense vs blocks at h = 2 and h = 1 (derived bounds) and their ratio."""
    import numpy as np

    for h in (2.0, 1.0):
        dense_t, blocks_t = [], []
        same = True
        for _ in range(runs if h > 1 else max(3, runs - 2)):  # alternate A/B so drift hits both
            d = compute_workspace(design, WorkspaceSettings(voxel=h, method="dense"))
            b = compute_workspace(design, WorkspaceSettings(voxel=h, method="blocks"))
            dense_t.append(d.compute_seconds)
            blocks_t.append(b.compute_seconds)
            same = same and bool(np.array_equal(d.occupancy, b.occupancy))
        md, mb = statistics.median(dense_t), statistics.median(blocks_t)
        print(f"  h={h:g} {d.grid.size:>10,} voxels: dense {md * 1e3:8.1f} ms  blocks {mb * 1e3:7.1f} ms  "
              f"ratio {md / mb:5.1f}x  identical voxels: {same}   (min-max blocks {min(blocks_t) * 1e3:.0f}-"
              f"{max(blocks_t) * 1e3:.0f} ms)")


def _median_time(fn, runs: int) -> tuple[float, object]:
    ts, out = [], None
    for _ in range(runs):
        t = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t)
    return statistics.median(ts), out


def option_rows(design: Design, runs: int = 5) -> None:
    """Item 5 of the module docstring."""
    from paraspace.kinematics.joints import Joints

    plain = WorkspaceSettings(voxel=2.0)
    options = {
        "plain (strokes only)": plain,
        "cones 45 deg, normal axes": WorkspaceSettings(voxel=2.0, joints=Joints(theta_u=45, theta_s=45)),
        "cones 45 deg, home axes": WorkspaceSettings(voxel=2.0, joints=Joints(theta_u=45, theta_s=45, cone_axis="home")),
        "legs of diameter 10": WorkspaceSettings(voxel=2.0, joints=Joints(leg_diameter=10.0)),
        "diagnostics (every chain)": WorkspaceSettings(voxel=2.0, diagnostics=True),
    }
    for st in options.values():
        compute_workspace(design, st)  # compile
    base, ref = _median_time(lambda: compute_workspace(design, plain), runs)
    for name, st in options.items():
        t, res = _median_time(lambda st=st: compute_workspace(design, st), runs)
        print(f"  {name:<28} {t * 1e3:8.1f} ms  x{t / base:5.2f}  volume {res.volume:.4g}")
    for refine in (0, 1, 2):
        st = WorkspaceSettings(voxel=2.0, bracket=True, bracket_refine=refine)
        t, res = _median_time(lambda st=st: compute_workspace(design, st), max(1, runs // 2))
        gap = (res.volume_outer - res.volume_inner) / res.volume
        print(f"  bracket, {refine} refinement(s)      {t * 1e3:8.1f} ms  x{t / base:5.2f}  gap {100 * gap:.1f} % of V "
              f"[{res.volume_inner:.5g}, {res.volume_outer:.5g}]")


def task_rows(design: Design, runs: int = 5) -> None:
    """Item 7 of the module docstring."""
    import numpy as np

    from paraspace.kinematics.task import OrientationSet, PoseList, Region, TaskSettings, pose_list_task, region_task

    box = Region("box", (0.0, 0.0, 130.0), (50.0, 50.0, 40.0))
    tilt = OrientationSet(tilt=15.0, torsion=0.0)
    st = TaskSettings(voxel=2.0)
    s = np.linspace(0.0, 1.0, 1000)
    path = np.stack([30 * np.cos(6 * np.pi * s), 30 * np.sin(6 * np.pi * s), 120 + 30 * s, 10 * np.sin(4 * np.pi * s),
                     8 * np.cos(2 * np.pi * s), 5 * np.sin(2 * np.pi * s)], 1)
    poses = PoseList(path, 20.0 * s)
    region_task(design, box, tilt, st)  # compile
    pose_list_task(design, PoseList(path[:20]), st)
    base, _ = _median_time(lambda: compute_workspace(design, WorkspaceSettings(voxel=2.0)), runs)
    print(f"  plain workspace h = 2 (derived bounds)  {base * 1e3:9.1f} ms  x 1.00")
    for name, fn in (("box 50x50x40, tilt <= 15, certified", lambda: region_task(design, box, tilt, st)),
                     ("  the same, not certified", lambda: region_task(design, box, tilt, st, certify=False)),
                     ("1,000-pose trajectory", lambda: pose_list_task(design, poses, st))):
        t, res = _median_time(fn, runs)
        extra = (f"fraction {res.fraction:.4f}, margin {res.margin:.3g}, {res.certified}, "
                 f"{res.details.get('sample_points', len(poses))} points x {res.details.get('orientation_samples', 1)}"
                 if res.kind == "region" else
                 f"fraction {res.fraction:.4f}, {len(res.discontinuities)} jumps, travel d "
                 f"{res.details['carriage']['travel_d']:.4g}")
        print(f"  {name:<38} {t * 1e3:9.1f} ms  x{t / base:5.2f}  {extra}")


def _alternating(fns: dict, runs: int) -> dict:
    """Median seconds of each callable of ``fns``, called in turn ``runs`` times (drift hits all).

    The callable named ``engine`` (every row's baseline) is called once untimed before each timed
    call: an engine run right after a long step read 1.15-1.35x the engine's own time on the 2-core
    machine (2026-11-29), which flattered every ratio against it. The timed run follows an engine
    run, as in the dexterity row."""
    times: dict = {k: [] for k in fns}
    for _ in range(runs):
        for k, f in fns.items():
            if k == "engine":
                f()
            t = time.perf_counter()
            f()
            times[k].append(time.perf_counter() - t)
    return {k: statistics.median(v) for k, v in times.items()}


def _row(name: str, t: float, base: float, note: str = "") -> None:
    print(f"  {name:<44} {t * 1e3:9.1f} ms  x{t / base:6.2f} engine  {note}")


def shell_rows(design: Design, runs: int = 5) -> None:
    """Target 9: ``make_shell`` at h = 1 as the explorer and the API call it (the display shell of
    kinematics.display_mesh: a block re-mesh of at most 3x the display budget, smoothed, decimated
    to it), and its former path without the display decimation (the 60 000-face block re-mesh,
    smoothed) with the block means from one summed-volume table, and with the former per-size means
    (``_block_mean`` for each k tried)."""
    from paraspace.app.explorer.workspace_job import FULL_FACES, make_shell
    from paraspace.kinematics import shell

    res = compute_workspace(design, WorkspaceSettings(voxel=1.0))
    fast_call = shell._BlockMeans.__call__

    def old():
        shell._BlockMeans.__call__ = lambda self, k: shell._block_mean(self.field, k)  # type: ignore[method-assign]
        try:
            return make_shell(res, FULL_FACES, display_faces=None)
        finally:
            shell._BlockMeans.__call__ = fast_call  # type: ignore[method-assign]

    med = _alternating({"engine": lambda: compute_workspace(design, WorkspaceSettings(voxel=1.0)),
                        "display": lambda: make_shell(res, FULL_FACES),
                        "new": lambda: make_shell(res, FULL_FACES, display_faces=None), "old": old}, runs)
    shown = make_shell(res, FULL_FACES)
    print(f"  target 9, make_shell h=1 (load average {os.getloadavg()[0]:.2f}; engine {med['engine'] * 1e3:.0f} ms):")
    _row(f"make_shell, display shell {shown.metadata['paraspace']['display_faces_from']:,} -> {len(shown.faces):,} faces",
         med["display"], med["engine"], "(target <= 2x; what the explorer and the API build)")
    _row("make_shell, 60k re-mesh, block means from one table", med["new"], med["engine"], "(before the display shell)")
    _row("make_shell, 60k re-mesh, block means per size (before)", med["old"], med["engine"])


def evaluation_rows(design: Design, runs: int = 5) -> None:
    """Target 2: one sweep point at h = 2 (every measure, and volume alone), and one optimiser
    evaluation at h = 4 of ``volume,-footprint`` (the measures it names) against every measure."""
    from paraspace.kinematics.optimize import OptimizeSettings
    from paraspace.kinematics.sweep import evaluate_design

    for h in (2.0, 4.0):
        ws = WorkspaceSettings(voxel=h)
        names = OptimizeSettings(objectives="volume,-footprint", workspace=ws).measure_fields
        hull = OptimizeSettings(objectives="volume,-hollowness", workspace=ws).measure_fields
        med = _alternating({"engine": lambda ws=ws: compute_workspace(design, ws),
                            "all": lambda ws=ws: evaluate_design(design, ws),
                            "named": lambda ws=ws, n=names: evaluate_design(design, ws, measures=n),
                            "hull": lambda ws=ws, n=hull: evaluate_design(design, ws, measures=n)}, runs)
        print(f"  target 2, one evaluation at h={h:g} (load average {os.getloadavg()[0]:.2f}; "
              f"engine {med['engine'] * 1e3:.0f} ms):")
        _row("every measure (what each evaluation computed before)", med["all"], med["engine"])
        _row("volume,-footprint: " + ",".join(names), med["named"], med["engine"], "(target <= 2x at h = 4)")
        _row("volume,-hollowness: " + ",".join(hull), med["hull"], med["engine"])


@contextlib.contextmanager
def _patched(*patches):
    """Set ``(module, {name: value})`` attributes for the ``with`` block, then restore them."""
    saved = [(module, {k: getattr(module, k) for k in patch}) for module, patch in patches]
    for module, patch in patches:
        for k, v in patch.items():
            setattr(module, k, v)
    try:
        yield
    finally:
        for module, old in saved:
            for k, v in old.items():
                setattr(module, k, v)


def _grid_euler(components: type, euler) -> type:
    """``components`` (a class like :class:`~kinematics.run_components.RunComponents`) whose
    ``euler_characteristic`` is ``euler(occupancy, connectivity)`` over the grid: the measures take
    the Euler number from their components' runs now, and the former paths from the grid."""

    class GridEuler(components):
        def __init__(self, occupancy, connectivity: int = 1) -> None:
            super().__init__(occupancy, connectivity)
            self._occupancy = occupancy

        def euler_characteristic(self, connectivity: int = 1) -> int:
            occ = getattr(self, "_occupancy", None)
            if occ is None:  # built from runs (of_runs: the filtered solid): the grid painted from them
                occ = self.grid()
            return euler(occ, connectivity)

    return GridEuler


@contextlib.contextmanager
def _former_measures():
    """kinematics.measures on its former path (before issue 24): skimage's Euler number, voids by
    labelling the whole padded complement, int32 dilations of the whole grid, every hull facet at
    every column, column gaps and cover by cumulative ors, components by scipy's labelled grid (the
    tests' slow path)."""
    import numpy as np
    from scipy import ndimage as ndi

    from paraspace.kinematics import measures as mod

    def voids(occ, conn, runs=None, ends=None):  # the set's runs and x ends are not used here
        v = voids_mod.void_mask_labelled(occ, conn)
        return v, int(ndi.label(v, structure=voids_mod._structure(voids_mod.dual_connectivity(conn)))[1])

    hull = mod.hull_mask

    def hollow(occ, mode="hull", hull_=None):
        u = np.logical_or.accumulate(occ[:, :, ::-1], axis=2)[:, :, ::-1] & ~occ
        return u & (hull(occ, raster=False) if hull_ is None else hull_)

    patch = {"_voids": voids,
             "hull_mask": lambda occ, raster=False: hull(occ, raster=False),
             "feature_filter": morph_mod.feature_filter_reference,
             "hollow_mask": hollow, "column_gap_count": lambda occ: int(mod.column_gap_mask(occ).sum()),
             "RunComponents": LabelledComponents}  # components by a labelled grid, the Euler number by skimage
    # the hull, its underside, the sealed part of it and the gaps counted on the grid by the definitions
    patch.update({name: getattr(column_counts, name + "_reference")
                  for name in ("hull_ranges", "under_ranges", "gap_count", "count_in_ranges")})
    with _patched((mod, patch)):
        yield


def measure_rows(design: Design, runs: int = 3) -> None:
    """Target 1: measure_workspace (every measure) at h = 2 and h = 1, and on its former path."""
    from paraspace.kinematics.measures import measure_workspace

    for h in (2.0, 1.0):
        res = compute_workspace(design, WorkspaceSettings(voxel=h))

        def old(res=res):
            with _former_measures():
                return measure_workspace(res)

        med = _alternating({"engine": lambda h=h: compute_workspace(design, WorkspaceSettings(voxel=h)),
                            "new": lambda res=res: measure_workspace(res), "old": old}, runs)
        print(f"  target 1, measure_workspace h={h:g} (load average {os.getloadavg()[0]:.2f}; "
              f"engine {med['engine'] * 1e3:.0f} ms):")
        _row("measure_workspace", med["new"], med["engine"], "(target <= 1x)")
        _row("measure_workspace, former path (before)", med["old"], med["engine"])


@contextlib.contextmanager
def _measures_before_meas1():
    """kinematics.measures as it was before the meas1 branch: every candidate component labelled
    (voids, sealed cavity), qhull given every column end, the Euler kernel reading eight voxels per
    window."""
    import numpy as np
    from numba import njit, prange

    from paraspace.kinematics import measures as mod

    @njit(parallel=True, cache=True, nogil=True)
    def euler_hist_windows(occ, hist):  # the former _euler_hist_kernel, verbatim
        n0, n1, n2 = occ.shape
        for i in prange(-1, n0):
            for j in range(-1, n1):
                for k in range(-1, n2):
                    c = 0
                    for a in range(2):
                        x = i + a
                        if x < 0 or x >= n0:
                            continue
                        for b in range(2):
                            y = j + b
                            if y < 0 or y >= n1:
                                continue
                            for e in range(2):
                                z = k + e
                                if z < 0 or z >= n2:
                                    continue
                                if occ[x, y, z]:
                                    c |= 1 << (4 * (1 - a) + (1 - b) + 2 * (1 - e))
                    hist[i + 1, c] += 1

    def euler(occ, conn=1):
        occ = np.ascontiguousarray(occ, dtype=np.bool_)
        coefs = euler_mod._EULER_26[::-1] if conn == 1 else euler_mod._EULER_26
        hist = np.zeros((occ.shape[0] + 1, 256), np.int64)
        with mod.KERNEL_LOCK:
            euler_hist_windows(occ, hist)
        return int(0.125 * int(coefs @ hist.sum(axis=0)))

    from paraspace.kinematics.run_components import RunComponents

    def labelled_box(occ, conn, runs=None, shape=None, ends=None):  # the voids by labelling, on the whole grid
        if occ is None:  # given by its runs: the grid painted from them
            occ = RunComponents.of_runs(runs, shape).grid()
        voids, n = voids_mod._voids_labelled_candidates(occ, conn)
        return (voids, tuple(slice(0, m) for m in voids.shape)) if n else None

    hull, sealed_box = mod.hull_mask, voids_mod.sealed_box
    patch = {"_voids": lambda occ, conn, runs=None, ends=None: voids_mod._voids_labelled_candidates(occ, conn),
             "_void_box": labelled_box,  # the filled genus's voids
             "sealed_box": lambda occ, conn=1, floor=True, runs=None, ends=None: sealed_box(occ, conn, floor),  # grid
             "hull_mask": lambda occ, raster=True: hull(occ, raster, extreme=False),
             "RunComponents": _grid_euler(mod.RunComponents, euler)}
    with _patched((mod, patch), (voids_mod, {"_void_box": labelled_box})):  # the sealed cavity's too
        yield


def measure_meas1_rows(design: Design, runs: int = 3) -> None:
    """Targets 1 and 7 (meas1): measure_workspace at h = 2 and h = 1 with the voids by a flood, the
    hull from the extreme column ends and the four-read Euler kernel,
    against the same function on the path before them, with 1 and 2 numba threads, each as a ratio
    to the engine (machine's threads) in the same run; and whether every measure is identical."""
    import numba

    from paraspace.kinematics.measures import measure_workspace

    threads = numba.get_num_threads()
    for h in (2.0, 1.0):
        res = compute_workspace(design, WorkspaceSettings(voxel=h))
        new_d = measure_workspace(res).to_dict()
        with _measures_before_meas1():
            same = measure_workspace(res).to_dict() == new_d

        def before(res=res):
            with _measures_before_meas1():
                return measure_workspace(res)

        fns = {"engine": lambda h=h: compute_workspace(design, WorkspaceSettings(voxel=h))}
        for nt in sorted({1, min(2, threads)}):
            def with_threads(f, nt=nt):
                def run():
                    numba.set_num_threads(nt)
                    try:
                        return f()
                    finally:
                        numba.set_num_threads(threads)
                return run
            fns[f"new {nt}"] = with_threads(lambda res=res: measure_workspace(res))
            fns[f"old {nt}"] = with_threads(before)
        med = _alternating(fns, runs)
        print(f"  targets 1/7 (meas1), measure_workspace h={h:g} (load average {os.getloadavg()[0]:.2f}, loaded "
              f"machine; engine {med['engine'] * 1e3:.0f} ms, {threads} threads; identical measures: {same}):")
        for k in fns:
            if k != "engine":
                kind, nt = k.split()
                name = "measure_workspace" if kind == "new" else "measure_workspace, before meas1"
                _row(f"{name}, {nt} thread{'s' if nt != '1' else ''}", med[k], med["engine"],
                     "(target <= 1x)" if kind == "new" else "")


@contextlib.contextmanager
def _measures_before_meas2():
    """kinematics.measures as it was before the meas2 branch: components by scipy's labelled grid,
    the void flood's seeds by testing every dual neighbour, the Euler kernel reading every window,
    the dilations' y and z steps by a search from each voxel over every block row. (Not restored:
    the counts by ``count_nonzero``, the one contiguous copy of the cropped grid and the enclosed
    voxels' column ends found from both ends, a few ms each at h = 1.)"""
    import numpy as np
    from numba import njit, prange
    from scipy import ndimage as ndi

    from paraspace.kinematics import measures as mod
    from paraspace.kinematics import void_flood

    @njit(parallel=True, cache=True, nogil=True)
    def euler_hist_all(occ, hist):  # the former _euler_hist_kernel, verbatim
        n0, n1, n2 = occ.shape
        for ii in prange(n0 + 1):
            i = ii - 1
            x0 = i >= 0
            x1 = i + 1 < n0
            row = np.zeros(256, np.int64)
            for j in range(-1, n1):
                y0 = j >= 0
                y1 = j + 1 < n1
                c00 = x0 and y0
                c01 = x0 and y1
                c10 = x1 and y0
                c11 = x1 and y1
                code = 0
                for k in range(-1, n2):
                    z = k + 1
                    far = 0
                    if z < n2:
                        if c00 and occ[i, j, z]:
                            far |= 32
                        if c01 and occ[i, j + 1, z]:
                            far |= 16
                        if c10 and occ[i + 1, j, z]:
                            far |= 2
                        if c11 and occ[i + 1, j + 1, z]:
                            far |= 1
                    code = ((code & 0x33) << 2) | far
                    row[code] += 1
            for c in range(256):
                hist[ii, c] = row[c]

    def euler(occ, conn=1):
        occ = np.ascontiguousarray(occ, dtype=np.bool_)
        coefs = euler_mod._EULER_26[::-1] if conn == 1 else euler_mod._EULER_26
        hist = np.zeros((occ.shape[0] + 1, 256), np.int64)
        with mod.KERNEL_LOCK:
            euler_hist_all(occ, hist)
        return int(0.125 * int(coefs @ hist.sum(axis=0)))

    @njit(parallel=True, cache=True, nogil=True)
    def set_blocks_before(m, inv, bs, blk):
        """The former _set_blocks_kernel, verbatim (every block row scanned)."""
        nx, ny, nz = m.shape
        nb1, nb2 = blk.shape[1], blk.shape[2]
        for q in prange(blk.shape[0] * nb1 * nb2):
            a = q // (nb1 * nb2)
            b = (q // nb2) % nb1
            c = q % nb2
            hit = False
            for i in range(a * bs, min(nx, (a + 1) * bs)):
                for j in range(b * bs, min(ny, (b + 1) * bs)):
                    for k in range(c * bs, min(nz, (c + 1) * bs)):
                        if m[i, j, k] != inv:
                            hit = True
                            break
                    if hit:
                        break
                if hit:
                    break
            blk[a, b, c] = hit

    @njit(parallel=True, cache=True, nogil=True)
    def dilate_fast_before(m, w, r2, inv_in, inv_out, half, near, bs, d1, out):
        """The former _ball_dilate_fast_kernel, verbatim (a search from each voxel for y and z)."""
        nx, ny, nz = m.shape
        j0 = ny // 2 if half else 0
        cap = 255
        for j in prange(j0, ny):
            # the distance along x to the nearest set voxel, by a forward and a backward sweep
            near_i = np.empty(nz, np.int32)
            far = np.int32(-(1 << 30))
            for k in range(nz):
                near_i[k] = far
            for i in range(nx):
                ii = np.int32(i)
                for k in range(nz):
                    q = ii if m[i, j, k] != inv_in else near_i[k]
                    near_i[k] = q
                    d = ii - q
                    d1[i, j, k] = d * d if d <= w else cap
            far = np.int32(1 << 30)
            for k in range(nz):
                near_i[k] = far
            for i in range(nx - 1, -1, -1):
                ii = np.int32(i)
                for k in range(nz):
                    q = ii if m[i, j, k] != inv_in else near_i[k]
                    near_i[k] = q
                    d = q - ii
                    v = d * d if d <= w else cap
                    o = np.int32(d1[i, j, k])
                    d1[i, j, k] = v if v < o else o
        kb = np.empty(nz, np.int64)
        for k in range(nz):
            kb[k] = k // bs
        for i in prange(nx):
            d2 = np.empty(nz, np.int32)
            for j in range(j0, ny):
                row = near[i // bs, j // bs]
                for k in range(nz):
                    if not row[kb[k]]:
                        d2[k] = cap
                        continue
                    best = np.int32(d1[i, j, k])
                    for dj in range(1, w + 1):
                        c = dj * dj
                        if c >= best:
                            break
                        jp = j + dj
                        if jp < ny:
                            v = np.int32(d1[i, jp, k]) + c
                            if v < best:
                                best = v
                        jm = j - dj
                        if jm >= 0:
                            if jm < j0:
                                jm = ny - 1 - jm
                            v = np.int32(d1[i, jm, k]) + c
                            if v < best:
                                best = v
                    d2[k] = best
                for k in range(nz):
                    best = d2[k]
                    if row[kb[k]]:
                        for dk in range(1, w + 1):
                            c = dk * dk
                            if c >= best or c > r2:
                                break
                            if k + dk < nz and d2[k + dk] + c < best:
                                best = d2[k + dk] + c
                            if k - dk >= 0 and d2[k - dk] + c < best:
                                best = d2[k - dk] + c
                    val = (best <= r2) != inv_out
                    out[i, j, k] = val
                    if half:
                        out[i, ny - 1 - j, k] = val


    def dilate_before(mask, radius_voxels, *, complement=False, symmetric=False):
        """The former ball_dilate."""
        m = np.ascontiguousarray(mask, dtype=np.bool_)
        w = int(np.floor(radius_voxels + 1e-9))
        if w <= 0 or m.size == 0:
            return m.copy()
        r2 = int(np.floor(radius_voxels * radius_voxels + 1e-9))
        out = np.empty(m.shape, np.bool_)
        if r2 < 255:
            d1 = np.empty(m.shape, np.uint8)
            bs = max(w, 4)
            blk = np.empty(tuple(-(-n // bs) for n in m.shape), np.bool_)
            with mod.KERNEL_LOCK:
                set_blocks_before(m, complement, bs, blk)
            near = ndi.binary_dilation(blk, structure=np.ones((3, 3, 3), bool))
            with mod.KERNEL_LOCK:
                dilate_fast_before(m, w, r2, complement, complement, symmetric, near, bs, d1, out)
            return out
        if complement:
            m = ~m
        d1i = np.empty(m.shape, np.int32)
        d2 = np.empty(m.shape, np.int32)
        with mod.KERNEL_LOCK:
            morph_mod._ball_dilate_kernel(m, w, r2, d1i, d2, out)
        return ~out if complement else out

    reference_filter = morph_mod.feature_filter_reference
    patch = {"RunComponents": _grid_euler(LabelledComponents, euler),
             "feature_filter": lambda occ, r, cancel=None, runs=None, as_runs=False: reference_filter(
                 occ, r, cancel, dilate=dilate_before, as_runs=as_runs)}
    labelled_count = {"count_components": lambda occ, conn=1: LabelledComponents(occ, conn).count}
    with _patched((mod, patch), (voids_mod, labelled_count),
                  (void_flood, {"_seed_kernel": void_flood._seed_kernel_reference})):
        yield


def measure_stage_rows(design: Design, runs: int = 5) -> None:
    """Target 1 (meas2): each step of ``measure_workspace`` (of ``_Steps``, exclusive of the steps it
    calls) at h = 2 and h = 1 on this path and on the path before meas2 (:func:`_measures_before_meas2`),
    with the engine, in CPU seconds of this process with 1 numba thread (less disturbed by the
    other processes of a loaded machine than wall time), medians of ``runs`` alternating runs;
    and whether every measure is identical."""
    import numba

    from paraspace.kinematics import measures

    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    clock = time.process_time

    def staged(before: bool, res) -> dict:
        steps: dict = {}
        get = measures._Steps.get
        stack: list = []

        def timed_get(self, name):
            if name in self._memo:
                return get(self, name)
            stack.append(0.0)
            t0 = clock()
            out = get(self, name)
            dt = clock() - t0
            inner = stack.pop()
            steps[name] = steps.get(name, 0.0) + dt - inner
            if stack:
                stack[-1] += dt
            return out

        measures._Steps.get = timed_get  # type: ignore[method-assign]
        try:
            with _measures_before_meas2() if before else contextlib.nullcontext():
                t = clock()
                measures.measure_workspace(res)
                total = clock() - t
        finally:
            measures._Steps.get = get  # type: ignore[method-assign]
        steps["(outside the steps)"] = total - sum(steps.values())
        steps["measure_workspace total"] = total
        return steps

    try:
        for h in (2.0, 1.0):
            ws = WorkspaceSettings(voxel=h)
            res = compute_workspace(design, ws)
            new_d = measures.measure_workspace(res).to_dict()
            with _measures_before_meas2():
                same = measures.measure_workspace(res).to_dict() == new_d
            eng: list = []
            per: dict = {True: {}, False: {}}
            for _ in range(runs):
                t = clock()
                compute_workspace(design, ws)
                eng.append(clock() - t)
                for before in (True, False):
                    for k, v in staged(before, res).items():
                        per[before].setdefault(k, []).append(v)
            e = statistics.median(eng)
            print(f"  target 1 (meas2), measure_workspace stages h={h:g} ({res.grid.size:,} voxels; load average "
                  f"{os.getloadavg()[0]:.2f}; 1 thread, CPU time, medians of {runs}; engine {e * 1e3:.1f} ms; "
                  f"identical measures: {same}):")
            for k in per[False]:
                b = statistics.median(per[True].get(k, [0.0]))
                a = statistics.median(per[False][k])
                if max(a, b) >= 5e-4:
                    print(f"    {k:<26} before {b * 1e3:8.1f} ms  after {a * 1e3:8.1f} ms  x{b / a if a else 0:5.2f}"
                          f"   (x{b / e:5.2f} -> x{a / e:5.2f} engine)")
    finally:
        numba.set_num_threads(threads)


def feature_filter_rows(design: Design, runs: int = 3) -> None:
    """Target 1, the feature filter alone (its four ball dilations of the padded solid) at h = 2 and
    h = 1, with 1 and 2 numba threads: the packed, mirrored kernel against the former int32
    whole-grid kernel (``ball_dilate_reference``), each as a ratio to the engine (at the
    machine's thread count) in the same run."""
    import numba
    import numpy as np

    from paraspace.kinematics import measures as mod

    threads = numba.get_num_threads()

    for h in (2.0, 1.0):
        res = compute_workspace(design, WorkspaceSettings(voxel=h))
        m = mod.measure_workspace(res)
        occ, rv = res.occupancy, m.feature_radius_voxels
        new_out = morph_mod.feature_filter(occ, rv)
        same = bool(np.array_equal(morph_mod.feature_filter_reference(occ, rv), new_out))

        def old(occ=occ, rv=rv):
            return morph_mod.feature_filter_reference(occ, rv)

        fns = {"engine": lambda h=h: compute_workspace(design, WorkspaceSettings(voxel=h))}
        for nt in sorted({1, min(2, threads)}):
            def with_threads(f, nt=nt):
                def run():
                    numba.set_num_threads(nt)
                    try:
                        return f()
                    finally:
                        numba.set_num_threads(threads)
                return run
            fns[f"new {nt}"] = with_threads(lambda occ=occ, rv=rv: morph_mod.feature_filter(occ, rv))
            fns[f"old {nt}"] = with_threads(old)
        med = _alternating(fns, runs)
        print(f"  target 1, feature filter h={h:g} (r = {rv:.2f} voxels, {occ.size:,} voxels; load average "
              f"{os.getloadavg()[0]:.2f}; engine {med['engine'] * 1e3:.0f} ms, {threads} threads; "
              f"identical: {same}):")
        for k in fns:
            if k != "engine":
                kind, nt = k.split()
                name = "feature filter" if kind == "new" else "feature filter, former int32 (before)"
                _row(f"{name}, {nt} thread{'s' if nt != '1' else ''}", med[k], med["engine"])


def tail_rows(design: Design, runs: int = 3) -> None:
    """Target 7: the engine's serial tail at h = 1 and 0.5: the former numpy mirror fill and ``== 7``
    test against the fused parallel pass on the same chain masks."""
    import numpy as np

    from paraspace.kinematics import workspace

    for h in (1.0, 0.5):
        ws = WorkspaceSettings(voxel=h)
        res = compute_workspace(design, WorkspaceSettings(voxel=h, diagnostics=True))
        ny = res.grid.shape[1]
        ny_eval = (ny + 1) // 2
        half = res.chain_mask.copy()
        half[:, ny_eval:] = 0
        occ = np.empty(half.shape, bool)

        def old_tail():
            out = half.copy()
            out[:, ny_eval:] = workspace._MIRROR_BITS[out[:, : ny - ny_eval]][:, ::-1]
            return out == workspace.ALL_CHAINS

        def new_tail():
            out = half.copy()
            workspace._finish_kernel(out, ny_eval, True, workspace._MIRROR_BITS, occ)
            return occ

        med = _alternating({"engine": lambda ws=ws: compute_workspace(design, ws),
                            "copy": lambda: half.copy(), "old": old_tail, "new": new_tail}, runs)
        print(f"  target 7, serial tail h={h:g} ({res.grid.size:,} voxels; load average {os.getloadavg()[0]:.2f}; "
              f"engine {med['engine'] * 1e3:.0f} ms):")
        _row("mirror fill + == 7, one parallel pass", med["new"] - med["copy"], med["engine"])
        _row("mirror fill + == 7, numpy (before)", med["old"] - med["copy"], med["engine"])


def display_rows(design: Design, runs: int = 5) -> None:
    """Target 10: the explorer's full shell at h = 2 for the screen: the display shell
    (kinematics.display_mesh.display_shell: a re-mesh of at most 3x the display budget, smoothed,
    decimated to it), against the path before it (the 60 000-face re-mesh, smoothed, decimated by
    display_mesh) and the re-mesh sent before that, with the GLB bytes of each."""
    from paraspace.app.explorer.scene import glb_with_material
    from paraspace.app.explorer.workspace_job import FULL_FACES, make_shell
    from paraspace.kinematics.display_mesh import display_mesh

    ws = WorkspaceSettings(voxel=2.0)
    res = compute_workspace(design, ws)
    med = _alternating({"engine": lambda: compute_workspace(design, ws),
                        "light": lambda: make_shell(res, FULL_FACES),
                        "decimated": lambda: display_mesh(make_shell(res, FULL_FACES, display_faces=None)),
                        "before": lambda: make_shell(res, FULL_FACES, display_faces=None)}, runs)
    before = make_shell(res, FULL_FACES, display_faces=None)
    meshes = {"light": make_shell(res, FULL_FACES), "decimated": display_mesh(before), "before": before}
    size = {k: len(glb_with_material(m.export(file_type="glb", include_normals=True), 0.55)) for k, m in meshes.items()}
    print(f"  target 10, the explorer's display shell h=2 (load average {os.getloadavg()[0]:.2f}; "
          f"engine {med['engine'] * 1e3:.0f} ms):")
    light = meshes["light"].metadata["paraspace"]
    _row(f"display shell, {light['display_faces_from']:,} -> {len(meshes['light'].faces):,} faces", med["light"],
         med["engine"], f"(target: no slower than the engine) GLB {size['light'] / 1e6:.2f} MB")
    _row(f"60k re-mesh + decimation (before), {len(meshes['decimated'].faces):,} faces", med["decimated"],
         med["engine"], f"GLB {size['decimated'] / 1e6:.2f} MB")
    _row(f"re-mesh alone (before that), {len(before.faces):,} faces", med["before"], med["engine"],
         f"GLB {size['before'] / 1e6:.2f} MB")


def optimizer_cluster_rows(h: float = 6.0, population: int = 8, generations: int = 3, workers: int = 2) -> None:
    """Target 8: an optimiser generation's wall time per design, as a ratio to the plain engine on
    the default design: serially, on a local cluster started by the run (generation 1 then pays the
    cluster and the workers' warm-up: every run before the warm client), and on the next run, which
    reuses the warm client (kinematics.distributed.shared_client)."""
    from paraspace.kinematics.distributed import close_clients, shared_client
    from paraspace.kinematics.optimize import OptimizeSettings, optimize

    ws = WorkspaceSettings(voxel=h)
    engine = _alternating({"engine": lambda: compute_workspace(Design(), ws)}, 5)["engine"]
    s = OptimizeSettings(objectives="volume,-footprint", workspace=ws, population=population,
                         generations=generations, seed=1)

    def gens(**kw) -> list[float]:
        marks = [time.perf_counter()]
        optimize(s, on_generation=lambda info: marks.append(time.perf_counter()), **kw)
        return [b - a for a, b in zip(marks, marks[1:])]

    close_clients()
    try:
        serial = gens()
        cold = gens(workers=workers)
        client = shared_client(None, workers)
        warm = gens(workers=workers)
        same = shared_client(None, workers) is client
    finally:
        close_clients()
    print(f"  target 8, optimiser generations of {population} designs at h={h:g}, {workers} local workers "
          f"(load average {os.getloadavg()[0]:.2f}; engine {engine * 1e3:.0f} ms; per design):")
    for name, g in (("serial", serial), ("cluster started by the run (before)", cold),
                    (f"warm client, next run (same client: {same})", warm)):
        _row(f"{name}: generation 1", g[0] / population, engine)
        _row(f"{name}: later generations (median)", statistics.median(g[1:]) / population, engine)


def dexterity_rows(design: Design, runs: int = 1, fast_runs: int = 5) -> None:
    """Target 3: the dexterity field (resolved 1/kappa) at h = 2: the neighbour search (the default:
    a local climb from the neighbour voxel's carriage pose, with its run-time sample check), the
    pruned sweep (the resolver's exact poses) and the full search at every voxel (before). The
    engine and the neighbour search alternate ``fast_runs`` times; the sweep and the full search
    (a minute or more each) run ``runs`` times, in the same process."""
    import numpy as np

    from paraspace.kinematics.dexterity import dexterity_field

    ws = WorkspaceSettings(voxel=2.0)
    res = compute_workspace(design, ws)
    box: dict = {}

    def neighbour():
        box["f"] = dexterity_field(res, 0.005)

    # the engine three times back to back between the fields, its ratio taken against the runs that
    # follow an engine run: the first run after a field read 1.15-1.35x those (2026-11-29, 2 cores),
    # and the row took its ratio against that until then, which flattered the field
    first: list = []
    steady: list = []

    def engine_thrice():
        ts = []
        for _ in range(3):
            t = time.perf_counter()
            compute_workspace(design, ws)
            ts.append(time.perf_counter() - t)
        first.append(ts[0])
        steady.extend(ts[1:])

    _alternating({"engine x3": engine_thrice, "neighbour": neighbour}, 1)  # warm both
    first.clear()
    steady.clear()
    fast = _alternating({"engine x3": engine_thrice, "neighbour": neighbour}, fast_runs)
    slow = _alternating({"engine": lambda: compute_workspace(design, ws),
                         "sweep": lambda: box.setdefault("s", dexterity_field(res, 0.005, search="sweep")),
                         "full": lambda: dexterity_field(res, 0.005, search="full")}, runs)
    engine = statistics.median(steady)
    print(f"  target 3, dexterity field h=2, {res.voxels:,} voxels (load average {os.getloadavg()[0]:.2f}; "
          f"engine {engine * 1e3:.0f} ms: median of its {len(steady)} runs that follow an engine run, "
          f"{statistics.median(first) * 1e3:.0f} ms the first after a field, {slow['engine'] * 1e3:.0f} ms "
          f"beside the slow rows; neighbour {fast_runs} runs, sweep and full {runs} run(s) each):")
    f, s_ = box["f"], box["s"]
    c = f.check
    _row("neighbour: local climb from the neighbour's pose", fast["neighbour"], engine,
         f"(target <= 20x; sample check {c.sample_size} voxels: margin gap <= {c.max_margin_gap:.3g}, "
         f"tolerance {c.margin_tolerance:g} {'held' if c.tolerance_held else 'BROKEN'})")
    _row("sweep: the same carriage poses, bounded search", slow["sweep"], engine)
    _row("full search (bounded) at every voxel + numpy SVD (before)", slow["full"], engine)
    occ = res.occupancy
    dk = np.abs(f.inverse_condition[occ] - s_.inverse_condition[occ])
    q = np.quantile(dk, [0.5, 0.9, 0.99, 1.0])
    print(f"    neighbour vs exact poses, all voxels: |delta 1/kappa| median {q[0]:.2g}, 90 % {q[1]:.2g}, "
          f"99 % {q[2]:.2g}, max {q[3]:.2g}; GCI {f.gci:.6g} vs {s_.gci:.6g} ({f.gci - s_.gci:+.2g}); "
          f"well-conditioned volume {f.well_conditioned_volume:.4g} vs {s_.well_conditioned_volume:.4g}")


def bracket_rows(design: Design, runs: int = 3) -> None:
    """Target 6: the certified bracket alone (:func:`kinematics.bracket.bracket_of` on a computed
    workspace) at h = 2 with 0, 1 and 2 refinements, alternating with the engine, with the former
    refinement that tests each child on its own (``method="cubes"``), which must give the same
    bracket, and with every cube classified (no mirror half, the path before)."""
    import functools

    from paraspace.kinematics.bracket import bracket_of, volume_bracket
    from paraspace.kinematics.kernel_args import kernel_args

    ws = WorkspaceSettings(voxel=2.0)
    res = compute_workspace(design, ws)
    args = kernel_args(design, ws.orientation, res.n_eta, ws.joints)
    sym = ws.mirror_symmetric(design)

    def per_child(refine: int):
        return volume_bracket(design, res.grid, args, res.n_eta, ws.z_floor, refine=refine, method="cubes",
                              symmetric=sym)

    def every_cube(refine: int):
        return volume_bracket(design, res.grid, args, res.n_eta, ws.z_floor, refine=refine)

    same = all(bracket_of(res, refine=r) == per_child(r) for r in (1, 2))  # also compiles both
    fns = {"engine": lambda: compute_workspace(design, ws)}
    fns.update({f"refine {r}": functools.partial(bracket_of, res, refine=r) for r in (0, 1, 2)})
    fns.update({f"cubes {r}": functools.partial(per_child, r) for r in (1, 2)})
    fns.update({f"full {r}": functools.partial(every_cube, r) for r in (0, 2)})
    med = _alternating(fns, runs)
    half, full = bracket_of(res, refine=2), every_cube(2)
    print(f"  target 6, certified bracket h=2 (load average {os.getloadavg()[0]:.2f}; "
          f"engine {med['engine'] * 1e3:.0f} ms; the same bracket both refinement methods: {same}; mirror half: "
          f"{sym}, refine 2 [{half.volume_inner:.6g}, {half.volume_outer:.6g}] vs every cube "
          f"[{full.volume_inner:.6g}, {full.volume_outer:.6g}]):")
    for r in (0, 1, 2):
        _row(f"bracket, refine {r}", med[f"refine {r}"], med["engine"], "(target <= 10x)" if r == 2 else "")
    for r in (1, 2):
        _row(f"bracket, refine {r}, each child alone", med[f"cubes {r}"], med["engine"])
    for r in (0, 2):
        _row(f"bracket, refine {r}, every cube (before)", med[f"full {r}"], med["engine"])


def cuda_rows(design: Design, runs: int = 5) -> None:
    """Target 11: the CUDA backend's dense test (:mod:`kinematics.cuda_dense`) at h = 2, 1 and 0.5
    against the CPU's blocks engine on the same design, alternating, with whether the voxels are the
    same; a line saying why where the machine has no GPU (or no CuPy)."""
    from paraspace.kinematics.cuda_dense import cuda_unavailable

    why = cuda_unavailable()
    if why is not None:
        print(f"  target 11, CUDA backend: not measured here: {why}")
        return
    for h in (2.0, 1.0, 0.5):
        ws = WorkspaceSettings(voxel=h)
        cpu, gpu = compute_workspace(design, ws), compute_workspace(design, ws, backend="cuda")  # also compiles
        same = gpu.grid == cpu.grid and bool((gpu.occupancy == cpu.occupancy).all())
        med = _alternating({"engine": lambda ws=ws: compute_workspace(design, ws),
                            "cuda": lambda ws=ws: compute_workspace(design, ws, backend="cuda")}, runs)
        print(f"  target 11, CUDA backend h={h:g} (load average {os.getloadavg()[0]:.2f}; the same voxels: {same}; "
              f"{cpu.voxels} of {cpu.occupancy.size}):")
        _row(f"cuda dense test h={h:g} (with the bounds' scout and the copy back)", med["cuda"], med["engine"])


def total_orientation_rows(design: Design, runs: int = 3) -> None:
    """Target 5: the total-orientation workspace 15/15 deg (step 5, 657 orientations) at h = 4:
    blocks excluded by the hardest orientations and voxels certified from their neighbour's cut of
    the orientation tree (the default, kinematics/orientation_blocks.py), the per-voxel orientation
    tree (before) and every orientation tested per pair; medians of alternating runs, wall and CPU
    seconds (the CPU ratio is steadier on a loaded machine)."""
    from paraspace.kinematics.dexterous import total_orientation_workspace

    ws = WorkspaceSettings(voxel=4.0)
    pos = compute_workspace(design, ws)
    total_orientation_workspace(design, 15.0, 15.0, 5.0, ws, pos)  # compile
    total_orientation_workspace(design, 15.0, 15.0, 5.0, ws, pos, method="tree")

    def run(method: str):
        return total_orientation_workspace(design, 15.0, 15.0, 5.0, ws, pos, method=method)

    fns = {"engine": lambda: compute_workspace(design, ws), "blocks": lambda: run("blocks"),
           "tree": lambda: run("tree"), "pairs": lambda: run("pairs")}
    wall: dict = {k: [] for k in fns}
    cpu: dict = {k: [] for k in fns}
    for _ in range(runs):
        for k, f in fns.items():
            t, c = time.perf_counter(), time.process_time()
            f()
            wall[k].append(time.perf_counter() - t)
            cpu[k].append(time.process_time() - c)
    med = {k: statistics.median(v) for k, v in wall.items()}
    mcpu = {k: statistics.median(v) for k, v in cpu.items()}
    print(f"  target 5, total orientation 15/15 deg h=4, {run('blocks').samples.shape[0]} orientations "
          f"(load average {os.getloadavg()[0]:.2f}; engine {med['engine'] * 1e3:.0f} ms, "
          f"{mcpu['engine'] * 1e3:.0f} ms CPU):")
    for k, name in (("blocks", "blocks x neighbour's cut (now)"), ("tree", "orientation tree per voxel (before)"),
                    ("pairs", "every orientation per pair")):
        _row(name, med[k], med["engine"], f"CPU x{mcpu[k] / mcpu['engine']:6.2f}" + (" (target <= 20x)"
                                                                                      if k == "blocks" else ""))


@contextlib.contextmanager
def _per_voxel_interference():
    """The engine's leg interference on its former path (before issue 24): the witness search of
    kinematics/interference.py at every voxel the chains reach."""
    import numpy as np

    from paraspace.kinematics import workspace
    from paraspace.kinematics.interference import interference_free

    def per_voxel(design, joints, axes, h, rot, n_eta, where, cancel=None, mirror=False):
        # every voxel, mirror or not
        idx = np.argwhere(where)
        out = np.zeros(where.shape, bool)
        pts = np.stack([axes[a][idx[:, a]] for a in range(3)], axis=1)
        out[idx[:, 0], idx[:, 1], idx[:, 2]] = interference_free(design, joints, pts, rot[None], n_eta)[:, 0]
        return out

    saved = workspace.interference_free_grid
    workspace.interference_free_grid = per_voxel
    try:
        yield
    finally:
        workspace.interference_free_grid = saved


def interference_rows(design: Design, runs: int = 3) -> None:
    """Target 4: the engine with leg interference (diameter 10) at h = 2 and h = 1, blocks decided
    with Lipschitz bounds (kinematics/interference_blocks.py) and the former per-voxel search."""
    import numpy as np

    from paraspace.kinematics.joints import Joints

    for h in (2.0, 1.0):
        plain = WorkspaceSettings(voxel=h)
        legs = WorkspaceSettings(voxel=h, joints=Joints(leg_diameter=10.0))

        def old(legs=legs):
            with _per_voxel_interference():
                return compute_workspace(design, legs)

        same = np.array_equal(old().occupancy, compute_workspace(design, legs).occupancy)
        med = _alternating({"engine": lambda s=plain: compute_workspace(design, s),
                            "new": lambda s=legs: compute_workspace(design, s), "old": old}, runs)
        print(f"  target 4, leg interference (diameter 10) h={h:g} (load average {os.getloadavg()[0]:.2f}; "
              f"engine {med['engine'] * 1e3:.0f} ms; identical voxels: {same}):")
        _row("engine + interference, blocks", med["new"], med["engine"], "(target <= 4x at h = 1)")
        _row("engine + interference, per voxel (before)", med["old"], med["engine"])


class _StageClock:
    """Exclusive seconds per stage: each patched callable's time less that of the patched callables it
    calls (a stack), summed per label over every call while the clock is on."""

    def __init__(self, patches: list) -> None:
        self.patches, self.saved, self.times, self.stack = patches, [], {}, []

    def _wrap(self, label: str, fn):
        def timed(*a, **k):
            self.stack.append(0.0)
            t = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                dt = time.perf_counter() - t
                inner = self.stack.pop()
                self.times[label] = self.times.get(label, 0.0) + dt - inner
                if self.stack:
                    self.stack[-1] += dt
        return timed

    def __enter__(self):
        for obj, attr, label in self.patches:
            fn = getattr(obj, attr)
            self.saved.append((obj, attr, fn))
            setattr(obj, attr, self._wrap(label, fn))
        return self

    def __exit__(self, *exc) -> None:
        for obj, attr, fn in reversed(self.saved):
            setattr(obj, attr, fn)


class _KernelClock:
    """Seconds spent inside numba's parallel kernels while the clock is on: every ``parallel=True``
    dispatcher bound in a module of ``paraspace.kinematics`` is wrapped (in each module that binds
    it) by a timer. The rest of a one-thread run is single-threaded code (numpy, scipy's qhull,
    serial kernels, Python) whatever the machine's load: target 7's direct measure."""

    def __init__(self) -> None:
        self.seconds, self.saved = 0.0, []

    def _wrap(self, fn):
        def timed(*a, **k):
            t = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                self.seconds += time.perf_counter() - t
        return timed

    def __enter__(self):
        import sys
        for name, mod in list(sys.modules.items()):
            if not name.startswith("paraspace.kinematics"):
                continue
            for attr, fn in list(vars(mod).items()):
                if hasattr(fn, "py_func") and getattr(fn, "targetoptions", {}).get("parallel"):
                    self.saved.append((mod, attr, fn))
                    setattr(mod, attr, self._wrap(fn))
        return self

    def __exit__(self, *exc) -> None:
        for mod, attr, fn in reversed(self.saved):
            setattr(mod, attr, fn)


#: Stage label of the per-level bookkeeping (a parallel kernel since target 7; its serial share is
#: estimated by Amdahl's law like a measure step's, not assumed 0).
ADVANCE = "_advance: write decided blocks, split (parallel)"


def stage_rows(design: Design, h: float = 0.5, runs: int = 5) -> None:
    """Target 7: each stage of the engine (bounds scout, block classification per level, the serial
    per-level bookkeeping ``_advance``, the fused mirror/``== 7`` pass, Python glue) and of
    ``measure_workspace`` (each step of ``_Steps``, exclusive of the steps it calls) at ``h``, with 1
    and 2 numba threads (medians of alternating runs), and the single-threaded share of the 1-thread
    time: the stages that are serial code (glue; ``_advance`` and each measure step by Amdahl's
    law from its 1- and 2-thread times, ``s = 2 t2 / t1 - 1`` clipped to [0, 1]). Other work on a
    shared machine only adds time, and more to the 2-thread runs (they need both cores), so the
    share is printed from the medians and from each stage's fastest runs (the least disturbed).
    The direct measure, which the load does not bias: in the 1-thread runs, the time outside
    numba's parallel kernels (:class:`_KernelClock`), per stage and in all."""
    import numba

    from paraspace.kinematics import blocks, measures, workspace
    from paraspace.kinematics.measures import measure_workspace

    ws = WorkspaceSettings(voxel=h)
    res = compute_workspace(design, ws)
    measure_workspace(res)
    eng_patch = [(workspace, "default_bounds", "bounds scout (blocks engine on a coarse grid)"),
                 (blocks, "_classify_kernel", "classify blocks (parallel kernel)"),
                 (blocks, "_advance", ADVANCE),
                 (workspace, "_finish_kernel", "mirror fill + == 7 (parallel kernel)")]
    meas_patch = [(measures._Steps, "get", None)]
    per: dict = {}
    outside: dict = {}  # 1-thread runs: seconds outside the parallel kernels, per stage
    for n in (1, 2) * runs:
        numba.set_num_threads(n)
        kernels = _KernelClock() if n == 1 else contextlib.nullcontext()
        with kernels:
            clock = _StageClock(eng_patch)
            with clock:
                t = time.perf_counter()
                compute_workspace(design, ws)
                total = time.perf_counter() - t
            eng_kernels = kernels.seconds if n == 1 else 0.0
            clock.times["Python glue (serial)"] = total - sum(clock.times.values())
            clock.times["engine total"] = total
            steps: dict = {}
            serial: dict = {}
            get = measures._Steps.get

            def timed_get(self, name, steps=steps, serial=serial, get=get, stack=[], kernels=kernels):  # noqa: B006
                if name in self._memo:
                    return get(self, name)
                k0 = kernels.seconds if n == 1 else 0.0
                stack.append([0.0, 0.0])
                t0 = time.perf_counter()
                out = get(self, name)
                dt = time.perf_counter() - t0
                dk = (kernels.seconds if n == 1 else 0.0) - k0
                inner, inner_k = stack.pop()
                key = "measures: " + name
                steps[key] = steps.get(key, 0.0) + dt - inner
                serial[key] = serial.get(key, 0.0) + (dt - inner) - (dk - inner_k)
                if stack:
                    stack[-1][0] += dt
                    stack[-1][1] += dk
                return out

            measures._Steps.get = timed_get  # type: ignore[method-assign]
            try:
                t = time.perf_counter()
                k0 = kernels.seconds if n == 1 else 0.0
                measure_workspace(res)
                mtotal = time.perf_counter() - t
                meas_kernels = (kernels.seconds if n == 1 else 0.0) - k0
            finally:
                measures._Steps.get = get  # type: ignore[method-assign]
        steps["measures: outside the steps"] = mtotal - sum(steps.values())
        steps["measures total"] = mtotal
        for k, v in {**clock.times, **steps}.items():
            per.setdefault(k, {1: [], 2: []})[n].append(v)
        if n == 1:
            serial["measures: outside the steps"] = (mtotal - meas_kernels) - sum(serial.values())
            serial["engine total"] = total - eng_kernels
            serial["measures total"] = mtotal - meas_kernels
            for k, v in serial.items():
                outside.setdefault(k, []).append(v)
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    del meas_patch
    med = {k: {n: statistics.median(v[n]) for n in (1, 2)} for k, v in per.items()}
    low = {k: {n: min(v[n]) for n in (1, 2)} for k, v in per.items()}
    print(f"  target 7, stages at h={h:g} ({res.grid.size:,} voxels; {runs} alternating runs per thread count; load "
          f"average {os.getloadavg()[0]:.2f}, a loaded 2-core machine: read the 2-thread column as indicative):")

    def share(k: str, t: dict) -> float:
        t1, t2 = t[1], t[2]
        if k in ("engine total", "measures total"):
            return float("nan")
        if k == "Python glue (serial)":
            return 1.0
        if k.startswith("measures:") or k == ADVANCE:
            return min(1.0, max(0.0, 2.0 * t2 / t1 - 1.0)) if t1 > 0 else 0.0
        return 0.0

    totals = {}
    for name, table in (("medians", med), ("fastest runs", low)):
        one = table["engine total"][1] + table["measures total"][1]
        totals[name] = sum(share(k, v) * v[1] for k, v in table.items() if share(k, v) == share(k, v)) / one
    for k, v in med.items():
        sm, sl = share(k, v), share(k, low[k])
        cell = "" if sm != sm else f"{sm:.2f} / {sl:.2f}"
        print(f"    {k:<52} 1 thread {v[1] * 1e3:8.1f} ms   2 threads {v[2] * 1e3:8.1f} ms   serial share "
              f"(medians / fastest) {cell}")
    print(f"    single-threaded share of the 1-thread time (engine + measures): {totals['medians']:.1%} from the "
          f"medians, {totals['fastest runs']:.1%} from the fastest runs (target < 10 %)")
    out_med = {k: statistics.median(v) for k, v in outside.items()}
    one = med["engine total"][1] + med["measures total"][1]
    direct = (out_med["engine total"] + out_med["measures total"]) / one
    top = sorted(((v, k) for k, v in out_med.items() if k.startswith("measures: ")), reverse=True)[:4]
    print(f"    direct: time outside numba's parallel kernels in the 1-thread runs, engine {out_med['engine total'] * 1e3:.1f}"
          f" ms + measures {out_med['measures total'] * 1e3:.1f} ms = {direct:.1%} of the 1-thread time (target < 10 %);"
          f" the largest: " + ", ".join(f"{k[10:]} {v * 1e3:.1f} ms" for v, k in top))


#: The groups of rows of ``--throughput``, in the order they run (``--rows`` picks some).
THROUGHPUT_ROWS = {
    "shell": shell_rows, "evaluation": evaluation_rows, "measures": measure_rows, "meas1": measure_meas1_rows,
    "measure-stages": measure_stage_rows, "feature-filter": feature_filter_rows, "tail": tail_rows,
    "display": display_rows, "optimizer": lambda _design: optimizer_cluster_rows(),
    "interference": interference_rows, "stages": stage_rows, "total-orientation": total_orientation_rows,
    "bracket": bracket_rows, "dexterity": dexterity_rows, "cuda": cuda_rows,
}


def throughput_rows(design: Design, rows: Sequence[str] = tuple(THROUGHPUT_ROWS)) -> None:
    """Item 7 of the module docstring (``rows``: the groups of :data:`THROUGHPUT_ROWS` to run)."""
    print(f"\nissue 24, throughput as ratios to the plain engine (load average {os.getloadavg()[0]:.2f}, "
          f"{os.cpu_count()} CPUs):")
    for name in rows:
        THROUGHPUT_ROWS[name](design)


def preset_rows(h: float = 2.0, runs: int = 5) -> None:
    """Item 7 of the module docstring."""
    import numpy as np

    from paraspace.kinematics.mechanism_workspace import compute_general_workspace, compute_mechanism_workspace
    from paraspace.kinematics.presets import PRESETS, preset

    design = Design()
    plain = WorkspaceSettings(voxel=h)
    ref = compute_workspace(design, plain)
    on_grid = WorkspaceSettings(voxel=h, bounds=(ref.grid.lo, ref.grid.hi))
    rows = {"paper engine, default design": lambda: compute_workspace(design, plain)}
    rows["paper engine, dense"] = lambda: compute_workspace(design, WorkspaceSettings(voxel=h, method="dense"))
    rows["paper preset (routed)"] = lambda: compute_mechanism_workspace(preset("paper"), plain)
    rows["paper preset, general engine"] = lambda: compute_general_workspace(preset("paper"), on_grid)
    dense_grid = WorkspaceSettings(voxel=h, bounds=(ref.grid.lo, ref.grid.hi), method="dense")
    rows["paper preset, general dense"] = lambda: compute_general_workspace(preset("paper"), dense_grid)
    for name in PRESETS:
        if name != "paper":
            rows[name] = lambda name=name: compute_mechanism_workspace(preset(name), plain)
    for fn in rows.values():
        fn()  # compile
    times: dict[str, list[float]] = {k: [] for k in rows}
    out = {}
    for _ in range(runs):  # alternate so drift hits every row
        for k, fn in rows.items():
            out[k] = fn()
            times[k].append(out[k].compute_seconds)
    base = statistics.median(times["paper engine, default design"])
    for k in rows:
        t, res = statistics.median(times[k]), out[k]
        extra = ""
        if k.startswith("paper preset") or k == "paper engine, dense":
            extra = f"  identical voxels: {bool(np.array_equal(res.occupancy, ref.occupancy))}"
        samples = getattr(res, "samples", ())
        print(f"  {k:<30} {t * 1e3:8.1f} ms  x{t / base:5.2f}  {res.grid.size:>10,} voxels in the box  "
              f"volume {res.volume:.5g}  carriage samples/chain {max(samples) if samples else res.n_eta}{extra}")


POLICIES = ("equal split", "chunks", "chunks+load")


@contextlib.contextmanager
def _thread_policy(name: str):
    """``"equal split"``: numba's default one slice per thread, and the orientation scan's pair-by-pair
    kernel (kinematics.workspace.reachable_pairs) -- the state before kinematics.parallel's chunks and
    kinematics.line_scan; ``"chunks"``: chunked launches and the line scan, every thread always;
    ``"chunks+load"``: today's default (and one thread while other tasks fill every core)."""
    from paraspace.kinematics import orientation, parallel
    from paraspace.kinematics.workspace import reachable_pairs

    saved = parallel.DEFAULT_CHUNK, parallel.LOAD_RULE, orientation.reachable_along
    parallel.LOAD_RULE = name == "chunks+load"
    if name == "equal split":
        parallel.DEFAULT_CHUNK = 0
        orientation.reachable_along = reachable_pairs
    try:
        yield
    finally:
        parallel.DEFAULT_CHUNK, parallel.LOAD_RULE, orientation.reachable_along = saved


def thread_rows(design: Design, runs: int = 7) -> None:
    """Item 6 of the module docstring: medians of ``runs`` alternating runs of every (policy, threads)
    configuration, so that drift in the machine's load hits all of them alike."""
    import numba

    from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace

    work = {"blocks h=2": lambda: compute_workspace(design, WorkspaceSettings(voxel=2.0)),
            "dense h=2": lambda: compute_workspace(design, WorkspaceSettings(voxel=2.0, method="dense")),
            "orientation indices": lambda: orientation_workspace(design, OrientationSettings())}
    policies = POLICIES
    configs = [(p, n) for p in policies for n in (1, 2)]
    for p in policies:
        with _thread_policy(p):
            for f in work.values():
                f()  # compile
    for loaded in (False, True):
        stop = multiprocessing.Event()
        spinner = None
        if loaded:
            spinner = multiprocessing.Process(target=_spin, args=(stop,), daemon=True)
            spinner.start()
            time.sleep(0.3)
        print(f"  {'with a second process busy on one core' if loaded else 'idle'} "
              f"(load average {os.getloadavg()[0]:.2f}, OMP_WAIT_POLICY={os.environ.get('OMP_WAIT_POLICY')}, "
              f"layer {numba.threading_layer()}):")
        for name, f in work.items():
            times: dict = {c: [] for c in configs}
            for _ in range(runs):
                for p, n in configs:
                    numba.set_num_threads(n)
                    with _thread_policy(p):
                        t = time.perf_counter()
                        f()
                        times[(p, n)].append(time.perf_counter() - t)
            numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
            med = {c: statistics.median(v) for c, v in times.items()}
            for p in policies:
                print(f"    {name:<20} {p:<12} 1 thread {med[(p, 1)] * 1e3:8.1f} ms   2 threads "
                      f"{med[(p, 2)] * 1e3:8.1f} ms   ratio {med[(p, 1)] / med[(p, 2)]:.2f}")
            print(f"    {name:<20} 2 threads, today vs equal split: {med[('equal split', 2)] / med[POLICIES[-1], 2]:.2f}x")
        if spinner is not None:
            stop.set()
            spinner.join(2)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--voxel", type=float, default=4.0, help="grid of the engine-vs-numpy comparison")
    ap.add_argument("--skip-converged", action="store_true")
    ap.add_argument("--no-load", action="store_true", help="skip the rows under a second busy process")
    ap.add_argument("--only-v2", action="store_true", help="only the engine-v2 rows")
    ap.add_argument("--options", action="store_true", help="only the option-cost rows (item 5)")
    ap.add_argument("--threads", action="store_true", help="only the thread rows (item 6)")
    ap.add_argument("--task", action="store_true", help="only the task rows (item 7)")
    ap.add_argument("--throughput", action="store_true", help="only the issue-24 throughput rows (item 8)")
    ap.add_argument("--presets", action="store_true", help="only the mechanism-preset rows (item 9)")
    ap.add_argument("--total-orientation", action="store_true",
                    help="only the total-orientation row of the throughput rows (item 8, target 5)")
    ap.add_argument("--serial-tail", action="store_true",
                    help="only the stage rows of the engine and the measures at h = 0.5 (item 8, target 7)")
    ap.add_argument("--measure-stages", action="store_true",
                    help="only the measure_workspace stage rows, before/after meas2 (item 8, target 1)")
    ap.add_argument("--rows", default=None,
                    help="with --throughput: only these groups, comma-separated, of " + ",".join(THROUGHPUT_ROWS))
    ns = ap.parse_args()
    rows = tuple(THROUGHPUT_ROWS) if ns.rows is None else tuple(r.strip() for r in ns.rows.split(",") if r.strip())
    unknown = [r for r in rows if r not in THROUGHPUT_ROWS]
    if unknown:
        ap.error(f"--rows: unknown group(s) {', '.join(unknown)}; valid: {', '.join(THROUGHPUT_ROWS)}")
    design = Design()
    print(f"compile/warm-up: {warm_up():.2f} s (numba cache on disk makes later starts fast)")
    if ns.task:
        print(f"\ntask against the plain workspace, default design (load average {os.getloadavg()[0]:.2f}):")
        task_rows(design)
    if ns.total_orientation:
        print(f"\nissue 24 target 5 (load average {os.getloadavg()[0]:.2f}, {os.cpu_count()} CPUs):")
        total_orientation_rows(design)
        return
    if ns.serial_tail:
        print(f"\nissue 24 target 7 (load average {os.getloadavg()[0]:.2f}, {os.cpu_count()} CPUs):")
        stage_rows(design)
        return
    if ns.measure_stages:
        print(f"\nissue 24 target 1, measure_workspace by stage (load average {os.getloadavg()[0]:.2f}):")
        measure_stage_rows(design)
        return
    if ns.throughput:
        throughput_rows(design, rows)
    if ns.presets:
        print(f"\nmechanism presets at h = 2, derived bounds (load average {os.getloadavg()[0]:.2f}):")
        preset_rows()
    if ns.task or ns.throughput or ns.presets:
        return
    if ns.options or ns.threads:
        if ns.options:
            print(f"\noption costs at h = 2, default design (load average {os.getloadavg()[0]:.2f}):")
            option_rows(design)
        if ns.threads:
            print(f"\none thread against two (load average {os.getloadavg()[0]:.2f}):")
            thread_rows(design)
        return
    print(f"\nengine v2 vs dense, paper default design, derived bounds (load average {os.getloadavg()[0]:.2f}):")
    engine_v2_rows(design)
    if not ns.no_load:
        stop = multiprocessing.Event()
        spinner = multiprocessing.Process(target=_spin, args=(stop,), daemon=True)
        spinner.start()
        try:
            print("  ... with a second process busy on one core:")
            engine_v2_rows(design)
        finally:
            stop.set()
            spinner.join(5)
    if ns.only_v2:
        return

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

    throughput_rows(design)

    if not ns.skip_converged:
        conv = compute_workspace(design, WorkspaceSettings(voxel=1.0, eta_step=0.125, bounds=BOX))
        v2 = compute_workspace(design, WorkspaceSettings(voxel=2.0, bounds=BOX)).volume
        print(f"\nconverged reference (h=1, eta step 0.125 deg): volume={conv.volume:.6g} in {conv.compute_seconds:.2f} s")
        print(f"  default h=2, eta step 0.5: relative error {abs(v2 - conv.volume) / conv.volume * 100:.3f} % (target <= 0.3 %)")


if __name__ == "__main__":
    main()
