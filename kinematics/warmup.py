"""Compile every numba kernel a request can reach, once, before the first request.

numba compiles a kernel on its first call (tens of seconds on a busy machine) and keeps the
machine code in its on-disk cache (``cache=True`` on every kernel): a later process loads it in
about a second. A server therefore calls :func:`warm_up` at start-up (in a background thread, with
a line on the console when it is done), so that no request waits on a compile; the test suite's
fixtures call it before they send a request.

"Every kernel a request can reach" is every entry point of the core on a tiny problem, one
:data:`STEPS` entry each: the workspace engines (blocks and dense, with diagnostics, the certified
bracket, refined as the explorer and the API refine it, and the mirror), the per-point test with
and without joint cones about both axes and with leg interference, the redundancy resolution with
joints (the explorer's pose panel and ``/ik``), the orientation line scan, the total-orientation
workspace (blocks and tree methods), the task answers (region and pose list: the certification and
pose kernels), the dexterity field, the measures, the shell and the display shell of a result, and
the general engine of a mechanism description (:mod:`kinematics.mechanism_workspace`) with its
orientation scan.

The steps are independent (each builds its own tiny problem), so that several processes can share
the compile into the same on-disk cache: :func:`run_unclaimed` runs the steps no process has claimed
yet in a shared folder, a step at a time, and :func:`steps_done` says when all of them are done (the
test suite's workers and its helper process do: ``tests/conftest.py``).

What the first compile costs, and why the helpers are ``forceinline=True``. numba's own inlining
(``inline="always"``) types a copy of the helper's code at every call site, and the caller's passes
(a parallel kernel's most of all) then run over every copy: measured per pass, ``inline_inlinables``
took 12.4 of ``feasibility._feasible_at``'s 15.0 s and 8.5 of ``bracket_children._parent_flags``'s
10.6 s. A helper marked ``forceinline=True`` is compiled once and inlined by LLVM (its
``alwaysinline``), after which numba prunes the reference counts of the inlined calls as before. So
the helpers of every module are ``forceinline=True``, except in the three whose loops decide the
bracket's children and the leg interference (``bracket_children``, ``interference``,
``interference_blocks``): there numba's inlining stays for the helpers that had it, since with
LLVM's inlining everywhere (and every other function pinned as a call, ``forceinline=False``) the
bracket (refine 2, h = 2) took 529-558 ms against 420-448 ms, one process of each alternating, three
times (load 1-2); without the pinning the bracket's times were within the host's noise, neither
faster nor clearly slower. On a fresh cache, in one process on the shared 2-core machine, the
warm-up compiled in 326 s of one core with numba's inlining everywhere and in 250 s with it in
those three modules only (2026-12-05; ``benchmarks/THROUGHPUT.md``, twentieth round). The leg
interference's functions that were calls of their own (the segment distance, the witness scans, the
per-voxel search, the blocks' clear certificate, its walks and bounds) are ``forceinline=True``
too: the engine with leg interference at h = 1 took 0.84 of its time (430 against 514 ms, medians
of three processes of each alternating, load 1.1-1.3; the same voxels), for about 8 s more of
its first compile (twenty-first round). numba passes a caller's
``forceinline`` to a plain function it compiles for it, so such a function may be inlined too: its
code, not its results, depends on which caller compiled it first.
"""

from __future__ import annotations

import os
import pathlib
import threading
import time
from collections.abc import Callable

import numpy as np

from .design import Design
from .joints import Joints
from .parallel import KERNEL_LOCK
from .pose import Pose

__all__ = ["STEPS", "warm_up", "is_warm", "run_unclaimed", "steps_done"]

_lock = threading.Lock()
_warm = False
_BOX = ((-100.0, -100.0, 0.0), (100.0, 100.0, 160.0))


