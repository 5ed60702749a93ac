"""What the explorer's workspace job computes: engine -> measures -> display mesh (no GUI here).

On the data path slider -> state -> job -> engine -> mesh -> scene this module is "job -> engine ->
mesh": :func:`workspace_job` turns one :class:`~app.urlstate.ExplorerState` into a job function
for the :class:`~app.jobs.JobManager` that computes a coarse preview (h = :data:`PREVIEW_VOXEL`)
and then the full workspace (:func:`run_engine`: ``kinematics.workspace.compute_workspace`` for the
paper's design, ``kinematics.mechanism_workspace.compute_mechanism_workspace`` for another
mechanism of the selector, ``ExplorerState.mechanism``), re-meshes each shell for
display (:func:`make_shell`) and measures it; it hands each :class:`ShellBundle` to the callbacks
it is given (``app/workspace_controller.py`` puts them on screen). Finished bundles go into the
explorer's shared cache under :func:`ws_key` (results are immutable).
"""

from __future__ import annotations

import dataclasses
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from paraspace.kinematics.display_mesh import DISPLAY_FACES, REMESH_FACTOR
from paraspace.kinematics.progress import Cancelled
from paraspace.kinematics.workspace import WorkspaceResult, WorkspaceSettings, compute_workspace

from ..mechanism_link import MechanismLink
from ..urlstate import ExplorerState

if TYPE_CHECKING:  # pragma: no cover - types only (the modules are imported where they are used)
    import trimesh

    from paraspace.kinematics.bracket import VolumeBracket
    from paraspace.kinematics.bytecache import ByteLRU
    from paraspace.kinematics.measures import WorkspaceMeasures

#: Voxel edge of the coarse preview shell.
PREVIEW_VOXEL = 6.0
#: Full results at this voxel edge or coarser come in a few tenths of a second (h = 2: about 0.05 s
#: of engine and 0.08 s of meshing on 2 idle cores), faster than a preview would help: the preview is
#: shown first only below it, or with leg interference (about 3x slower) (:func:`wants_preview`).
PREVIEW_BELOW = 2.0
#: Face budgets of the block re-mesh of the preview and full shells, at most ``REMESH_FACTOR`` times
#: the display budget when decimated to it (:func:`make_shell`).
PREVIEW_FACES = 20_000
FULL_FACES = 60_000
#: Boundary refinements of the explorer's certified bracket (one: about 2 s of CPU at h = 2, after the
#: shell and the measures are on screen; the CLI and the API default to two).
EXPLORER_BRACKET_REFINE = 1

Progress = Callable[[float, str], None]
JobFn = Callable[[Progress, threading.Event], Any]


@dataclasses.dataclass
class ShellBundle:
    """A computed workspace and what is derived from it (immutable once built)."""

    result: WorkspaceResult
    mesh: trimesh.Trimesh  # decimated shell, colored by z
    measures: WorkspaceMeasures | None = None
    shell_seconds: float = 0.0
    bracket: VolumeBracket | None = None  # certified volume_inner <= V <= volume_outer
    mechanism: MechanismLink | None = None  # the selector's mechanism it was computed for (None: the design)


def make_shell(result: WorkspaceResult, max_faces: int, display_faces: int | None = DISPLAY_FACES) -> trimesh.Trimesh:
    """The shell of ``result`` on screen, colored by z over the voxels' heights (:func:`voxel_z_range`):
    the display shell of :func:`kinematics.display_mesh.display_shell` (a re-mesh of at most
    ``min(max_faces, REMESH_FACTOR * display_faces)`` faces, smoothed, decimated to ``display_faces``,
    enclosing the voxel volume).

    ``display_faces=None``: not decimated, the block re-mesh to ``max_faces`` of
    :func:`kinematics.shell.workspace_shell`, smoothed for display and scaled to the voxel volume
    (:func:`kinematics.shell.smooth_for_display`; the path the explorer took before the display shell)."""
    from paraspace.kinematics.display_mesh import display_shell
    from paraspace.kinematics.shell import smooth_for_display, workspace_shell

    zr = voxel_z_range(result)
    if display_faces is not None:
        return display_shell(result, display_faces, remesh_faces=min(max_faces, REMESH_FACTOR * display_faces),
                             color_range=zr)
    mesh = workspace_shell(result, max_faces=max_faces, color_by_z=True, reduction="remesh", volume_rtol=1e-2,
                           color_range=zr)
    mesh = smooth_for_display(mesh, volume=result.volume)
    if zr is not None:
        mesh.metadata.setdefault("paraspace", {})["color_range"] = zr
    return mesh


