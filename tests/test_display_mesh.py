"""The explorer's lighter display shell (kinematics.display_mesh, issue 24 target 10): a closed mesh
under the face budget, within the stated Hausdorff bound of the undecimated re-mesh and of the
full-resolution shell, enclosing the voxel volume; the exported shell is not decimated.

Hausdorff distances are estimated with trimesh's surface sampling: the symmetric maximum, over
dense samples and the vertices of each surface, of the distance to the nearest such point of the
other (scipy's k-d tree); it overstates the true distance by the sample spacing (up to about 0.5 h
here: a mesh against itself reads 0.5 h)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from paraspace.kinematics.design import Design
from paraspace.kinematics.display_mesh import DISPLAY_FACES, display_mesh, is_closed
from paraspace.kinematics.shell import viridis, workspace_shell
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


def _hausdorff(a: trimesh.Trimesh, b: trimesh.Trimesh, n: int = 150_000) -> float:
    sa = np.vstack([trimesh.sample.sample_surface(a, n, seed=1)[0], a.vertices])
    sb = np.vstack([trimesh.sample.sample_surface(b, n, seed=2)[0], b.vertices])
    return float(max(cKDTree(sa).query(sb)[0].max(), cKDTree(sb).query(sa)[0].max()))


@pytest.fixture(scope="module")
def shells():
    """(result, full-resolution shell, explorer re-mesh before decimation) at h = 4."""
    from paraspace.app.explorer.workspace_job import FULL_FACES, make_shell

    out = []
    for design in (Design(), Design(a=10)):
        res = compute_workspace(design, WorkspaceSettings(voxel=4.0))
        out.append((res, workspace_shell(res), make_shell(res, FULL_FACES, display_faces=None)))
    return out


def test_display_shell_is_closed_under_budget_and_close_to_the_full_shell(shells):
    from paraspace.app.explorer.workspace_job import FULL_FACES, make_shell

    decimated = 0
    for (res, full, remesh), slack in zip(shells, (0.5, 3.0)):  # the default design; the thin caps of a = 10
        h = res.grid.h
        shown = make_shell(res, FULL_FACES)  # what the explorer sends
        assert len(shown.faces) <= DISPLAY_FACES or len(remesh.faces) <= DISPLAY_FACES
        if len(remesh.faces) > DISPLAY_FACES:
            decimated += 1
            assert shown.metadata["paraspace"]["display_faces_from"] == len(remesh.faces)
        # valid: watertight and outward where the full shell is
        assert full.is_watertight and shown.is_watertight and shown.is_winding_consistent and shown.volume > 0
        # the voxel volume, as the undecimated display shell encloses it
        assert abs(shown.volume - res.volume) <= 1e-9 * res.volume
        # the stated bounds: Hausdorff(D, M) <= 1.5 h, Hausdorff(D, full) <= Hausdorff(M, full) + 0.5 h
        # (default design); 3 h in both for the thin caps
        d_remesh = _hausdorff(shown, remesh)
        assert d_remesh <= max(1.5, slack) * h, (d_remesh, h)
        assert _hausdorff(shown, full) <= _hausdorff(remesh, full) + slack * h
        # colours by height: the viridis colour of each vertex's own height, to within a few steps
        lo, hi = shown.metadata["paraspace"]["color_range"]
        expected = viridis(np.clip((shown.vertices[:, 2] - lo) / (hi - lo), 0.0, 1.0)).astype(int)
        diff = np.abs(np.asarray(shown.visual.vertex_colors).astype(int)[:, :3] - expected[:, :3])
        assert np.median(diff) <= 2 and np.percentile(diff, 99) <= 24, (np.median(diff), np.percentile(diff, 99))
    assert decimated >= 1  # the default design's re-mesh at h = 4 (about 51 000 faces) is decimated


def test_every_budget_gives_a_closed_mesh_under_it_or_the_input(shells):
    _, _, remesh = shells[0]
    for budget in (20_000, 5_000, 1_000):
        out = display_mesh(remesh, budget)
        assert out is remesh or (is_closed(out) and len(out.faces) <= budget), budget
    assert display_mesh(remesh, len(remesh.faces)) is remesh  # within the budget: unchanged
    for bad in (3, 0, 2.5, True):
        with pytest.raises(ValueError, match="max_faces"):
            display_mesh(remesh, bad)  # type: ignore[arg-type]
