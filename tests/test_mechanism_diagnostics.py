"""Which limit binds at a general mechanism's surface (kinematics/mechanism_diagnostics.py), each
attribution checked against the description's brute force over its carriage joints."""

from __future__ import annotations

import dataclasses

import numpy as np

from paraspace.kinematics.mechanism import Cone, carriage_samples, reachable_brute_force
from paraspace.kinematics.mechanism_diagnostics import chain_limits, mechanism_limit_binding
from paraspace.kinematics.mechanism_workspace import compute_general_workspace
from paraspace.kinematics.presets import preset
from paraspace.kinematics.workspace import WorkspaceSettings

WS = WorkspaceSettings(voxel=16.0)


def _surface_points(res, n: int = 25) -> np.ndarray:
    from paraspace.kinematics.diagnostics import surface_layer

    idx = np.argwhere(surface_layer(res.occupancy))
    idx = idx[np.random.default_rng(1).choice(len(idx), size=min(n, len(idx)), replace=False)]
    return np.asarray(res.grid.origin) + res.grid.h * idx


def _brute_best(chain, p):
    """The chain's carriage sample of largest smallest length margin: (margin, lengths there)."""
    _, bases, _ = carriage_samples(chain, {"prismatic": 2001, "revolute": 61})
    u = np.array([leg.platform for leg in chain.legs])
    length = np.linalg.norm(p + u[None] - bases, axis=2)
    lo = np.array([leg.length[0] for leg in chain.legs])
    hi = np.array([leg.length[1] for leg in chain.legs])
    m = np.minimum(length - lo, hi - length).min(axis=1)
    k = int(np.argmax(m))
    return float(m[k]), length[k]


def test_length_limits_agree_with_the_brute_force() -> None:
    mech = preset("6-pups", {"platform_half_angle": 20.0})
    res = compute_general_workspace(mech, WS)
    pts = _surface_points(res)
    rows = chain_limits(mech, pts, eta_step=0.5, length_step=1.0)
    seen = set()
    for p, row in zip(pts, rows):
        assert row and not reachable_brute_force(mech, p, np.eye(3), samples={"prismatic": 2001})
        for entry in row:
            c, lim = entry.split(":")
            seen.add(lim)
            chain = mech.chains[int(c)]
            best, lengths = _brute_best(chain, p)
            assert best < 0.0  # the chain alone has no carriage value in range (brute force)
            j = int(np.argmin([min(x - leg.length[0], leg.length[1] - x) for x, leg in zip(lengths, chain.legs)]))
            assert lim == ("l_max" if lengths[j] > chain.legs[j].length[1] else "l_min"), (p, entry)
    assert seen & {"l_max", "l_min"}
    summary = mechanism_limit_binding(res, max_samples=25, seed=1)
    assert summary.failures == sum(len(r) for r in rows) and abs(sum(summary.fractions.values()) - 1.0) < 1e-12
    assert "the surface is set by" in summary.summary


def test_cone_limits_agree_with_the_brute_force() -> None:
    base = preset("6-pups")
    cone = Cone((0.0, 0.0, 1.0), 40.0)  # the legs lean about 28 deg at home: the cones bind
    mech = dataclasses.replace(base, chains=tuple(
        dataclasses.replace(c, legs=tuple(dataclasses.replace(leg, u_cone=cone) for leg in c.legs))
        for c in base.chains))
    res = compute_general_workspace(mech, WS)
    pts = _surface_points(res)
    rows = chain_limits(mech, pts)
    cones = 0
    for p, row in zip(pts, rows):
        for entry in row:
            c, lim = entry.split(":")
            alone = dataclasses.replace(mech, chains=(mech.chains[int(c)],))
            assert not reachable_brute_force(alone, p, np.eye(3), samples={"prismatic": 2001})
            if lim == "u_cone":  # passes without its cones (a witness of a fine brute force)
                plain = dataclasses.replace(base, chains=(base.chains[int(c)],))
                assert reachable_brute_force(plain, p, np.eye(3), samples={"prismatic": 20001})
                cones += 1
            else:
                assert lim in ("l_max", "l_min", "sampling")
    assert cones > 0


def test_cli_workspace_diagnostics_of_a_general_mechanism(capsys) -> None:
    import json

    from paraspace.app.cli import main

    assert main(["workspace", "--mechanism", "6-pups", "--voxel", "16", "--diagnostics", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    ref = mechanism_limit_binding(compute_general_workspace(preset("6-pups"), WS))
    assert out["limit_binding"]["fractions"] == ref.fractions and out["limit_binding"]["failures"] == ref.failures