def voxel_z_range(result: WorkspaceResult) -> tuple[float, float] | None:
    """The heights the reachable voxels' cubes span, ``[z_bottom, z_top]`` (the colour bar's range:
    the display smoothing moves the surface by a fraction of a voxel, e.g. to z = -0.21, which is
    not a height of the workspace); ``None`` for an empty workspace."""
    occ = result.occupancy
    layers = np.flatnonzero(occ.any(axis=(0, 1)))
    if len(layers) == 0:
        return None
    h, oz = result.grid.h, result.grid.origin[2]
    lo = max(oz + h * (layers[0] - 0.5), result.settings.z_floor)
    return float(lo), float(oz + h * (layers[-1] + 0.5))


def measure(result: WorkspaceResult, cancel: threading.Event | None = None) -> WorkspaceMeasures:
    """The numbers panel's measures of ``result`` (:func:`kinematics.measures.measure_workspace`);
    raises :class:`~kinematics.progress.Cancelled` between its steps once ``cancel`` is set."""
    from paraspace.kinematics.measures import measure_workspace

    return measure_workspace(result, cancel=cancel)


def bracket_unavailable(result: WorkspaceResult) -> str | None:
    """Why the numbers panel shows no certified bracket for ``result`` (the words after "certified
    bracket"), or ``None`` when :func:`bracket` computes one."""
    if result.settings.joints.min_distance > 0.0:
        from paraspace.kinematics.bracket import NO_BRACKET_INTERFERENCE

        return NO_BRACKET_INTERFERENCE
    mech = getattr(result, "mechanism", None)
    if result.design is None and mech is not None:  # a general mechanism
        from paraspace.kinematics.mechanism_workspace import bracket_unavailable as general_unavailable

        return general_unavailable(mech)
    return None


def bracket(result: WorkspaceResult, cancel: threading.Event | None = None,
            progress: Progress | None = None) -> VolumeBracket | None:
    """The certified bracket shown in the numbers panel: the paper engine's
    (:func:`kinematics.bracket.bracket_of`) or a general mechanism's
    (:func:`kinematics.mechanism_workspace.general_bracket_of`); ``None`` where
    :func:`bracket_unavailable` gives a reason. Raises :class:`~kinematics.progress.Cancelled` once
    ``cancel`` is set (both check it between their launches)."""
    if bracket_unavailable(result) is not None:
        return None
    if result.design is None:
        from paraspace.kinematics.mechanism_workspace import MechanismWorkspaceResult, general_bracket_of

        return general_bracket_of(cast(MechanismWorkspaceResult, result), refine=EXPLORER_BRACKET_REFINE,
                                  progress=progress, cancel=cancel)
    from paraspace.kinematics.bracket import bracket_of
    from paraspace.kinematics.progress import Reporter

    return bracket_of(result, refine=EXPLORER_BRACKET_REFINE, progress=Reporter(progress), cancel=cancel)


def ws_settings(s: ExplorerState, voxel: float) -> WorkspaceSettings:
    """The engine settings of ``s`` at voxel edge ``voxel`` (its orientation and joint options; a
    mechanism of the selector has none: its legs carry their own cones)."""
    orientation = (s.pose.psi, s.pose.theta, s.pose.phi)
    if s.mechanism is not None:
        return WorkspaceSettings(voxel=voxel, orientation=orientation)
    return WorkspaceSettings(voxel=voxel, orientation=orientation, joints=s.joints)


def ws_key(s: ExplorerState, voxel: float) -> tuple:
    """Cache key of the workspace of ``s`` at voxel edge ``voxel``."""
    if s.mechanism is not None:
        return (("mechanism", s.mechanism.key()), (s.pose.psi, s.pose.theta, s.pose.phi), float(voxel))
    return (s.design.key(), (s.pose.psi, s.pose.theta, s.pose.phi), float(voxel), s.joints.key())


