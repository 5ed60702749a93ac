"""Tasks on a general mechanism (kinematics/mechanism_task.py) against the description's plain brute
force (kinematics.mechanism.reachable_brute_force: every carriage joint on a fine grid): the
region's fraction, margin (K2) and failing chains, a pose list's reachability and margins."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from paraspace.kinematics.design import ParameterError
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.mechanism import carriage_samples, reachable_brute_force
from paraspace.kinematics.mechanism_task import evaluate_mechanism_task
from paraspace.kinematics.mechanism_workspace import platform_rotation
from paraspace.kinematics.presets import preset
from paraspace.kinematics.rotation import euler_zyx_deg
from paraspace.kinematics.task import OrientationSet, PoseList, Region, TaskSettings, _lattice

#: 6-PUPS: one prismatic joint per chain (stroke 50), exact in the engine; 2001 brute-force values
FINE = {"prismatic": 2001}


def _brute(mech, pts, rots) -> np.ndarray:
    """Reachable at every orientation: the brute force, and where only the engine passes (a feasible
    set of the lift thinner than the brute force's step) a 100x finer brute force at that point."""
    ok = np.ones(len(pts), bool)
    for rot in rots:
        r = platform_rotation(mech, rot)
        got = reachable_brute_force(mech, pts, r, samples=FINE)
        ok &= got
    return ok


def _witness(mech, p, rots) -> bool:
    return all(reachable_brute_force(mech, p, platform_rotation(mech, rot), samples={"prismatic": 200_001})
               for rot in rots)


@pytest.mark.parametrize("region, oset", [
    (Region.parse("box", [0.0, 0.0, 175.0, 60.0, 60.0, 40.0]), OrientationSet(fixed=(0.0, 6.0, 0.0))),
    (Region.parse("sphere", [10.0, 0.0, 160.0, 30.0]), OrientationSet(tilt=5.0, torsion=0.0, step=10.0)),
])
def test_region_task_equals_the_brute_force(region, oset) -> None:
    mech = preset("6-pups", {"platform_half_angle": 20.0})
    h, grow = (8.0, 16.0) if not oset.total else (12.0, 12.0)
    res = evaluate_mechanism_task(mech, region, oset, TaskSettings(voxel=h, margin_range=grow))
    # the lattice of kinematics.task (the definition of the sampling), decided by the brute force
    axes, _, _ = _lattice(region, h, grow)
    g = np.meshgrid(*axes, indexing="ij")
    pts = np.stack([a.ravel() for a in g], axis=1)
    sdf = region.sdf(pts)
    keep = sdf <= grow + 1e-9
    pts, sdf = pts[keep], sdf[keep]
    rots = oset.rotations()
    brute = _brute(mech, pts, rots)
    inside = sdf <= 1e-9
    # the engine's reachable cells: every brute-force pass is one (the engine is exact in the lift);
    # a cell only the engine passes needs a witness of a 100x finer brute force
    cells = {tuple(p) for p in np.round(res.cells[res.cells_ok], 9)}
    for i in np.flatnonzero(inside):
        key = tuple(np.round(pts[i], 9))
        if brute[i]:
            assert key in cells, pts[i]
        elif key in cells:
            assert _witness(mech, pts[i], rots), pts[i]
            brute[i] = True
    assert 0.0 < res.fraction == pytest.approx(brute[inside].mean(), abs=1e-12)
    assert res.contained == bool(brute[inside].all())
    assert res.details["sample_points"] == int(inside.sum())
    # (K2): the smallest signed distance of an unreachable lattice point; the nearest brute-force
    # failures get a witness first (a thin feasible set the brute force's step misses)
    for i in np.flatnonzero(~brute)[np.argsort(sdf[~brute])][:8]:
        if _witness(mech, pts[i], rots):
            brute[i] = True
        else:
            break
    bad = np.flatnonzero(~brute)
    assert bad.size and float(sdf[bad].min()) == pytest.approx(res.margin, abs=1e-9)
    q = np.asarray(res.worst["at"]["position"])
    assert float(region.sdf(q[None])[0]) == pytest.approx(res.margin, abs=1e-9)
    if not oset.total:
        # the reported chains fail alone at q* (brute force, a subset of the engine's passes); every
        # other chain has a witness there
        assert res.binding["chains"] and res.binding["chain"] == res.binding["chains"][0]
        for c, chain in enumerate(mech.chains):
            alone = dataclasses.replace(mech, chains=(chain,))
            if c in res.binding["chains"]:
                assert not _brute(alone, q[None], rots)[0]
            else:
                assert _witness(alone, q, rots)


def test_pose_list_task_equals_the_brute_force() -> None:
    mech = preset("6-pups")
    poses = np.array([[0.0, 0.0, 150.0, 0.0, 0.0, 0.0], [10.0, 0.0, 160.0, 0.0, 5.0, 0.0],
                      [40.0, 30.0, 130.0, 5.0, 0.0, -3.0], [0.0, 0.0, 400.0, 0.0, 0.0, 0.0],
                      [0.0, 0.0, 60.0, 0.0, 0.0, 0.0]])
    res = evaluate_mechanism_task(mech, PoseList(poses, t=np.arange(5.0)), settings=TaskSettings())
    step = 50.0 / 2000
    for row, pose in zip(res.poses, poses):
        rot = platform_rotation(mech, euler_zyx_deg(*pose[3:]))
        brute = bool(reachable_brute_force(mech, pose[:3], rot, samples=FINE))
        assert row["reachable"] == brute or (row["reachable"] and _witness(mech, pose[:3], [rot]))
        # margin: the largest smallest length margin over the carriage values, per chain, brute force
        best = []
        for chain in mech.chains:
            _, bases, _ = carriage_samples(chain, FINE)
            u = np.array([leg.platform for leg in chain.legs]) @ rot.T
            length = np.linalg.norm(pose[:3] + u[None] - bases, axis=2)
            lo = np.array([leg.length[0] for leg in chain.legs])
            hi = np.array([leg.length[1] for leg in chain.legs])
            best.append(float(np.minimum(length - lo, hi - length).min(axis=1).max()))
        assert min(best) - 1e-9 <= row["margin"] <= min(best) + 0.5 * step + 1e-9
        assert row["reachable"] == (min(best) >= -0.5 * step)  # no cones: reachable iff a margin >= 0
    assert res.fraction == pytest.approx(np.mean([r["reachable"] for r in res.poses]))
    assert res.margin == min(r["margin"] for r in res.poses) and res.worst["index"] == 3
    assert res.details["unreachable"] == [i for i, r in enumerate(res.poses) if not r["reachable"]]


def test_refusals_name_the_field() -> None:
    mech = preset("6-pups")
    with pytest.raises(ParameterError) as ei:
        evaluate_mechanism_task(mech, Region.parse("sphere", [0, 0, 150, 10]),
                                settings=TaskSettings(joints=Joints(theta_u=30.0)))
    assert ei.value.field == "joints"
    with pytest.raises(ParameterError) as ei:
        evaluate_mechanism_task(mech, Region.parse("sphere", [0, 0, 150, 10]), length_step=0.0)
    assert ei.value.field == "length_step"


def test_cli_task_on_a_mechanism(capsys) -> None:
    from paraspace.app.cli import main

    assert main(["task", "--mechanism", "6-pups", "--box", "0,0,175,60,60,40", "--voxel", "8", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    res = evaluate_mechanism_task(preset("6-pups"), Region.parse("box", [0, 0, 175, 60, 60, 40]),
                                  settings=TaskSettings(voxel=8.0))
    assert out["fraction"] == res.fraction and out["margin"] == res.margin and out["engine"] == "general"
    assert main(["task", "--mechanism", "6-pups", "--box", "0,0,175,60,60,40", "--u-cone", "30"]) == 2
    assert "--u-cone" in capsys.readouterr().err


def test_rest_task_on_a_mechanism() -> None:
    import httpx

    from paraspace.app.api import API_PREFIX, ApiLimits, create_api
    from paraspace.app.jobs import JobManager
    from paraspace.app.serve import start_api

    jobs = JobManager(max_workers=1, max_jobs_total=8, max_jobs_per_client=8, max_seconds=120)
    srv = start_api(create_api(jobs, limits=ApiLimits()), "127.0.0.1", 0)
    try:
        with httpx.Client(base_url=srv.url, timeout=60.0) as http:
            body = {"mechanism": {"preset": "6-pups"}, "poses": [[0, 0, 150, 0, 0, 0], [0, 0, 400, 0, 0, 0]]}
            r = http.post(f"{API_PREFIX}/task", params={"wait": 60}, json=body)
            assert r.status_code == 200, r.text
            out = r.json()["result"]
            ref = evaluate_mechanism_task(preset("6-pups"), PoseList(np.array(body["poses"], float)))
            assert out["fraction"] == 0.5 and out["margin"] == ref.margin and out["unreachable"] == [1]
            for patch, field in (({"design": {"a": 40}}, "design"),
                                 ({"settings": {"joints": {"theta_u": 30}}}, "settings.joints"),
                                 ({"mechanism": {"preset": "6-pups", "params": {"lifts": 1}}}, "mechanism.lifts")):
                r = http.post(f"{API_PREFIX}/task", json={**body, **patch})
                assert r.status_code == 422 and any(d["field"] == field for d in r.json()["detail"]), r.text
    finally:
        jobs.shutdown(wait=False)
        srv.stop()
