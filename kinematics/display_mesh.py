r"""A lighter copy of a shell for the screen: a coarse re-mesh, then quadric decimation to a face budget.

Definition. For a workspace result with occupancy ``O`` (voxel edge ``h``, voxel volume ``V``), a
display face budget ``B`` and a re-mesh budget ``R`` (default ``3 B``), the display shell is

    S_k = marching cubes of the k^3 block means of O (k = 1: O itself, level 1/2; k >= 2: the
          level whose mesh encloses V to 1 %; :func:`kinematics.shell.workspace_shell` step 4),
          for the smallest k whose mesh is closed and has at most R faces,
    T   = S_k after 5 passes of Taubin smoothing (:func:`kinematics.shell.smooth_for_display`),
    D   = Q_B(T)  if Q_B(T) is closed,  else T,

scaled uniformly about its centroid to enclose ``V`` exactly, and coloured by height (viridis of
each vertex's own z over ``color_range``). ``Q_B`` is quadric edge collapse (Garland-Heckbert,
``fast_simplification``) down to ``B`` faces: adaptive, it removes vertices where the surface is
flat (where detail does not show) and keeps them along ridges and knife edges. *Closed* means every
directed edge appears once and its reverse once (watertight, consistently wound) and the enclosed
volume is positive. A block size ``k`` whose mixed cells (each yields about two faces) already
promise more than ``R`` faces is skipped without meshing it.

:func:`display_shell` is what the explorer sends; :func:`display_mesh` (the path before: decimate a
given re-mesh of up to 60 000 faces) is kept for the A/B of ``benchmarks/explorer_latency.py``.
Re-meshing at about three times the display budget instead of five costs less in every step
(marching cubes on a coarser grid, smoothing, decimation of a third as many faces, no k-d tree for
the colours) and keeps the budget's adaptive decimation.

Only the display copy is coarse: the exported meshes (STL/PLY/GLB downloads,
``paraspace workspace --export``) and every measure are computed from the workspace result at full
resolution, never from ``D``.

Measured (load average 8-16 on 2 cores, medians of 3-5; symmetric Hausdorff distances estimated
from 150 000 surface samples plus the vertices of each mesh, which overstate them by up to about
0.5 h), the display shell against the path before it (the 60 000-face re-mesh decimated), time as a
ratio to the engine on the same design, distance to the full-resolution shell:

=========================  ==========================================  ==================
case                       now                                         before
=========================  ==========================================  ==================
default, h = 2             3^3 blocks, 22 900 -> 12 000; 0.88x; 5.4 mm  2.7x; 4.5 mm
default, h = 1             5^3 blocks, 32 848 -> 12 000; 1.1x; 4.3 mm   2.4x; 3.6 mm
default, h = 4             2^3 blocks, 12 336 -> 12 000; 1.0x; 8.7 mm   5x; 3.2 mm
default, h = 6             voxels, 22 568 -> 12 000; 2.3x; 4.3 mm       3.9x; 4.3 mm
a = 10 (thin caps), h = 4  voxels, 27 260 -> 12 000; 2.5x; 12.5 mm     4x; 12.5 mm
=========================  ==========================================  ==================

Since then the closedness test buckets the directed edges by their first vertex (linear in the faces,
instead of a sort and a search of all of them) and the mixed cells are counted in one compiled pass:
the same meshes, at h = 2 in 31-32 ms instead of 41-43 ms (0.93-0.96x the engine, from 1.25-1.29x;
alternating runs, load 0.4).

The coarser re-mesh rounds ridges at about a block (``k h``); quadric collapse keeps the budget's
faces where the surface bends. Stated bounds (the tests use them): ``Hausdorff(T, full) <= (k + 1) h``
and ``Hausdorff(D, T) <= 1.5 h`` (``3 h`` for thin, knife-edged workspaces such as the caps of
``a = 10``, whose fins of one or two voxels quadric collapse thins), so ``Hausdorff(D, full) <=
(k + 2.5) h``; the tests check ``Hausdorff(D, full) <= (k + 1) h`` where the workspace is not thin.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

if TYPE_CHECKING:  # pragma: no cover - types only
    import trimesh

    from .workspace import WorkspaceResult

__all__ = ["DISPLAY_FACES", "REMESH_FACTOR", "display_mesh", "display_shell", "edges_closed", "is_closed"]

#: Face budget of the shell on screen (the explorer's full shell; the exported meshes are not
#: decimated). 12 000 faces draw in software WebGL in a fraction of the 50 000-face re-mesh's time.
DISPLAY_FACES = 12_000
#: The re-mesh of :func:`display_shell` has at most this many times the display budget's faces (the
#: quadric collapse then picks where the budget's faces go).
REMESH_FACTOR = 3
#: Marching-cubes faces per mixed cell assumed when skipping a block size unmeshed (about 2 on the
#: workspaces tried; a block size skipped wrongly only gives a coarser re-mesh, still closed).
_FACES_PER_MIXED_CELL = 2
#: Taubin passes of the display smoothing (as :func:`kinematics.shell.smooth_for_display`).
_SMOOTH_ITERATIONS = 5


def is_closed(mesh: trimesh.Trimesh) -> bool:
    """Watertight, consistently wound and enclosing a positive volume."""
    return bool(len(mesh.faces) and mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0)


def edges_closed(faces: np.ndarray) -> bool:
    """Whether every directed edge of ``faces`` (F, 3) appears exactly once and its reverse exactly
    once: a watertight, consistently wound, edge-manifold triangle mesh (the directed edges grouped
    by their first vertex, each looked up among its second vertex's: :func:`_edges_closed_kernel`)."""
    f = np.ascontiguousarray(faces, dtype=np.int64)
    if len(f) == 0:
        return False
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"faces of shape {f.shape} are invalid: valid values (F, 3)")
    if int(f.min()) < 0:  # not vertex indices
        return False
    return bool(_edges_closed_kernel(f, int(f.max()) + 1))