def run_engine(s: ExplorerState, voxel: float, progress: Progress | None = None,
               cancel: threading.Event | None = None) -> WorkspaceResult:
    """The workspace of ``s`` at ``voxel``: the paper's engine on its design, or
    ``compute_mechanism_workspace`` on the selector's mechanism."""
    if s.mechanism is None:
        return compute_workspace(s.design, ws_settings(s, voxel), progress=progress, cancel=cancel)
    from paraspace.kinematics.mechanism_workspace import compute_mechanism_workspace

    return compute_mechanism_workspace(s.mechanism.mechanism(), ws_settings(s, voxel), progress=progress,
                                       cancel=cancel)


def cached_bundle(cache: ByteLRU, state: ExplorerState) -> ShellBundle | None:
    """The measured bundle of ``state`` (at its own voxel edge) if the cache holds one."""
    hit = cache.get(ws_key(state, state.voxel))
    return hit if hit is not None and hit.measures is not None else None


def compute_bundle(cache: ByteLRU, state: ExplorerState, progress: Progress, cancel: threading.Event) -> ShellBundle:
    """Compute, mesh and measure the workspace of ``state`` in one go and cache it (the Compare
    tab's pinned design)."""
    res = compute_workspace(state.design, ws_settings(state, state.voxel), progress=progress, cancel=cancel)
    bundle = ShellBundle(res, make_shell(res, FULL_FACES))
    bundle.measures = measure(res)
    cache.put(ws_key(state, state.voxel), bundle)
    return bundle


def wants_preview(s: ExplorerState, voxel: float) -> bool:
    """Whether the job shows the coarse preview before the full workspace of ``s`` at ``voxel``
    (:data:`PREVIEW_BELOW`)."""
    return voxel < PREVIEW_VOXEL and (voxel < PREVIEW_BELOW or s.joints.min_distance > 0.0 or s.mechanism is not None)


def workspace_job(s: ExplorerState, cache: ByteLRU, show: Callable[[ShellBundle, bool, float], Any],
                  show_measures: Callable[[ShellBundle, bool], None]) -> JobFn:
    """The job function of the workspace of ``s``: when the full result takes a while
    (:func:`wants_preview`), the preview shell (cached) is computed and shown first
    (``show(bundle, preview=True, seconds)``; no measures: the full result follows at once); then
    the full workspace and its shell, shown as soon as meshed, then its measures
    (``show_measures(bundle, preview=False)``). Everything before the full shell is on its critical
    path, so nothing else runs there; the certified bracket is a job of its own (:func:`bracket`,
    submitted by the controller). Raises :class:`~kinematics.progress.Cancelled` once cancelled."""
    voxel = s.voxel

    def fn(progress: Progress, cancel: threading.Event) -> ShellBundle:
        t0 = time.perf_counter()
        full_key = ws_key(s, voxel)
        if wants_preview(s, voxel):
            pkey = ws_key(s, PREVIEW_VOXEL)
            pre = cache.get(pkey)
            if pre is None:
                res = run_engine(s, PREVIEW_VOXEL, lambda f, m: progress(0.12 * f, f"preview: {m}"), cancel)
                t1 = time.perf_counter()
                pre = ShellBundle(res, make_shell(res, PREVIEW_FACES), mechanism=s.mechanism)
                pre.shell_seconds = time.perf_counter() - t1
                cache.put(pkey, pre)
            if cancel.is_set():
                raise Cancelled()
            show(pre, True, time.perf_counter() - t0)
            progress(0.15, f"full workspace h = {voxel:g}...")
        res = run_engine(s, voxel, lambda f, m: progress(0.15 + 0.6 * f, f"full h = {voxel:g}: {m}"), cancel)
        progress(0.78, "meshing the shell...")
        t1 = time.perf_counter()
        bundle = ShellBundle(res, make_shell(res, FULL_FACES), mechanism=s.mechanism)
        bundle.shell_seconds = time.perf_counter() - t1
        if cancel.is_set():
            raise Cancelled()
        show(bundle, False, time.perf_counter() - t0)
        progress(0.9, "measuring (voids, genus, hollowness)...")
        bundle.measures = measure(res, cancel)
        cache.put(full_key, bundle)
        if cancel.is_set():
            raise Cancelled()
        show_measures(bundle, False)
        return bundle

    return fn
