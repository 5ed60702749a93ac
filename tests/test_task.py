"""Design for a task (kinematics/task.py): every answer against an independent per-pose brute force.

The oracles are :func:`kinematics.workspace.reachable` on every sample (the engine's documented
per-pose test), the sample sets rebuilt here from the module's definitions (cell centres of the
region, :func:`kinematics.dexterous.orientation_samples`), and leg lengths / joint angles computed
with :mod:`kinematics.inverse` and :func:`kinematics.joints.cone_angles` on a carriage grid.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.dexterous import orientation_samples
from paraspace.kinematics.geometry import base_points, platform_points
from paraspace.kinematics.inverse import leg_lengths
from paraspace.kinematics.joints import Joints, cone_angles
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.rotation import euler_zyx_deg
from paraspace.kinematics.task import (
    MAX_POSES,
    OrientationSet,
    PoseList,
    Region,
    TaskSettings,
    pose_list_task,
    read_pose_csv,
    region_task,
)
from paraspace.kinematics.tilt_torsion import tt_rotation, tt_rotations
from paraspace.kinematics.workspace import reachable

H = 5.0


def _cells(region: Region, h: float) -> np.ndarray:
    """Cell centres inside the region (the module's sampling, rebuilt from its definition)."""
    c = np.asarray(region.center)
    if region.shape == "box":
        ext = np.asarray(region.sizes)
    elif region.shape == "cylinder":
        ext = np.array([2 * region.sizes[0], 2 * region.sizes[0], region.sizes[1]])
    else:
        ext = np.full(3, 2 * region.sizes[0])
    axes = []
    for a in range(3):
        n = max(1, math.ceil(ext[a] / h - 1e-9))
        axes.append(c[a] - ext[a] / 2 + ext[a] / n * (np.arange(n) + 0.5))
    g = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    q = g - c
    if region.shape == "cylinder":
        g = g[np.hypot(q[:, 0], q[:, 1]) <= region.sizes[0] + 1e-9]
    elif region.shape == "sphere":
        g = g[np.linalg.norm(q, axis=1) <= region.sizes[0] + 1e-9]
    return g


def _brute_points(design, pts, oset: OrientationSet, joints) -> np.ndarray:
    if oset.tilt is None and oset.torsion is None:
        rots = [euler_zyx_deg(*oset.fixed)]
    else:
        s = orientation_samples(oset.tilt or 0.0, oset.torsion or 0.0, oset.step)
        rots = [tt_rotation(*row) for row in s]
    ok = np.ones(len(pts), bool)
    for R in rots:
        ok &= reachable(design, pts, R, 0.5, joints)
    return ok


CASES = [
    (Design(), Region("box", (0.0, 0.0, 150.0), (40.0, 30.0, 20.0)), OrientationSet(tilt=10.0, torsion=0.0),
     Joints()),
    (Design(l_s=40.0, eta_s=40.0), Region("cylinder", (10.0, -5.0, 140.0), (30.0, 20.0)),
     OrientationSet(fixed=(10.0, 5.0, 0.0)), Joints(theta_u=40.0, theta_s=45.0)),
    (Design(a=40.0, d_s=30.0), Region("sphere", (0.0, 10.0, 145.0), (25.0,)),
     OrientationSet(tilt=5.0, torsion=10.0, step=5.0), Joints(theta_s=50.0, cone_axis="home")),
    (Design(), Region("box", (60.0, 0.0, 120.0), (30.0, 30.0, 10.0)), OrientationSet(), Joints()),
]


@pytest.mark.parametrize("design,region,oset,joints", CASES)
def test_region_answers_equal_brute_force(design, region, oset, joints):
    res = region_task(design, region, oset, TaskSettings(voxel=H, joints=joints, margin_range=8.0))
    pts = _cells(region, H)
    ok = _brute_points(design, pts, oset, joints)
    assert res.details["sample_points"] == len(pts)
    assert res.fraction == pytest.approx(ok.mean(), abs=1e-12)
    assert res.contained == bool(ok.all())
    # the margin is the signed distance of the nearest unreachable lattice point: non-positive exactly when a
    # sample is unreachable, and inside, the deepest unreachable sample's depth
    if not ok.all():
        assert res.margin <= 0.0
        depth = -region.sdf(pts[~ok]).min()
        assert res.margin == pytest.approx(-depth, abs=1e-9)
        assert res.certified in ("not contained", "undecided")
    else:
        assert res.margin > 0.0
        assert res.certified in ("contained", "undecided")
    if res.certified == "not contained":  # the proven pose is unreachable with a far finer arc
        op = res.details["outside_pose"]
        o = op["orientation"]
        R = tt_rotation(o["azimuth"], o["tilt"], o["torsion"]) if "tilt" in o and "azimuth" in o else \
            euler_zyx_deg(o["psi"], o["theta"], o["phi"])
        assert not reachable(design, np.array([op["position"]]), R, 0.02, joints)[0]
        assert region.sdf(np.array([op["position"]]))[0] <= 1e-9


def test_margin_of_a_contained_sphere_is_the_distance_to_the_nearest_unreachable_point():
    design, region = Design(), Region("sphere", (0.0, 0.0, 140.0), (12.0,))
    res = region_task(design, region, OrientationSet(), TaskSettings(voxel=H, margin_range=40.0))
    assert res.contained and not res.details["margin_saturated"]
    # brute force on the same lattice: every lattice point within 40 of the sphere
    n = math.ceil(24 / H - 1e-9)
    ha = 24 / n
    g = math.ceil(40 / ha - 1e-9)
    ax = [c - 12 + ha * (np.arange(-g, n + g) + 0.5) for c in (0.0, 0.0, 140.0)]
    lat = np.stack(np.meshgrid(*ax, indexing="ij"), -1).reshape(-1, 3)
    s = np.linalg.norm(lat - [0, 0, 140], axis=1) - 12.0
    lat, s = lat[s <= 40 + 1e-9], s[s <= 40 + 1e-9]
    ok = reachable(design, lat)
    assert res.margin == pytest.approx(s[~ok].min(), abs=1e-9)
    assert res.binding["limit"] in ("l_max", "l_min", "sampling")
    assert res.worst["at"]["position"] == pytest.approx(lat[~ok][np.argmin(s[~ok])].tolist())


@pytest.mark.parametrize("joints,size,tilt,step", [
    (Joints(), (16.0, 16.0, 8.0), 4.0, 2.0),
    (Joints(theta_u=40.0, theta_s=40.0, cone_axis="home"), (12.0, 12.0, 6.0), 2.0, 1.0),
])
def test_certified_contained_never_contradicts_dense_sampling(joints, size, tilt, step):
    design = Design()
    region = Region("box", (0.0, 0.0, 140.0), size)
    oset = OrientationSet(tilt=tilt, torsion=tilt, step=step)
    res = region_task(design, region, oset, TaskSettings(voxel=size[2] / 2, margin_range=0.0, joints=joints))
    assert res.certified == "contained"
    rng = np.random.default_rng(7)
    pts = np.asarray(region.center) + (rng.random((400, 3)) - 0.5) * np.asarray(region.sizes)
    corners = np.asarray(region.center) + 0.5 * np.asarray(region.sizes) * np.array(
        [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    pts = np.concatenate([pts, corners])
    az, tl, tor = rng.uniform(0, 360, 30), tilt * np.sqrt(rng.random(30)), rng.uniform(-tilt, tilt, 30)
    tl[:8], tor[:8] = tilt, np.where(np.arange(8) % 2, tilt, -tilt)  # the set's edges
    for R in tt_rotations(az, tl, tor):
        assert reachable(design, pts, R, 0.1, joints).all()


def test_certified_not_contained_for_a_region_partly_outside():
    res = region_task(Design(), Region("box", (0.0, 0.0, 170.0), (20.0, 20.0, 20.0)), OrientationSet(),
                      TaskSettings(voxel=H, margin_range=0.0))
    assert not res.contained and res.certified == "not contained"
    assert res.binding["limit"] == "l_max"


def _path(n: int = 60) -> np.ndarray:
    s = np.linspace(0.0, 1.0, n)
    return np.stack([25 * np.cos(2 * np.pi * s), 25 * np.sin(2 * np.pi * s), 135 + 8 * s, 6 * np.sin(2 * np.pi * s),
                     4 * s, 0 * s], 1)


@pytest.mark.parametrize("joints", [Joints(), Joints(theta_u=45.0, theta_s=45.0)])
def test_pose_list_answers_equal_brute_force_and_carriages_are_feasible(joints):
    design = Design()
    P = _path()
    P = np.concatenate([P, [[0.0, 0.0, 400.0, 0, 0, 0], [90.0, 0.0, 120.0, 0, 0, 0]]])  # two unreachable
    res = pose_list_task(design, PoseList(P), TaskSettings(joints=joints))
    ok = np.array([reachable(design, p[None, :3], euler_zyx_deg(*p[3:]), 0.5, joints)[0] for p in P])
    assert [r["reachable"] for r in res.poses] == ok.tolist()
    assert res.fraction == pytest.approx(ok.mean()) and res.contained is False
    assert res.certified in ("not contained", "undecided")
    assert res.margin < 0 and not res.worst["reachable"]
    lo, hi = design.eta_limits
    for row, p in zip(res.poses, P):
        q = np.array(row["q"])
        d, eta = q[6:9], q[9:12]
        pose = Pose(*p)
        L = leg_lengths(design, pose, d, eta)
        assert np.allclose(L.reshape(6), q[:6])
        assert np.all((d >= -1e-9) & (d <= design.d_s + 1e-9)) and np.all((eta >= lo - 1e-9) & (eta <= hi + 1e-9))
        if row["reachable"]:
            assert L.min() >= design.l_min - 1e-9 and L.max() <= design.l_max + 1e-9
            if joints.has_cones:
                ang = cone_angles(design, joints, pose.rotation, platform_points(design, pose.position, pose.rotation),
                                  base_points(design, d, eta), eta)
                assert ang[:, :, 0].max() <= joints.theta_u + 1e-6 and ang[:, :, 1].max() <= joints.theta_s + 1e-6
    # actuator ranges are the ranges of the reported values
    acts = res.details["actuators"]
    qs = np.array([r["q"] for r in res.poses])[ok]
    assert [a["min"] for a in acts] == pytest.approx(qs.min(axis=0).tolist())
    assert [a["max"] for a in acts] == pytest.approx(qs.max(axis=0).tolist())


def test_continuous_path_has_no_jump_and_travel_matches_the_values():
    """Every pose of the path is served by one constant carriage pose (checked by brute force), so a
    continuous solution exists: no discontinuity, small steps, travel = the sum of the steps."""
    design = Design()
    P = _path(80)
    d0, e0 = np.full(3, 25.0), np.zeros(3)
    for p in P:
        L = leg_lengths(design, Pose(*p), d0, e0)
        assert L.min() > design.l_min + 1 and L.max() < design.l_max - 1
    t = np.linspace(0.0, 8.0, len(P))
    res = pose_list_task(design, PoseList(P, t), TaskSettings())
    assert res.contained and res.certified == "contained"
    assert res.discontinuities == []
    q = np.array([r["q"] for r in res.poses])
    steps_d, steps_e = np.abs(np.diff(q[:, 6:9], axis=0)), np.abs(np.diff(q[:, 9:12], axis=0))
    assert steps_d.max() < 5.0 and steps_e.max() < 5.0
    car = res.details["carriage"]
    assert car["travel_d"] == pytest.approx(steps_d.sum()) and car["travel_eta"] == pytest.approx(steps_e.sum())
    assert car["max_speed_d"] == pytest.approx((steps_d / np.diff(t)[:, None]).max())


def _feasible_set(design, pose, chain, n=121):
    """Carriage poses (d, eta) of a fine grid that put both legs of ``chain`` inside the limits."""
    lo, hi = design.eta_limits
    dd, ee = np.meshgrid(np.linspace(0, design.d_s, n), np.linspace(lo, hi, n), indexing="ij")
    out = np.zeros(dd.shape, bool)
    for a in range(n):
        for b in range(n):
            L = leg_lengths(design, pose, [dd[a, b]] * 3, [ee[a, b]] * 3)[chain]
            out[a, b] = L.min() >= design.l_min and L.max() <= design.l_max
    return out, dd, ee


def test_a_path_without_continuous_solution_reports_the_jump():
    """Two reachable poses whose feasible carriage sets of chain 1 are far apart (brute force on a fine
    grid): the carriages must jump between them, at sample index 1."""
    design = Design()
    p0, p1 = Pose(-60.5, -67.8, 132.7), Pose(-20.1, -4.3, 107.3)
    f0, dd, ee = _feasible_set(design, p0, 0, 61)
    f1, _, _ = _feasible_set(design, p1, 0, 61)
    assert f0.any() and f1.any()
    a = np.stack([dd[f0], ee[f0]], 1)
    b = np.stack([dd[f1], ee[f1]], 1)
    gap = np.min(np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2))
    assert gap > 3.0  # clearly disjoint, not a grid effect
    P = np.array([p0.as_array(), p1.as_array(), p1.as_array()])
    res = pose_list_task(design, PoseList(P), TaskSettings())
    assert res.contained
    assert any(j["index"] == 1 and j["chain"] == 1 for j in res.discontinuities)
    assert all(j["index"] == 1 for j in res.discontinuities)


def test_pose_csv_and_bad_input_name_the_field():
    pl = read_pose_csv("x,y,z,psi,theta,phi,t\n0,0,130,0,0,0,0\n1,0,130,0,0,0,0.5\n")
    assert len(pl) == 2 and pl.t is not None
    with pytest.raises(ParameterError, match="header x,y,z,psi,theta,phi"):
        read_pose_csv("a,b\n1,2\n")
    with pytest.raises(ParameterError, match=r"theta \(row 1\)"):
        read_pose_csv("x,y,z,psi,theta,phi\n0,0,130,0,95,0\n")
    with pytest.raises(ParameterError, match="line 2"):
        read_pose_csv("x,y,z,psi,theta,phi\n0,0,x,0,0,0\n")
    with pytest.raises(ParameterError, match="readable CSV"):
        read_pose_csv("x,y,z,psi,theta,phi\n\"" + "9" * 140_000 + "\",0,0,0,0,0\n")  # over csv's field limit
    with pytest.raises(ParameterError, match="strictly increasing"):
        read_pose_csv("x,y,z,psi,theta,phi,t\n0,0,130,0,0,0,1\n0,0,130,0,0,0,1\n")
    big = "x,y,z,psi,theta,phi\n" + "0,0,130,0,0,0\n" * (MAX_POSES + 1)
    with pytest.raises(ParameterError, match=f"at most {MAX_POSES:,} poses"):
        read_pose_csv(big)
    with pytest.raises(ParameterError, match="LX"):
        Region.parse("box", [0, 0, 130, 10])
    with pytest.raises(ParameterError, match=r"R = -1.0 is invalid: valid range \[0, 10000\]"):
        Region("sphere", (0, 0, 130), (-1.0,))
    with pytest.raises(ParameterError, match="tilt"):
        OrientationSet(tilt=120.0)
    with pytest.raises(ParameterError, match="voxel"):
        TaskSettings(voxel=0.0)


def test_cli_task_json_and_csv(tmp_path, capsys):
    import json

    from paraspace.app import cli

    assert cli.main(["task", "--box", "0,0,150,30,30,20", "--tilt", "5", "--voxel", "5", "--margin-range", "5",
                     "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("fraction", "contained", "certified", "margin", "worst", "binding"):
        assert key in out
    region = Region("box", (0.0, 0.0, 150.0), (30.0, 30.0, 20.0))
    ok = _brute_points(Design(), _cells(region, 5.0), OrientationSet(tilt=5.0), Joints())
    assert out["fraction"] == pytest.approx(ok.mean())
    f = tmp_path / "p.csv"
    f.write_text("x,y,z,psi,theta,phi,t\n0,0,130,0,0,0,0\n5,0,132,2,0,0,0.5\n0,0,400,0,0,0,1\n")
    assert cli.main(["task", "--points", str(f), "--u-cone", "50", "--json", "--csv", str(tmp_path / "o.csv")]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [p["reachable"] for p in out["poses"]] == [True, True, False] and "discontinuities" in out
    assert len(out["poses"][0]["q"]) == 12
    rows = (tmp_path / "o.csv").read_text().splitlines()
    assert len(rows) == 4 and rows[0].startswith("index,t,reachable,leg_slack,l_1^1")
    assert cli.main(["task", "--sphere", "0,0,150,-3"]) == 2
    assert "R = -3.0 is invalid: valid range [0, 10000]" in capsys.readouterr().err
    assert cli.main(["task", "--sphere", "0,0,150,10", "--tilt", "100"]) == 2
    assert "tilt = 100.0 is invalid: valid range [0, 90] degrees" in capsys.readouterr().err
    assert cli.main(["task", "--box", "0,0,150,1,1,1", "--sphere", "0,0,150,1"]) == 2
    assert "exactly one of" in capsys.readouterr().err


def test_rest_task_over_http():
    import time

    import httpx

    from paraspace.app.api import API_PREFIX, ApiLimits, create_api
    from paraspace.app.jobs import JobManager
    from paraspace.app.serve import start_api

    jobs = JobManager(max_workers=1, max_jobs_total=4, max_jobs_per_client=4, max_seconds=120)
    srv = start_api(create_api(jobs, limits=ApiLimits(max_task_samples=200_000)), "127.0.0.1", 0)
    try:
        with httpx.Client(base_url=srv.url, timeout=60.0) as http:
            body = {"region": {"shape": "cylinder", "center": [0, 0, 145], "sizes": [15, 10]},
                    "settings": {"voxel": 5, "margin_range": 5}}
            r = http.post(f"{API_PREFIX}/task", params={"wait": 60}, json=body)
            assert r.status_code in (200, 202), r.text
            job = r.json()["job_id"]
            deadline = time.monotonic() + 60
            while http.get(f"{API_PREFIX}/jobs/{job}").json()["status"] not in ("done", "failed"):
                assert time.monotonic() < deadline
                time.sleep(0.05)
            res = http.get(f"{API_PREFIX}/jobs/{job}/result").json()["result"]
            region = Region("cylinder", (0.0, 0.0, 145.0), (15.0, 10.0))
            ok = reachable(Design(), _cells(region, 5.0))
            assert res["fraction"] == pytest.approx(ok.mean()) and res["contained"] == bool(ok.all())
            r = http.post(f"{API_PREFIX}/task", params={"wait": 60},
                          json={"csv": "x,y,z,psi,theta,phi\n0,0,130,0,0,0\n0,0,400,0,0,0\n"})
            job = r.json()["job_id"]
            while http.get(f"{API_PREFIX}/jobs/{job}").json()["status"] not in ("done", "failed"):
                time.sleep(0.05)
            res = http.get(f"{API_PREFIX}/jobs/{job}/result").json()["result"]
            assert [p["reachable"] for p in res["poses"]] == [True, False]
            r = http.post(f"{API_PREFIX}/task", json={"region": {"shape": "sphere", "center": [0, 0, 140],
                                                                 "sizes": [-2]}})
            assert r.status_code == 422 and "R = -2.0 is invalid: valid range [0, 10000]" in r.text
            r = http.post(f"{API_PREFIX}/task", json={"region": {"shape": "box", "center": [0, 0, 140],
                                                                 "sizes": [300, 300, 300]}})
            assert r.status_code == 413 and "max_task_samples" in r.json()["detail"]
            r = http.post(f"{API_PREFIX}/task", json={"settings": {"voxel": 0.1},
                                                      "region": {"shape": "sphere", "center": [0, 0, 1], "sizes": [1]}})
            assert r.status_code == 422 and "[0.25, 100]" in r.text
            r = http.post(f"{API_PREFIX}/task", json={})
            assert r.status_code == 422 and "exactly one of region, poses or csv" in r.text
    finally:
        jobs.shutdown(wait=False)
        srv.stop()


def test_optimiser_task_measures_and_constraint_match_brute_force():
    from paraspace.kinematics.objectives import MEASURES, parse_constraint
    from paraspace.kinematics.optimize import OptimizeSettings, optimize
    from paraspace.kinematics.task import TaskSpec
    from paraspace.kinematics.workspace import WorkspaceSettings

    region = Region("box", (0.0, 0.0, 140.0), (20.0, 20.0, 10.0))
    spec = TaskSpec(region, OrientationSet(tilt=5.0), TaskSettings(voxel=H, margin_range=5.0))
    with pytest.raises(ParameterError, match="task"):
        OptimizeSettings(objectives="-l_s", constraints=["contains_task"])
    assert MEASURES["contains_task"].flag and parse_constraint("task_margin>=2").measure == "task_margin"
    s = OptimizeSettings(params=("l_s",), bounds={"l_s": (10.0, 60.0)}, objectives="-l_s,task_margin",
                         constraints=["contains_task"], workspace=WorkspaceSettings(voxel=10.0), task=spec,
                         population=4, generations=1, seed=3)
    res = optimize(s).to_dict()
    rows = res["front"]
    assert rows
    pts = _cells(region, H)
    for e in rows:
        d = Design(**e["design"])
        ok = _brute_points(d, pts, OrientationSet(tilt=5.0), Joints())
        assert ok.all()  # the constraint holds by brute force
        assert e["measures"]["l_s"] == d.l_s


def test_patched_task_bound_reaches_core_and_cli(monkeypatch, capsys):
    import dataclasses

    from paraspace.app import cli
    from paraspace.kinematics.design import ParameterError
    from paraspace.kinematics.settings import TASK
    from paraspace.kinematics.task import TaskSettings

    assert TaskSettings(margin_range=50.0).margin_range == 50.0
    monkeypatch.setitem(TASK, "margin_range", dataclasses.replace(TASK["margin_range"], hi=20.0))
    with pytest.raises(ParameterError, match=r"margin_range = 50.0 is invalid: valid range \[0, 20\]"):
        TaskSettings(margin_range=50.0)
    assert cli.main(["task", "--sphere", "0,0,140,5", "--margin-range", "50"]) == 2
    assert "margin_range = 50.0 is invalid: valid range [0, 20]" in capsys.readouterr().err


def test_rest_optimize_takes_a_task():
    from paraspace.app.api.models import OptimizeRequest

    req = OptimizeRequest(params=["l_s"], objectives=["-l_s"], constraints=["contains_task"],
                          settings={"voxel": 10.0, "joints": {"theta_u": 60.0}},
                          task={"region": {"shape": "sphere", "center": [0, 0, 140], "sizes": [5]}, "tilt": 5})
    s = req.build()
    assert s.task_used is not None and s.task.settings.joints.theta_u == 60.0
    assert s.task.orientations.tilt == 5.0 and s.to_dict()["task"]["task"]["shape"] == "sphere"


def test_sweep_rows_carry_the_task_measures():
    from paraspace.kinematics.sweep import sweep_1d
    from paraspace.kinematics.task import TaskSpec
    from paraspace.kinematics.workspace import WorkspaceSettings

    region = Region("sphere", (0.0, 0.0, 140.0), (12.0,))
    spec = TaskSpec(region, OrientationSet(), TaskSettings(voxel=H, margin_range=4.0))
    rows = sweep_1d(Design(), "l_s", [20.0, 50.0], WorkspaceSettings(voxel=10.0), task=spec)
    pts = _cells(region, H)
    for row in rows:
        ok = reachable(Design(l_s=row["value"]), pts)
        assert row["task_fraction"] == pytest.approx(ok.mean()) and row["contains_task"] == bool(ok.all())


def test_patched_task_bound_reaches_the_rest_model():
    import json
    import subprocess
    import sys

    script = (
        "import dataclasses, json\n"
        "from paraspace.kinematics.settings import TASK\n"
        "TASK['margin_range'] = dataclasses.replace(TASK['margin_range'], hi=20.0)\n"
        "from paraspace.app.api import errors, models\n"
        "p = models.TaskSettingsIn.model_json_schema()['properties']['margin_range']\n"
        "print(json.dumps([p['maximum'], errors.RANGES[('settings', 'margin_range')]]))\n")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, check=True)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == [20.0, "[0, 20]"]


def test_binding_names_the_cone_or_the_leg_limit():
    from paraspace.kinematics.task import pose_binding

    design, p, R = Design(), np.array([[0.0, 0.0, 130.0]]), np.eye(3)
    tight = Joints(theta_u=5.0)
    assert reachable(design, p, R) and not reachable(design, p, R, 0.5, tight)[0]
    assert pose_binding(design, p[0], R, tight)["limit"] == "u_cone"
    tight_s = Joints(theta_s=5.0)
    if not reachable(design, p, R, 0.5, tight_s)[0]:
        assert pose_binding(design, p[0], R, tight_s)["limit"] == "s_cone"
    high = np.array([0.0, 0.0, 200.0])
    b = pose_binding(design, high, R, Joints())
    assert b["limit"] == "l_max" and b["chain"] == 1  # every leg is too long: the first chain reports it
    assert pose_binding(design, p[0], R, Joints())["limit"] is None


def test_optimiser_offers_gci_and_total_orientation_volume():
    from paraspace.kinematics.dexterity import dexterity_field
    from paraspace.kinematics.optimize import OptimizeSettings
    from paraspace.kinematics.sweep import evaluate_design
    from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

    s = OptimizeSettings(params=("l_s",), objectives="gci,total_orientation_volume", total_orientation=(10, 0, 5))
    assert s.extra_used == {"dexterity": True, "total_orientation": (10.0, 0.0, 5.0)}
    with pytest.raises(ParameterError, match="tilt"):
        OptimizeSettings(objectives="total_orientation_volume", total_orientation=(100, 0, 5))
    design, ws = Design(), WorkspaceSettings(voxel=10.0)
    row = evaluate_design(design, ws, **s.extra_used)
    res = compute_workspace(design, ws)
    assert row["gci"] == pytest.approx(dexterity_field(res).summary()["gci"])
    pts = res.grid.points()[res.occupancy]  # brute force: reachable at every orientation sample
    ok = np.ones(len(pts), bool)
    for az, tilt, tor in orientation_samples(10.0, 0.0, 5.0):
        ok &= reachable(design, pts, tt_rotation(az, tilt, tor))
    assert row["total_orientation_volume"] == pytest.approx(ok.sum() * 10.0 ** 3)


def test_actuator_usage_maps_against_per_voxel_brute_force():
    from paraspace.kinematics.usage import actuator_usage, usage_summary
    from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

    design, joints = Design(), Joints(theta_u=60.0, cone_axis="home")
    res = compute_workspace(design, WorkspaceSettings(voxel=10.0, joints=joints))
    maps = actuator_usage(res, n_eta=9, n_rho=7)
    assert np.isnan(maps.leg_use[~res.occupancy]).all() and np.isfinite(maps.leg_use[res.occupancy]).all()
    idx = np.argwhere(res.occupancy)[np.random.default_rng(3).choice(int(res.occupancy.sum()), 4, replace=False)]
    lo, hi = design.eta_limits
    etas, ds = np.linspace(lo, hi, 9), design.r - np.linspace(design.r - design.d_s, design.r, 7)
    for ix, iy, iz in idx:
        p = res.grid.points()[ix, iy, iz]
        pose = Pose(*p)
        d, eta = maps.d[:, ix, iy, iz], maps.eta[:, ix, iy, iz]
        for i in range(3):  # the chosen carriage is the grid's best (leg lengths recomputed)
            best = max(min(np.minimum(L - design.l_min, design.l_max - L))
                       for L in (leg_lengths(design, pose, [dd] * 3, [ee] * 3)[i] for ee in etas for dd in ds))
            L = leg_lengths(design, pose, d, eta)[i]
            assert min(np.minimum(L - design.l_min, design.l_max - L)) == pytest.approx(best)
        L = leg_lengths(design, pose, d, eta)
        mid, half = design.l_min + design.l_s / 2, design.l_s / 2
        assert maps.leg_use[ix, iy, iz] == pytest.approx(np.abs(L - mid).max() / half)
        ang = cone_angles(design, joints, np.eye(3), platform_points(design, p, np.eye(3)),
                          base_points(design, d, eta), eta)
        assert maps.joint_angle[ix, iy, iz] == pytest.approx(ang.max())
    summary = usage_summary(maps)
    assert sum(summary["leg_use"]["counts"]) <= int(res.occupancy.sum())
