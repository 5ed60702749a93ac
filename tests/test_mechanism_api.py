"""A mechanism (preset + params, or a description) in ``POST /workspace`` over real HTTP (uvicorn
on a loopback port, httpx as the client), as tests/test_api.py does for the paper's design.

The voxels are checked against the core run in-process (the general engine is tested voxel by
voxel against the brute force in test_mechanism_workspace.py; the paper preset against the
paper's engine); refusals name the field and the limit.
"""

from __future__ import annotations

import io
import json
import time

import httpx
import numpy as np
import pytest

from paraspace.app.api import API_PREFIX, ApiLimits, create_api
from paraspace.app.jobs import JobManager
from paraspace.app.serve import start_api
from paraspace.kinematics.design import Design
from paraspace.kinematics.mechanism import dumps_mechanism
from paraspace.kinematics.mechanism_workspace import compute_mechanism_workspace
from paraspace.kinematics.presets import gough_stewart, six_pss, six_pups
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

V1 = API_PREFIX


@pytest.fixture(scope="module")
def http():
    jobs = JobManager(max_workers=1, max_jobs_total=8, max_jobs_per_client=8, max_seconds=120)
    limits = ApiLimits(max_voxels=200_000, max_jobs_per_client=8)
    srv = start_api(create_api(jobs, explorer_url="http://127.0.0.1:9999", limits=limits), "127.0.0.1", 0)
    with httpx.Client(base_url=srv.url, timeout=60.0) as c:
        yield c
    jobs.shutdown(wait=False)
    srv.stop()


def _result(http, body) -> dict:
    r = http.post(f"{V1}/workspace", params={"wait": 60}, json=body)
    assert r.status_code == 200, r.text
    return r.json()


def test_preset_with_params_is_the_general_engine_and_has_a_shell(http) -> None:
    import trimesh

    out = _result(http, {"mechanism": {"preset": "6-pups", "params": {"lift": 40}}, "settings": {"voxel": 8}})
    res = out["result"]
    ref = compute_mechanism_workspace(six_pups(lift=40.0), WorkspaceSettings(voxel=8.0))
    assert res["engine"] == "general" and res["design"] is None and res["voxels"] == ref.voxels > 100
    assert res["grid"]["shape"] == list(ref.grid.shape)
    assert res["measures"]["volume"] == pytest.approx(ref.volume)
    assert res["mechanism"]["chains"][0]["carriage"][0]["range"] == [0.0, 40.0]
    s = http.get(f"{V1}/workspace/{out['job_id']}/shell.stl")
    assert s.status_code == 200
    assert len(trimesh.load(io.BytesIO(s.content), file_type="stl", force="mesh").faces) > 100


@pytest.mark.parametrize("as_text", [False, True])
def test_a_description_as_object_or_toml_text(http, as_text) -> None:
    mech = six_pss(leg_length=130.0)
    desc = dumps_mechanism(mech) if as_text else mech.to_dict()
    res = _result(http, {"mechanism": {"description": desc},
                         "settings": {"voxel": 8, "orientation": {"psi": 10, "theta": 5, "phi": 0}}})["result"]
    ref = compute_mechanism_workspace(mech, WorkspaceSettings(voxel=8.0, orientation=(10.0, 5.0, 0.0)))
    assert res["voxels"] == ref.voxels > 50 and res["mechanism"] == mech.to_dict()


def test_paper_preset_is_the_paper_engine(http) -> None:
    res = _result(http, {"mechanism": {"preset": "paper", "params": {"a": 60}}, "settings": {"voxel": 9}})["result"]
    ref = compute_workspace(Design(a=60.0), WorkspaceSettings(voxel=9.0))
    assert res["design"]["a"] == 60.0 and res["voxels"] == ref.voxels


def test_bad_mechanisms_name_the_field(http) -> None:
    def detail(body, status=422):
        r = http.post(f"{V1}/workspace", json=body)
        assert r.status_code == status, r.text
        return r.json()["detail"]

    d = detail({"mechanism": {"preset": "6-pups", "params": {"lift": -1}}})[0]
    assert d["field"] == "mechanism.lift" and "[0, 1000]" in d["message"]
    d = detail({"mechanism": {"preset": "gough-stewart", "params": {"a": 3}}})[0]
    assert d["field"] == "mechanism.a" and "a parameter of preset 'gough-stewart'" in d["message"]
    bad = gough_stewart().to_dict()
    bad["chains"][4]["legs"][0]["length"] = [150.0, 120.0]
    d = detail({"mechanism": {"description": bad}})[0]
    assert d["field"] == "mechanism.description.chains[4].legs[0].length" and "low <= high" in d["message"]
    d = detail({"mechanism": {"description": "[[chains]\n"}})[0]
    assert d["field"] == "mechanism.description.mechanism" and "valid TOML" in d["message"]
    assert detail({"mechanism": {"preset": "paper", "description": bad}})[0]["field"] == "mechanism"
    assert detail({"mechanism": {"preset": "6-pups"}, "design": {"a": 40}})[0]["field"] == "design"
    d = detail({"mechanism": {"preset": "6-pups"}, "settings": {"voxel": 8, "diagnostics": True}})[0]
    assert d["field"] == "settings.diagnostics" and "general mechanism" in d["message"]
    d = detail({"mechanism": {"preset": "6-pups", "length_step": 0}})[0]
    assert d["field"] == "mechanism.length_step" and "0.01" in d["message"]