@njit(cache=True, nogil=True)
def _edges_closed_kernel(faces, n):
    """:func:`edges_closed` of ``faces`` on vertices ``0 .. n - 1``: the directed edges ``(a, b)``
    bucketed by ``a`` (a counting sort, O(F)), then each edge must be alone in its bucket and ``(b, a)``
    must be in ``b``'s."""
    m = faces.shape[0]
    start = np.zeros(n + 1, np.int64)
    for f in range(m):
        for c in range(3):
            start[faces[f, c] + 1] += 1
    for v in range(n):
        start[v + 1] += start[v]
    fill = start[:n].copy()
    target = np.empty(3 * m, np.int64)
    for f in range(m):
        for c in range(3):
            a = faces[f, c]
            target[fill[a]] = faces[f, (c + 1) % 3]
            fill[a] += 1
    for a in range(n):
        for p in range(start[a], start[a + 1]):
            b = target[p]
            for q in range(p + 1, start[a + 1]):
                if target[q] == b:
                    return False
            found = False
            for q in range(start[b], start[b + 1]):
                if target[q] == a:
                    found = True
                    break
            if not found:
                return False
    return True


def _signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    tri = vertices[faces]
    return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0) if len(tri) else 0.0


def _closed(vertices: np.ndarray, faces: np.ndarray) -> bool:
    return edges_closed(faces) and _signed_volume(vertices, faces) > 0


