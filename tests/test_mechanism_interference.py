"""Leg interference of a general mechanism (kinematics/mechanism_interference.py) against a plain
brute force over the same sampled carriages: every combination of every chain's feasible carriage
samples, every pair of legs by the paper's closed-form segment distance."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from paraspace.kinematics.design import ParameterError
from paraspace.kinematics.interference import segment_distance
from paraspace.kinematics.mechanism import carriage_samples
from paraspace.kinematics.mechanism_interference import interference_free_general, segment_distances
from paraspace.kinematics.mechanism_workspace import compute_general_workspace, platform_rotation
from paraspace.kinematics.presets import preset
from paraspace.kinematics.workspace import WorkspaceSettings

#: the paper's arc (30 deg) every 10 deg and its radial stroke (50) every 10: 4 x 6 carriage samples
ETA, LEN = 10.0, 10.0
GRID = {"revolute": 4, "prismatic": 6}


def _with_diameter(mech, d):
    return dataclasses.replace(mech, chains=tuple(
        dataclasses.replace(c, legs=tuple(dataclasses.replace(leg, diameter=d) for leg in c.legs))
        for c in mech.chains))


def _brute(mech, point, rot) -> bool:
    """Every combination of the chains' feasible grid configurations; every pair of the six legs."""
    tops = mech.platform_points(point, rot)
    per_chain, legs_of = [], []
    first = 0
    for chain in mech.chains:
        _, bases, _ = carriage_samples(chain, GRID)
        n = len(chain.legs)
        idx = list(range(first, first + n))
        first += n
        length = np.linalg.norm(tops[idx][None] - bases, axis=2)
        lo = np.array([leg.length[0] for leg in chain.legs]) - 1e-9
        hi = np.array([leg.length[1] for leg in chain.legs]) + 1e-9
        per_chain.append(bases[np.all((length >= lo) & (length <= hi), axis=1)])
        legs_of.append(idx)
    diam = [leg.diameter for _, _, leg in mech.legs]
    for combo in itertools.product(*per_chain):
        base = np.concatenate(combo)
        if all(segment_distance(*base[i], *tops[i], *base[j], *tops[j]) >= 0.5 * (diam[i] + diam[j]) - 1e-9
               for i, j in itertools.combinations(range(len(base)), 2)):
            return True
    return False


def test_segment_distances_equal_the_closed_form() -> None:
    rng = np.random.default_rng(3)
    pts = rng.normal(size=(400, 4, 3)) * 10.0
    pts[:40, 1] = pts[:40, 0]          # degenerate first segment (a point)
    pts[40:80, 3] = pts[40:80, 2]      # degenerate second segment
    pts[80:120, 2:] = pts[80:120, :2] + np.array([0.0, 0.0, 1.0])  # parallel segments
    got = segment_distances(pts[:, 0], pts[:, 1], pts[:, 2], pts[:, 3])
    ref = [segment_distance(*p[0], *p[1], *p[2], *p[3]) for p in pts]
    np.testing.assert_allclose(got, ref, atol=1e-9)


def test_interference_equals_the_brute_force_over_the_sampled_carriages() -> None:
    mech = _with_diameter(preset("paper"), 11.0)  # the general engine on the paper's chains (never routed)
    rng = np.random.default_rng(7)
    pts = np.column_stack([rng.uniform(-50, 50, 60), rng.uniform(-50, 50, 60), rng.uniform(100, 160, 60)])
    orientations = [(0.0, 0.0, 0.0), (10.0, 5.0, -5.0)]
    counts = {True: 0, False: 0}
    for k, p in enumerate(pts):
        angles = orientations[k % 2]
        rot = platform_rotation(mech, angles)
        res = interference_free_general(mech, p, angles, eta_step=ETA, length_step=LEN)
        assert not res.undecided
        assert res.free == _brute(mech, p, rot), (p, angles)
        counts[res.free] += 1
        if res.free:  # the carriage values found: feasible and clear, recomputed from the description
            assert res.carriages is not None
            base = mech.base_points(res.carriages)
            tops = mech.platform_points(p, rot)
            length = np.linalg.norm(tops - base, axis=1)
            assert all(leg.length[0] - 1e-9 <= x <= leg.length[1] + 1e-9 for x, (_, _, leg) in zip(length, mech.legs))
            for i, j in itertools.combinations(range(6), 2):
                assert segment_distance(*base[i], *tops[i], *base[j], *tops[j]) >= 11.0 - 1e-9
    assert counts[True] >= 5 and counts[False] >= 5  # both answers occur among the samples


def test_workspace_with_diameters_is_the_filtered_workspace() -> None:
    ws = WorkspaceSettings(voxel=16.0, eta_step=ETA)
    plain = compute_general_workspace(preset("paper"), ws, length_step=LEN)
    thin = compute_general_workspace(_with_diameter(preset("paper"), 11.0), ws, length_step=LEN)
    assert not np.any(thin.occupancy & ~plain.occupancy) and 0 < thin.voxels < plain.voxels
    # a few voxels each way, decided by the brute force
    xs, ys, zs = plain.grid.axes()
    mech = _with_diameter(preset("paper"), 11.0)
    for want in (True, False):
        idx = np.argwhere(plain.occupancy & (thin.occupancy == want))[:4]
        for i, j, k in idx:
            assert _brute(mech, np.array([xs[i], ys[j], zs[k]]), np.eye(3)) == want
    with pytest.raises(ParameterError) as ei:
        compute_general_workspace(_with_diameter(preset("6-pups"), 5.0), WorkspaceSettings(voxel=16.0, bracket=True))
    assert ei.value.field == "bracket"