def test_size_limits(http) -> None:
    # a description over 64 KiB (inside the body limit): 413 naming the field
    big = "# padding\n" * 7000 + dumps_mechanism(gough_stewart())
    r = http.post(f"{V1}/workspace", json={"mechanism": {"description": big}})
    assert r.status_code == 413 and "mechanism.description" in r.json()["detail"]
    assert "65,536 bytes" in r.json()["detail"]
    # a body over max_body_bytes: refused before parsing
    r = http.post(f"{V1}/workspace", content=json.dumps({"mechanism": {"description": "#" * 1_500_000}}),
                  headers={"content-type": "application/json"})
    assert r.status_code == 413 and "max_body_bytes" in r.json()["detail"]
    # a grid over max_voxels: 413 with the voxel edge that fits, nothing queued
    r = http.post(f"{V1}/workspace", json={"mechanism": {"preset": "6-pss"}, "settings": {"voxel": 1}})
    assert r.status_code == 413 and "max_voxels = 200000" in r.json()["detail"]
    assert "voxel >= " in r.json()["detail"]
    assert np.isfinite(float(r.json()["detail"].split("voxel >= ")[1].split()[0]))


def test_ik_of_a_mechanism(http) -> None:
    from paraspace.kinematics.rotation import euler_zyx_deg

    r = http.post(f"{V1}/ik", json={"mechanism": {"preset": "6-pups"},
                                    "pose": {"x": 5, "y": 10, "z": 160, "psi": 0, "theta": 8, "phi": 0}})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["feasible"] is True and len(body["chains"]) == 6 and body["condition_number"] >= 1.0
    lengths = six_pups().leg_lengths([c["q"] for c in body["chains"]], (5.0, 10.0, 160.0),
                                     euler_zyx_deg(0.0, 8.0, 0.0))
    np.testing.assert_allclose(lengths, [c["lengths"][0] for c in body["chains"]], atol=1e-9)
    assert np.all((lengths >= 114.5) & (lengths <= 164.5))
    # the paper preset answers as the paper's /ik
    paper_ik = http.post(f"{V1}/ik", json={"mechanism": {"preset": "paper"}, "pose": {"z": 130}}).json()
    assert paper_ik == http.post(f"{V1}/ik", json={"pose": {"z": 130}}).json()
    r = http.post(f"{V1}/ik", json={"mechanism": {"preset": "6-pups"}, "d": [0, 0, 0], "eta": [0, 0, 0]})
    assert r.status_code == 422 and r.json()["detail"][0]["field"] == "d"


def test_carriage_samples_are_bounded(http) -> None:
    """A chain of 36,001 turntable samples (0.01 deg over 360 deg) is refused before any work."""
    data = six_pups().to_dict()
    for chain in data["chains"]:
        chain["carriage"].insert(0, {"type": "revolute", "axis": [0, 0, 1], "range": [-180.0, 180.0]})
    r = http.post(f"{V1}/workspace", json={"mechanism": {"description": data},
                                           "settings": {"voxel": 20, "eta_step": 0.01}})
    assert r.status_code == 413 and "36,001 carriage samples" in r.json()["detail"]
    assert "settings.eta_step" in r.json()["detail"]


def test_presets_endpoint_lists_what_the_requests_take(http) -> None:
    from paraspace.kinematics.presets import PRESETS, preset

    body = http.get(f"{V1}/mechanism/presets").json()
    assert [p["name"] for p in body["presets"]] == list(PRESETS)
    for p in body["presets"]:
        assert p["mechanism"] == preset(p["name"]).to_dict()
        assert {q["name"] for q in p["params"]} == {q.name for q in PRESETS[p["name"]].params}
    pups = next(p for p in body["presets"] if p["name"] == "6-pups")
    lift = next(q for q in pups["params"] if q["name"] == "lift")
    assert (lift["default"], lift["min"], lift["max"]) == (50.0, 0.0, 1000.0)
    # a listed description is accepted back as a request's mechanism
    res = _result(http, {"mechanism": {"description": pups["mechanism"]}, "settings": {"voxel": 10}})["result"]
    assert res["voxels"] == compute_mechanism_workspace(six_pups(), WorkspaceSettings(voxel=10.0)).voxels