def _validate_faces(name: str, value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 4:
        raise ValueError(f"{name} = {value!r} is invalid: an integer >= 4")
    return int(value)


def display_shell(result: WorkspaceResult, max_faces: int = DISPLAY_FACES, remesh_faces: int | None = None,
                  color_range: tuple[float, float] | None = None) -> trimesh.Trimesh:
    """The display shell ``D`` of ``result`` (module docstring) for the face budget ``max_faces`` and
    the re-mesh budget ``remesh_faces`` (default ``REMESH_FACTOR * max_faces``).

    Colours are viridis by height over ``color_range`` (default: the mesh's z range). The mesh's
    ``metadata["paraspace"]`` records ``h``, ``reduction`` (which re-mesh, and whether decimated),
    ``block`` (``k``; ``None`` for the fallback), ``display_faces_from`` (the re-mesh's faces),
    ``voxel_volume`` and ``color_range``.
    An empty workspace gives an empty mesh.

    Raises:
        ValueError: ``max_faces`` or ``remesh_faces`` below 4.
    """
    import math

    import fast_simplification
    import trimesh

    from .shell import _MAX_BLOCK, DIRECT_SIZES, HALF_LEVEL, _BlockMeans, _mc, _mixed_cells, _volume_preserving, viridis

    budget = _validate_faces("max_faces", max_faces)
    cap = REMESH_FACTOR * budget if remesh_faces is None else _validate_faces("remesh_faces", remesh_faces)
    h = float(result.grid.h)
    occ = np.asarray(result.occupancy, dtype=bool)
    target = float(occ.sum()) * h ** 3
    meta: dict = {"h": h, "voxel_volume": target, "reduction": "none", "display_faces_from": 0, "block": None}
    if target == 0.0:
        empty = trimesh.Trimesh()
        empty.metadata["paraspace"] = meta
        return empty
    # the occupancy framed by one empty voxel, as uint8: its mixed cells and block counts read a
    # quarter of the bytes of the float32 field that marching cubes at k = 1 takes (built only then)
    field = np.zeros(tuple(n + 2 for n in occ.shape), np.uint8)
    field[1:-1, 1:-1, 1:-1] = occ
    means = _BlockMeans(field, binary=True, direct=DIRECT_SIZES)
    origin = np.asarray(result.grid.origin, dtype=float)
    mixed1 = _mixed_cells(field, HALF_LEVEL)
    # mixed cells fall like 1/k^2: start near the first block size that can fit
    k0 = max(1, int(math.sqrt(_FACES_PER_MIXED_CELL * mixed1 / cap)))
    last = min(max(field.shape), _MAX_BLOCK)
    mesh: trimesh.Trimesh | None = None
    for k in range(min(k0, last), last + 1):
        f = field if k == 1 else means(k)
        if k < last and _FACES_PER_MIXED_CELL * (mixed1 if k == 1 else _mixed_cells(f, HALF_LEVEL)) > cap:
            continue
        if k == 1:
            m = _mc(field.astype(np.float32), HALF_LEVEL, h)  # vertices at the edge midpoints: the exact shell
            m.vertices = m.vertices + (origin - h)
        else:
            m, _level = _volume_preserving(f, k * h, target, 1e-2)
            m.vertices = m.vertices + (origin - h * (1 + 0.5 * (k + 1)))
        if len(m.faces) <= cap and _closed(np.asarray(m.vertices), np.asarray(m.faces)):
            mesh = m
            meta["reduction"] = "re-mesh (voxels)" if k == 1 else f"block re-mesh ({k}^3 voxels)"
            meta["block"] = k
            break
    if mesh is None:  # no block size gave a closed mesh within the cap: the shell module's own reduction
        from .shell import workspace_shell

        mesh = workspace_shell(result, max_faces=cap, color_by_z=False)
        meta["reduction"] = f"{mesh.metadata['paraspace']['reduction']} (fallback)"
    trimesh.smoothing.filter_taubin(mesh, lamb=0.5, nu=-0.53, iterations=_SMOOTH_ITERATIONS)
    v, f = np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64)
    meta["display_faces_from"] = int(len(f))
    if len(f) > budget:
        vd, fd = fast_simplification.simplify(v, f, target_count=budget)
        if len(fd) <= budget and _closed(np.asarray(vd, dtype=float), np.asarray(fd)):
            v, f = np.asarray(vd, dtype=float), np.asarray(fd, dtype=np.int64)
            meta["reduction"] += " + quadric"
        else:
            meta["reduction"] += " (quadric not closed: not decimated)"
    vol = _signed_volume(v, f)
    if vol > 0:
        c = v.mean(axis=0)
        v = c + (v - c) * (target / vol) ** (1.0 / 3.0)
    z = v[:, 2]
    lo, hi = (float(z.min()), float(z.max())) if color_range is None else (float(color_range[0]),
                                                                              float(color_range[1]))
    out = trimesh.Trimesh(vertices=v, faces=f, process=False)
    out.visual.vertex_colors = viridis((z - lo) / (hi - lo) if hi > lo else np.zeros_like(z))  # type: ignore[union-attr]
    meta["color_range"] = (lo, hi)
    out.metadata["paraspace"] = meta
    return out


def display_mesh(mesh: trimesh.Trimesh, max_faces: int = DISPLAY_FACES) -> trimesh.Trimesh:
    """The display copy ``D`` of ``mesh`` for the face budget ``max_faces`` (module docstring).

    Returns ``mesh`` itself when it is within the budget or when the decimated copy is not closed
    (quadric collapse has no manifold guard). The copy's ``metadata["paraspace"]`` is ``mesh``'s with
    ``display_faces_from`` (the faces before decimation) added.

    Raises:
        ValueError: ``max_faces`` below 4 (no closed surface has fewer faces).
    """
    import fast_simplification
    import trimesh
    from scipy.spatial import cKDTree

    max_faces = _validate_faces("max_faces", max_faces)
    n = len(mesh.faces)
    if n <= max_faces:
        return mesh
    v, f = fast_simplification.simplify(np.asarray(mesh.vertices, dtype=float),
                                        np.asarray(mesh.faces, dtype=np.int64),
                                        target_reduction=1.0 - max_faces / n)
    out = trimesh.Trimesh(vertices=np.asarray(v, dtype=float), faces=np.asarray(f), process=False)
    if len(out.faces) > max_faces or not is_closed(out):
        return mesh
    v0, v1 = float(mesh.volume), float(out.volume)
    if v0 > 0:
        c = out.vertices.mean(axis=0)
        out.vertices = c + (out.vertices - c) * (v0 / v1) ** (1.0 / 3.0)
    if mesh.visual is not None and mesh.visual.kind == "vertex" and len(mesh.vertices):
        _, nearest = cKDTree(mesh.vertices).query(out.vertices)
        out.visual.vertex_colors = np.asarray(mesh.visual.vertex_colors)[nearest]  # type: ignore[union-attr]
    meta = dict(mesh.metadata.get("paraspace", {}))
    meta["display_faces_from"] = int(n)
    out.metadata["paraspace"] = meta
    return out
