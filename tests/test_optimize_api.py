"""POST /api/v1/optimize over real HTTP: a job like the sweeps, same result as the core, cached
on repeat, limits (413), bad input (422 naming the field)."""

from __future__ import annotations

import time

import httpx
import pytest

from paraspace.app.api import API_PREFIX, ApiLimits, create_api
from paraspace.app.jobs import JobManager
from paraspace.app.serve import start_api
from paraspace.kinematics.design import Design
from paraspace.kinematics.optimize import OptimizeSettings, optimize
from paraspace.kinematics.workspace import WorkspaceSettings

V1 = API_PREFIX
BODY = {"params": ["a", "l_s"], "objectives": ["volume", "-footprint"], "constraints": ["boundary_complete"],
        "bounds": {"l_s": [20, 100]}, "population": 6, "generations": 2, "seed": 7, "settings": {"voxel": 10}}


@pytest.fixture(scope="module")
def http():
    jobs = JobManager(max_workers=2, max_jobs_total=16, max_jobs_per_client=8, max_seconds=120)
    limits = ApiLimits(max_optimize_evaluations=200, max_optimize_voxels=50_000_000)
    srv = start_api(create_api(jobs, limits=limits), "127.0.0.1", 0)
    with httpx.Client(base_url=srv.url, timeout=60.0) as c:
        yield c
    jobs.shutdown(wait=False)
    srv.stop()


def _poll(http: httpx.Client, job_id: str, timeout: float = 60.0) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        st = http.get(f"{V1}/jobs/{job_id}").json()
        if st["status"] in ("done", "failed", "cancelled") or time.monotonic() > deadline:
            return st
        time.sleep(0.05)


def test_optimize_job_matches_core_and_is_cached(http):
    r = http.post(f"{V1}/optimize", json=BODY)
    assert r.status_code in (200, 202), r.text
    job = r.json()
    assert _poll(http, job["job_id"])["status"] == "done"
    res = http.get(f"{V1}/jobs/{job['job_id']}/result").json()["result"]
    core = optimize(OptimizeSettings(params=("a", "l_s"), objectives="volume,-footprint",
                                     constraints=["boundary_complete"], bounds={"l_s": (20.0, 100.0)},
                                     population=6, generations=2, seed=7, design=Design(),
                                     workspace=WorkspaceSettings(voxel=10.0))).to_dict()
    assert res["front"] == core["front"] and res["hypervolume"] == core["hypervolume"]
    assert res["settings"] == core["settings"]
    again = http.post(f"{V1}/optimize", json=BODY, params={"wait": 5})
    assert again.status_code == 200 and again.json()["cached"] is True
    assert again.json()["result"]["front"] == res["front"]
    assert "/api/v1/optimize" in http.get("/openapi.json").json()["paths"]


@pytest.mark.parametrize("patch, field", [
    ({"objectives": ["volume", "-nope"]}, "objectives"),
    ({"constraints": ["volume"]}, "constraint"),
    ({"params": ["a", "zz"]}, "params"),
    ({"bounds": {"l_s": [90, 20]}}, "l_s"),
    ({"population": 2}, "population"),
    ({"settings": {"voxel": 0.01}}, "settings.voxel"),
])
def test_bad_input_422_names_field(http, patch, field):
    r = http.post(f"{V1}/optimize", json={**BODY, **patch})
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    assert any(field in d["field"] for d in detail), detail


def test_limits_413(http):
    r = http.post(f"{V1}/optimize", json={**BODY, "population": 20, "generations": 20})
    assert r.status_code == 413 and "max_optimize_evaluations" in r.json()["detail"]
    r = http.post(f"{V1}/optimize", json={**BODY, "settings": {"voxel": 1.0}})
    assert r.status_code == 413 and "max_optimize_voxels" in r.json()["detail"]


PRESET_BODY = {"mechanism": {"preset": "6-pups", "params": {"platform_half_angle": 20}},
               "params": ["lift", "platform_radius"], "objectives": ["volume", "-lift"],
               "population": 4, "generations": 2, "seed": 3, "settings": {"voxel": 16}}


def test_optimize_a_preset_matches_core(http):
    r = http.post(f"{V1}/optimize", json=PRESET_BODY)
    assert r.status_code in (200, 202), r.text
    job_id = r.json()["job_id"]
    assert _poll(http, job_id)["status"] == "done"
    res = http.get(f"{V1}/jobs/{job_id}/result").json()["result"]
    core = optimize(OptimizeSettings(preset="6-pups", preset_values={"platform_half_angle": 20.0},
                                     params=("lift", "platform_radius"), objectives="volume,-lift",
                                     population=4, generations=2, seed=3, workspace=WorkspaceSettings(voxel=16.0)))
    assert [e["design"] for e in res["front"]] == [e["design"] for e in core.front]
    assert [e["measures"]["volume"] for e in res["front"]] == [e["measures"]["volume"] for e in core.front]
    assert res["settings"]["mechanism"] == "6-pups"


@pytest.mark.parametrize("patch, field", [
    ({"params": ["lift", "a"]}, "params"),
    ({"objectives": ["volume", "TI_1"]}, "objectives"),
    ({"mechanism": {"preset": "6-pups", "params": {"lifts": 3}}}, "lifts"),
    ({"mechanism": {"description": {"chains": []}}}, "mechanism.preset"),
    ({"design": {"a": 40}}, "design"),
])
def test_optimize_a_preset_bad_input_422_names_field(http, patch, field):
    r = http.post(f"{V1}/optimize", json={**PRESET_BODY, **patch})
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    assert any(field in d["field"] for d in detail), detail


def test_optimize_a_preset_over_the_voxel_limit_413(http):
    r = http.post(f"{V1}/optimize", json={**PRESET_BODY, "settings": {"voxel": 1.0}})
    assert r.status_code == 413 and "max_optimize_voxels" in r.json()["detail"], r.text
