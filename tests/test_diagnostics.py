"""Which limit binds at the workspace surface (kinematics.diagnostics) against geometry."""

from __future__ import annotations

import numpy as np
import pytest

from paraspace.kinematics.design import Design
from paraspace.kinematics.diagnostics import limit_binding, surface_layer
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


@pytest.fixture(scope="module")
def default_ws():
    return compute_workspace(Design(), WorkspaceSettings(voxel=4.0))


def _columns(res):
    occ = res.occupancy
    has = occ.any(axis=2)
    top = np.where(has, occ.shape[2] - 1 - np.argmax(occ[:, :, ::-1], axis=2), -1)
    bot = np.where(has, np.argmax(occ, axis=2), -1)
    return has, top, bot


def test_above_the_dome_legs_are_too_short_to_reach(default_ws):
    """The voxel just above each column's highest reachable voxel fails on l_max only."""
    res = default_ws
    has, top, _ = _columns(res)
    mask = np.zeros_like(res.occupancy)
    for i, j in np.argwhere(has & (top + 1 < res.occupancy.shape[2])):
        mask[i, j, top[i, j] + 1] = True
    lb = limit_binding(res, voxels=mask, max_samples=400)
    assert lb.failures > 100
    assert lb.fractions["l_min"] == 0.0  # never too close above the dome
    assert lb.fractions["sampling"] < 0.02 and lb.fractions["l_max"] > 0.98


def test_under_the_dome_legs_are_too_long_at_closest_approach(default_ws):
    """In the hollow underside (central columns, just below the lowest reachable voxel) the
    platform is too close to every carriage: failures are l_min only."""
    res = default_ws
    has, _, bot = _columns(res)
    xs, ys, _ = res.grid.axes()
    central = (np.abs(xs)[:, None] < 30) & (np.abs(ys)[None, :] < 30)
    mask = np.zeros_like(res.occupancy)
    for i, j in np.argwhere(has & central & (bot > 0)):
        mask[i, j, bot[i, j] - 1] = True
    lb = limit_binding(res, voxels=mask, max_samples=None)
    assert lb.failures > 20
    assert lb.fractions["l_max"] == 0.0  # never out of reach under the dome
    assert lb.fractions["sampling"] < 0.05 and lb.fractions["l_min"] > 0.95


def test_surface_summary_is_consistent(default_ws):
    lb = limit_binding(default_ws, max_samples=600)
    assert lb.samples == 600 and lb.failures >= lb.samples  # every surface voxel fails >= 1 chain
    assert sum(lb.fractions.values()) == pytest.approx(1.0)
    assert lb.fractions["l_max"] > 0 and lb.fractions["l_min"] > 0
    assert sum(c["failures"] for c in lb.per_chain) == lb.failures
    assert "l_max" in lb.summary and "%" in lb.summary
    layer = surface_layer(default_ws.occupancy)
    assert not (layer & default_ws.occupancy).any() and layer.sum() > 600


def test_without_a_minimum_length_only_l_max_binds():
    res = compute_workspace(Design(l_min=1.0), WorkspaceSettings(voxel=12.0))
    lb = limit_binding(res, max_samples=300)
    assert lb.failures > 0 and lb.fractions["l_min"] == 0.0 and lb.fractions["l_max"] > 0.95
