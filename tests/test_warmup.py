"""No request compiles (trust item 9): after kinematics.warmup.warm_up(), requests over real HTTP
that reach every engine option (joint cones about both axes, leg interference, the bracket, the
dense engine, orientation, inverse kinematics, tasks), the measures of a grid fine enough for the
feature filter's dilations, a shell download over its face budget, and the explorer's jobs on that
grid (its measures, display shell and dexterity colours) add no compiled signature to any numba
kernel."""

from __future__ import annotations

import importlib
import pkgutil
import time

import httpx
from numba.core.registry import CPUDispatcher

import paraspace.kinematics as core
from paraspace.app.api import API_PREFIX, create_api
from paraspace.app.explorer.workspace_job import make_shell as explorer_shell
from paraspace.app.explorer.workspace_job import measure as explorer_measures
from paraspace.app.jobs import JobManager
from paraspace.app.serve import start_api
from paraspace.kinematics.design import Design
from paraspace.kinematics.dexterity import dexterity_field
from paraspace.kinematics.warmup import warm_up
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


def _compiled() -> dict[str, int]:
    out: dict[str, int] = {}
    for info in pkgutil.iter_modules(core.__path__):
        mod = importlib.import_module(f"paraspace.kinematics.{info.name}")
        for name, obj in vars(mod).items():
            if isinstance(obj, CPUDispatcher):
                out[f"{info.name}.{name}"] = len(obj.overloads)
    return out


def _wait(http: httpx.Client, job_id: str) -> dict:
    deadline = time.monotonic() + 300
    while True:
        st = http.get(f"{API_PREFIX}/jobs/{job_id}").json()
        if st["status"] in ("done", "failed", "cancelled"):
            return st
        assert time.monotonic() < deadline, f"job {job_id} did not finish within 300 s: {st}"
        time.sleep(0.05)


def test_requests_after_warm_up_compile_nothing() -> None:
    warm_up()
    before = _compiled()
    assert before["workspace._points_kernel"] >= 1, "the warm-up ran the kernels"
    jobs = JobManager(max_workers=1)
    srv = start_api(create_api(jobs), "127.0.0.1", 0)
    try:
        with httpx.Client(base_url=srv.url, timeout=120) as http:
            for joints in ({"theta_u": 30, "theta_s": 40, "cone_axis": "home"}, {"theta_u": 45},
                           {"leg_diameter": 10, "clearance": 1}):
                r = http.post(f"{API_PREFIX}/ik", json={"pose": {"z": 130, "psi": 5}, "joints": joints})
                assert r.status_code == 200, r.text
                bracket = "leg_diameter" not in joints  # the bracket does not model interference
                r = http.post(f"{API_PREFIX}/workspace", json={"settings": {"voxel": 12, "joints": joints,
                                                                             "bracket": bracket, "bracket_refine": 0}})
                assert r.status_code in (200, 202), r.text  # 200: done before the answer
                assert _wait(http, r.json()["job_id"])["status"] == "done"
            r = http.post(f"{API_PREFIX}/workspace", json={"settings": {"voxel": 12, "method": "dense",
                                                                         "orientation": {"psi": 10}}})
            assert _wait(http, r.json()["job_id"])["status"] == "done"
            # voxel 4: the feature radius (2 % of the extent) is over one voxel, so the measures run the
            # packed dilations; the shell at 500 faces is decimated
            job_id = http.post(f"{API_PREFIX}/workspace", json={"settings": {"voxel": 4}}).json()["job_id"]
            assert _wait(http, job_id)["status"] == "done"
            measures = http.get(f"{API_PREFIX}/workspace/{job_id}").json()["measures"]
            assert measures["feature_radius_voxels"] >= 1.0, measures
            r = http.get(f"{API_PREFIX}/workspace/{job_id}/shell.glb", params={"max_faces": 500})
            assert r.status_code == 200, r.text
            r = http.post(f"{API_PREFIX}/orientation", json={"settings": {"angle_step": 15, "position_step": 20}})
            assert r.status_code in (200, 202), r.text  # 200: done before the answer
            assert _wait(http, r.json()["job_id"])["status"] == "done"
            for body in ({"region": {"shape": "box", "center": [0, 0, 140], "sizes": [10, 10, 6]}, "tilt": 5,
                          "settings": {"voxel": 5, "margin_range": 5, "joints": {"theta_u": 45}}},
                         {"region": {"shape": "sphere", "center": [0, 0, 170], "sizes": [8]},
                          "settings": {"voxel": 8, "margin_range": 0}},
                         {"csv": "x,y,z,psi,theta,phi\n0,0,130,0,0,0\n5,0,132,3,0,0\n0,0,400,0,0,0\n"}):
                r = http.post(f"{API_PREFIX}/task", json=body)
                assert r.status_code in (200, 202), r.text  # 200: done before the answer
                assert _wait(http, r.json()["job_id"])["status"] == "done"
    finally:
        jobs.shutdown(wait=False)
        srv.stop()
    # the explorer's job on a real grid: its measures, its display shell from the block means (a
    # re-mesh budget under the full mesh's faces, as on every grid the explorer shows) and its
    # dexterity colours (the default design at zero orientation: the field's mirror path)
    res = compute_workspace(Design(), WorkspaceSettings(voxel=4.0))
    explorer_measures(res)
    dexterity_field(res, 0.005)
    shell = explorer_shell(res, max_faces=2000)
    assert "block re-mesh" in shell.metadata["paraspace"]["reduction"], shell.metadata["paraspace"]
    after = _compiled()
    grown = {k: (before.get(k, 0), v) for k, v in after.items() if v > before.get(k, 0)}
    assert not grown, f"kernels compiled inside a request (before, after): {grown}"