ORIENT = {"angle_range": 60, "angle_step": 10, "position_step": 12, "z0": 150}


def test_orientation_of_a_mechanism(http) -> None:
    """``POST /orientation`` with a mechanism: the core's scans (tested per sample against the brute
    force in test_mechanism_orientation.py); the paper preset the paper path's indices."""
    from paraspace.kinematics.mechanism_orientation import mechanism_orientation_workspace
    from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace

    scan = OrientationSettings(angle_range=60.0, angle_step=10.0, position_step=12.0, z0=150.0)
    r = http.post(f"{V1}/orientation", params={"wait": 60},
                  json={"mechanism": {"preset": "6-pups", "params": {"lift": 40}}, "settings": ORIENT})
    assert r.status_code == 200, r.text
    res = r.json()["result"]
    ref = mechanism_orientation_workspace(six_pups(lift=40.0), scan)
    assert res["engine"] == "general" and res["symmetry_order"] == 3
    assert (res["TI_1"], res["TI_2"]) == (ref.ti1, ref.ti2) and res["TI_1"] > 0
    r = http.post(f"{V1}/orientation", params={"wait": 60}, json={"mechanism": {"preset": "paper"}, "settings": ORIENT})
    assert r.status_code == 200, r.text
    paper = orientation_workspace(Design(), scan)
    assert (r.json()["result"]["TI_1"], r.json()["result"]["TI_2"]) == (paper.ti1, paper.ti2)


def test_orientation_refusals_name_the_field(http) -> None:
    def detail(body, status=422):
        r = http.post(f"{V1}/orientation", json=body)
        assert r.status_code == status, r.text
        return r.json()["detail"]

    d = detail({"mechanism": {"preset": "6-pups"}, "settings": {**ORIENT, "joints": {"theta_u": 30}}})[0]
    assert d["field"] == "settings.joints" and "u_cone/s_cone" in d["message"]
    assert detail({"mechanism": {"preset": "6-pups"}, "design": {"a": 40}})[0]["field"] == "design"
    assert detail({"mechanism": {"preset": "6-pups", "params": {"lift": -1}}})[0]["field"] == "mechanism.lift"
    d = detail({"mechanism": {"preset": "6-pups"}, "settings": {"angle_step": 0.01, "position_step": 0.01}}, 413)
    assert "max_orientation_samples" in d


def test_a_cancelled_bracket_frees_its_worker_and_the_kernels() -> None:
    """A general mechanism's certified bracket over HTTP is a job like any other: cancelled mid-way
    (DELETE), it stops at its next launch, and the next request computes at once. Before, the whole
    bracket ran as one step holding the kernel lock: 6-pss at voxel 2, refine 3 (2.3 M voxels, 79-173 s
    on the 2-core machine) kept the one worker and every kernel of the server busy after the cancel, and the
    next request waited for it (it was not done within this test's 60 s)."""
    jobs = JobManager(max_workers=1, max_jobs_total=8, max_jobs_per_client=8, max_seconds=600)
    srv = start_api(create_api(jobs, explorer_url="http://127.0.0.1:9999", limits=ApiLimits(max_voxels=3_000_000)),
                    "127.0.0.1", 0)
    try:
        with httpx.Client(base_url=srv.url, timeout=60.0) as c:
            r = c.post(f"{V1}/workspace", params={"wait": 0},
                       json={"mechanism": {"preset": "6-pss"},
                             "settings": {"voxel": 2, "bracket": True, "bracket_refine": 3}})
            assert r.status_code == 202, r.text
            job = r.json()["job_id"]
            deadline = time.monotonic() + 120.0
            while "certified bracket: refining" not in (st := c.get(f"{V1}/jobs/{job}").json())["message"]:
                assert st["status"] in ("queued", "running") and time.monotonic() < deadline, st
                time.sleep(0.05)
            d = c.delete(f"{V1}/jobs/{job}")
            assert d.status_code == 200 and d.json()["status"] == "cancelled"
            nxt = c.post(f"{V1}/workspace", params={"wait": 60},
                         json={"mechanism": {"preset": "6-pups"}, "settings": {"voxel": 8}})
            assert nxt.status_code == 200 and nxt.json()["job"]["status"] == "done", nxt.text[:300]
    finally:
        jobs.shutdown(wait=False)
        srv.stop()
