"""The certified volume bracket (kinematics.bracket) against independent computations: the voxel
estimates at h and h/2 lie inside it, random points of "inside" cubes are reachable by the plain
numpy brute force, and random points of "outside" cubes are unreachable for it even with a 20x
finer arc sampling."""

from __future__ import annotations

import numpy as np
import pytest

from paraspace.kinematics.bracket import BOUNDARY, INSIDE, OUTSIDE, cube_classes
from paraspace.kinematics.design import Design
from paraspace.kinematics.reference import reference_reachable
from paraspace.kinematics.workspace import WorkspaceSettings, _kernel_args, compute_workspace


@pytest.mark.parametrize("design", [Design(), Design(a=10), Design(eta_range="from-zero", l_s=80)])
def test_bracket_contains_the_estimates_and_shrinks(design):
    coarse = compute_workspace(design, WorkspaceSettings(voxel=6.0, bracket=True))
    fine = compute_workspace(design, WorkspaceSettings(voxel=3.0, bracket=True))
    for r in (coarse, fine):
        assert r.volume_inner <= r.volume <= r.volume_outer
    # the finer bracket is narrower and both contain the finer estimate
    assert fine.volume_outer - fine.volume_inner < coarse.volume_outer - coarse.volume_inner
    assert coarse.volume_inner <= fine.volume <= coarse.volume_outer


def test_cube_classes_against_the_brute_force():
    design = Design()
    res = compute_workspace(design, WorkspaceSettings(voxel=8.0))
    grid = res.grid
    cls = cube_classes(design, grid, _kernel_args(design, (0.0, 0.0, 0.0), res.n_eta), res.n_eta, 0.0)
    assert {INSIDE, OUTSIDE, BOUNDARY} <= set(np.unique(cls).tolist())
    rng = np.random.default_rng(3)
    centres = grid.points()

    def sample(which: int, n_cubes: int = 60, per: int = 6) -> np.ndarray:
        idx = np.argwhere(cls == which)
        pick = idx[rng.choice(len(idx), size=min(n_cubes, len(idx)), replace=False)]
        c = centres[pick[:, 0], pick[:, 1], pick[:, 2]]
        off = rng.uniform(-0.5, 0.5, size=(len(c), per, 3)) * grid.h
        return (c[:, None, :] + off).reshape(-1, 3)

    inside = sample(INSIDE)
    assert reference_reachable(design, inside).all()
    outside = sample(OUTSIDE)
    # outside cubes near the boundary are the informative ones: take those next to a non-outside cube
    assert not reference_reachable(design, outside, eta_step=0.025).any()
    near = np.argwhere((cls == OUTSIDE) & (np.roll(cls, 1, axis=2) != OUTSIDE))
    c = centres[near[:, 0], near[:, 1], near[:, 2]]
    pts = (c[:, None, :] + rng.uniform(-0.5, 0.5, size=(len(c), 4, 3)) * grid.h).reshape(-1, 3)
    assert not reference_reachable(design, pts, eta_step=0.025).any()


def test_cli_and_api_report_the_bracket():
    import json
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "paraspace.app.cli", "workspace", "--voxel", "8", "--bracket", "--json"],
                         capture_output=True, text=True, timeout=300, check=True)
    doc = json.loads(out.stdout)
    assert doc["volume_inner"] <= doc["volume"] <= doc["volume_outer"]
    from paraspace.app.api import _workspace_payload

    r = compute_workspace(Design(), WorkspaceSettings(voxel=8.0, bracket=True))
    payload = _workspace_payload(r)
    assert payload["volume_inner"] == r.volume_inner and payload["volume_outer"] == r.volume_outer


def test_explorer_shows_the_certified_bracket():
    from explorer_client import FakeBrowser, wait_idle  # tests/ (pytest's prepend import mode)

    from paraspace.app.explorer import Explorer

    exp = Explorer("127.0.0.1", 0).start()
    try:
        b = FakeBrowser(exp, "voxel=6")
        s = b.session
        wait_idle(exp, s)
        br = s.bundle.bracket
        assert br is not None and br.volume_inner <= s.bundle.result.volume <= br.volume_outer
        text = s.panels.numbers.content
        assert "certified:" in text and "continuous workspace" in text
        b.close()
    finally:
        exp.stop()