def _tiny_result():  # noqa: ANN202 - a WorkspaceResult (imported lazily)
    """A small result built by hand (a 5 x 5 x 5 block of voxels with voids), so that a step that
    needs a result does not compile the engine: a process sharing the warm-up leaves that to the one
    that claimed the engines (:func:`run_unclaimed`)."""
    from .feasibility import default_n_eta
    from .grid import GridSpec
    from .workspace import WorkspaceResult, WorkspaceSettings

    h, lo, shape = 40.0, _BOX[0], (7, 7, 6)
    settings = WorkspaceSettings(voxel=h, bounds=_BOX)
    grid = GridSpec(origin=tuple(a + 0.5 * h for a in lo), h=h, shape=shape)
    occ = np.zeros(shape, bool)
    occ[1:6, 1:6, 0:5] = True  # on the floor, with the measures' void paths:
    occ[4, 4, 1] = False  # a sealed void,
    occ[2, 2, 3:5] = False  # a bent tunnel from the top, whose end (3, 2, 3) is enclosed along every axis
    occ[3, 2, 3] = False  # but leaks (the flood from the candidates that leak),
    occ[5, 1:3, 4] = False  # and an open notch
    return WorkspaceResult(design=Design(), settings=settings, grid=grid, occupancy=occ, chain_mask=None,
                           compute_seconds=0.0, n_eta=default_n_eta(Design(), settings.eta_step))


def _tiny_mirror_result():  # noqa: ANN202 - a WorkspaceResult
    """A small result symmetric under ``y -> -y`` (grid and voxels), by hand like :func:`_tiny_result`:
    the dexterity field's mirror path (:func:`kinematics.dexterity_neighbour.mirror_rows`)."""
    import dataclasses

    res = _tiny_result()
    h = res.grid.h
    grid = dataclasses.replace(res.grid, origin=(res.grid.origin[0], -3 * h, res.grid.origin[2]))
    occ = np.zeros(res.grid.shape, bool)
    occ[1:6, 1:6, 0:4] = True  # symmetric about the middle row j = 3 (y = 0)
    return dataclasses.replace(res, grid=grid, occupancy=occ)


def _engines() -> None:
    from .workspace import WorkspaceSettings, compute_workspace

    d = Design()
    compute_workspace(d, WorkspaceSettings(voxel=40.0, bounds=_BOX))
    compute_workspace(d, WorkspaceSettings(voxel=40.0, bounds=_BOX, diagnostics=True, bracket=True))
    compute_workspace(d, WorkspaceSettings(voxel=40.0, bounds=_BOX, method="dense"))


def _joints() -> None:
    from .redundancy import resolve_redundancy
    from .workspace import WorkspaceSettings, compute_workspace, reachable

    d = Design()
    pts = np.array([[0.0, 0.0, 130.0], [10.0, 5.0, 120.0]])
    for joints in (Joints(), Joints(theta_u=45.0, theta_s=45.0), Joints(theta_u=30.0, cone_axis="home"),
                   Joints(leg_diameter=10.0, clearance=1.0)):
        reachable(d, pts, (0.0, 0.0, 0.0), joints=joints)
        reachable(d, pts, (5.0, 3.0, 2.0), joints=joints)
        resolve_redundancy(d, Pose(z=130.0), joints)
        compute_workspace(d, WorkspaceSettings(voxel=40.0, bounds=_BOX, joints=joints))


def _bracket() -> None:
    from .bracket import bracket_of

    res = _tiny_result()
    for refine in (1, 2):  # the explorer's and the API's refinements
        bracket_of(res, refine=refine)


def _orientation() -> None:
    from .orientation import OrientationSettings, orientation_workspace

    orientation_workspace(Design(), OrientationSettings(angle_step=30.0, position_step=40.0))


def _total_orientation() -> None:
    from .dexterous import total_orientation_workspace
    from .workspace import WorkspaceSettings

    d, ws = Design(), WorkspaceSettings(voxel=40.0, bounds=_BOX)
    for method in ("blocks", "tree"):
        total_orientation_workspace(d, 15.0, 15.0, step=15.0, settings=ws, method=method)


def _task() -> None:
    from .task import OrientationSet, PoseList, Region, TaskSettings, pose_list_task, region_task

    d, coarse = Design(), TaskSettings(voxel=8.0, margin_range=8.0)
    region_task(d, Region("sphere", (0.0, 0.0, 130.0), (4.0,)), OrientationSet(tilt=5.0), coarse)
    region_task(d, Region("box", (0.0, 0.0, 165.0), (10.0, 10.0, 10.0)), OrientationSet(), coarse)
    pose_list_task(d, PoseList(np.array([[0.0, 0.0, 130.0, 0.0, 0.0, 0.0], [0.0, 0.0, 400.0, 0.0, 0.0, 0.0]])),
                   coarse)


def _dexterity() -> None:
    from .dexterity import dexterity_field

    res = _tiny_result()
    for search in ("neighbour", "sweep"):  # the full search's kernels: the neighbour's run-time check
        dexterity_field(res, search=search)
    dexterity_field(_tiny_mirror_result())  # the mirror fill (every symmetric design at zero orientation)


def _measures_and_shells() -> None:
    from .display_mesh import display_shell
    from .measures import measure_workspace
    from .run_components import RunComponents
    from .shell import workspace_shell

    res = _tiny_result()
    measure_workspace(res)
    # the feature filter's packed dilations run only for a radius of at least one voxel (the tiny
    # result's default radius is under one), as on every real grid
    measure_workspace(res, feature_radius=2.5 * res.grid.h)
    RunComponents(np.ones((2, 2, 2), bool)).mask(np.ones(1, bool))  # the pieces' mask: only with fragments
    workspace_shell(res)
    display_shell(res)
    # over their face budgets (as every real grid is): the block re-mesh, its block means from the
    # summed-volume table (workspace_shell) and counted over a uint8 occupancy (display_shell)
    workspace_shell(res, max_faces=24, reduction="remesh")
    display_shell(res, max_faces=24)


def _general() -> None:
    from .mechanism_orientation import mechanism_orientation_workspace
    from .mechanism_workspace import warm_up_general
    from .orientation import OrientationSettings
    from .presets import six_pups

    warm_up_general()
    mechanism_orientation_workspace(six_pups(), OrientationSettings(angle_step=30.0, position_step=40.0))


#: The warm-up, in the order :func:`warm_up` runs it and :func:`run_unclaimed` claims it:
#: ``(name, step)``. On a cold cache they compile for about 250 s of one core in all (the module
#: docstring; 326 s before the helpers were ``forceinline``, 413 s on a slow hour of the shared host:
#: benchmarks/THROUGHPUT.md, sixteenth and twentieth rounds, list the longest kernels).
STEPS: tuple[tuple[str, Callable[[], None]], ...] = (
    ("engines", _engines), ("joints", _joints), ("orientation", _orientation), ("bracket", _bracket),
    ("task", _task), ("total orientation", _total_orientation), ("dexterity", _dexterity),
    ("measures and shells", _measures_and_shells), ("general mechanism", _general),
)


def is_warm() -> bool:
    """Whether :func:`warm_up` has run to its end in this process."""
    return _warm


def _slug(name: str) -> str:
    return name.replace(" ", "-")


def run_unclaimed(folder: pathlib.Path, backwards: bool = False) -> list[str]:
    """Claim and run, one at a time in :data:`STEPS` order (from the last one when ``backwards``),
    each step that no process has claimed in ``folder`` (a file ``<step>.claimed`` created
    exclusively there), marking it done (``<step>.done``) after it; returns the names this process
    ran. Several processes calling it on one folder share the compile, each taking the next step as
    soon as it is free. Steps next to each other share kernels (the engines, the joints, the bracket),
    so one process should go forwards and the others backwards: two processes compiling the same
    kernel at once would each pay for it."""
    folder.mkdir(parents=True, exist_ok=True)
    ran = []
    for name, step in (reversed(STEPS) if backwards else STEPS):
        try:
            os.close(os.open(folder / f"{_slug(name)}.claimed", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        except FileExistsError:
            continue
        try:
            step()
        finally:
            (folder / f"{_slug(name)}.done").touch()
        ran.append(name)
    return ran


def steps_done(folder: pathlib.Path) -> bool:
    """Whether every step of :data:`STEPS` is marked done in ``folder`` (:func:`run_unclaimed`)."""
    return all((folder / f"{_slug(name)}.done").exists() for name, _ in STEPS)


def warm_up() -> float:
    """Compile (or load from numba's cache) every kernel requests reach; returns the seconds it
    took (0 when already done in this process). Thread-safe: concurrent callers wait for one run."""
    global _warm
    t0 = time.perf_counter()
    with _lock:
        if _warm:
            return 0.0
        with KERNEL_LOCK.background():  # a request's launches go first (kinematics/parallel.py)
            for _name, step in STEPS:
                step()
        _warm = True
    return time.perf_counter() - t0
