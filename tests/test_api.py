"""The REST API over real HTTP: uvicorn on a free loopback port in a thread, httpx as the client."""

from __future__ import annotations

import io
import time

import httpx
import pytest

from paraspace.app.api import API_PREFIX, ApiLimits, create_api, decode_link_token, encode_link_token
from paraspace.app.jobs import JobManager
from paraspace.app.serve import start_api

V1 = API_PREFIX


@pytest.fixture(scope="module")
def server():
    jobs = JobManager(max_workers=2, max_jobs_total=16, max_jobs_per_client=8, max_seconds=120)
    limits = ApiLimits(max_voxels=3_000_000, max_sweep_points=12, max_jobs_per_client=4)
    app = create_api(jobs, explorer_url="http://127.0.0.1:9999", limits=limits)
    srv = start_api(app, "127.0.0.1", 0)
    yield srv
    jobs.shutdown(wait=False)
    srv.stop()


@pytest.fixture(scope="module")
def http(server):
    with httpx.Client(base_url=server.url, timeout=60.0) as c:
        yield c


def _poll(http: httpx.Client, job_id: str, timeout: float = 60.0) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        st = http.get(f"{V1}/jobs/{job_id}").json()
        if st["status"] in ("done", "failed", "cancelled") or time.monotonic() > deadline:
            return st
        time.sleep(0.02)


def _wait_running(http: httpx.Client, job_id: str, timeout: float = 120.0) -> None:
    """Until the job has started (its worker is computing), or fail saying what was awaited."""
    deadline = time.monotonic() + timeout
    while http.get(f"{V1}/jobs/{job_id}").json()["status"] == "queued":
        assert time.monotonic() < deadline, f"job {job_id} did not start within {timeout:g} s"
        time.sleep(0.02)


def test_health_and_docs(http):
    r = http.get(f"{V1}/health")
    assert r.status_code == 200
    body = r.json()
    assert body["status"] == "ok" and body["limits"]["max_voxels"] == 3_000_000
    assert http.get("/docs").status_code == 200
    spec = http.get("/openapi.json").json()
    paths = set(spec["paths"])
    for p in ("/health", "/design/defaults", "/ik", "/workspace", "/workspace/{job_id}",
              "/workspace/{job_id}/shell.{fmt}", "/orientation", "/sweep", "/jobs/{job_id}",
              "/jobs/{job_id}/result", "/links"):
        assert V1 + p in paths, p
    assert "/s" in paths and "/s/{token}" in paths
    # the model ranges of the design are in the schema
    a = spec["components"]["schemas"]["DesignIn"]["properties"]["a"]
    assert a["minimum"] == 1e-6 and a["maximum"] == 1000.0


def test_design_defaults(http):
    from paraspace.kinematics.design import PARAMS, Design

    body = http.get(f"{V1}/design/defaults").json()
    assert body["defaults"] == Design().to_dict()
    for name, spec in PARAMS.items():
        f = body["fields"][name]
        assert (f["default"], f["slider_min"], f["slider_max"]) == (spec.default, spec.slider_min, spec.slider_max)
    assert body["eta_range"]["options"] == ["centered", "from-zero"]


def test_ik_default_pose_feasible(http):
    r = http.post(f"{V1}/ik", json={"pose": {"x": 0, "y": 0, "z": 130}})
    assert r.status_code == 200, r.text
    res = r.json()
    assert res["feasible"] is True
    assert len(res["d"]) == 3 and len(res["eta"]) == 3 and len(res["lengths"]) == 3
    lmin, lmax = 114.5, 164.5
    assert all(lmin - 1e-6 <= l <= lmax + 1e-6 for row in res["lengths"] for l in row)
    # hand-set carriages: the same IK evaluated at the resolved carriages is also feasible
    r2 = http.post(f"{V1}/ik", json={"pose": {"z": 130}, "d": res["d"], "eta": res["eta"]})
    assert r2.status_code == 200 and r2.json()["feasible"] is True and r2.json()["mode"] == "manual"
    # a pose far away is answered (not an error) and reported infeasible
    r3 = http.post(f"{V1}/ik", json={"pose": {"z": 1000}})
    assert r3.status_code == 200 and r3.json()["feasible"] is False and r3.json()["message"]


@pytest.mark.parametrize("body, field, rng", [
    ({"design": {"a": -5}}, "design.a", "[1e-06, 1000]"),
    ({"design": {"eta_s": 500}}, "design.eta_s", "[0, 180]"),
    ({"design": {"d_s": 150}}, "design.d_s", "[0, r=100]"),  # cross-field, from the core
    ({"pose": {"theta": 91}}, "pose.theta", "[-90, 90]"),
    ({"pose": {"z": "high"}}, "pose.z", "[-10000, 10000]"),
    ({"d": [0, 0, 60], "eta": [0, 0, 0]}, "carriage.d_3", "[0, d_s=50]"),
])
def test_ik_bad_input_422_names_field_and_range(http, body, field, rng):
    r = http.post(f"{V1}/ik", json=body)
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    assert isinstance(detail, list) and detail
    hit = [d for d in detail if d["field"] == field]
    assert hit, detail
    assert rng in hit[0]["message"] and "valid range" in hit[0]["message"]
    assert "Traceback" not in r.text


def test_unknown_field_and_bad_json_are_422(http):
    r = http.post(f"{V1}/ik", json={"design": {"aa": 1}})
    assert r.status_code == 422 and r.json()["detail"][0]["field"] == "design.aa"
    r = http.post(f"{V1}/ik", content=b"{not json", headers={"content-type": "application/json"})
    assert r.status_code == 422 and r.json()["detail"][0]["field"] == "body"


def test_workspace_job_measures_and_shells(http):
    import trimesh

    r = http.post(f"{V1}/workspace", json={"settings": {"voxel": 8}})
    assert r.status_code in (200, 202), r.text
    job_id = r.json()["job_id"]
    st = _poll(http, job_id)
    assert st["status"] == "done", st
    assert st["progress"] == 1.0
    m = http.get(f"{V1}/workspace/{job_id}")
    assert m.status_code == 200
    body = m.json()
    assert body["volume"] > 0 and body["voxels"] > 0
    assert body["measures"]["volume"] == pytest.approx(body["volume"])
    generic = http.get(f"{V1}/jobs/{job_id}/result").json()
    assert generic["result"]["volume"] == body["volume"]
    for fmt, ftype in (("stl", "stl"), ("ply", "ply"), ("glb", "glb"), ("obj", "obj")):
        t0 = time.perf_counter()
        s = http.get(f"{V1}/workspace/{job_id}/shell.{fmt}")
        print(f"shell.{fmt}: {len(s.content)} bytes in {1e3 * (time.perf_counter() - t0):.0f} ms")
        assert s.status_code == 200, s.text
        assert "attachment" in s.headers["content-disposition"]
        mesh = trimesh.load(io.BytesIO(s.content), file_type=ftype, force="mesh")
        assert len(mesh.faces) > 100 and mesh.bounds is not None
        # the shell lies within the grid box
        lo, hi = body["grid"]["lo"], body["grid"]["hi"]
        assert all(mesh.bounds[0][i] >= lo[i] - 8 and mesh.bounds[1][i] <= hi[i] + 8 for i in range(3))
    assert http.get(f"{V1}/workspace/{job_id}/shell.xyz").status_code == 422
    dec = http.get(f"{V1}/workspace/{job_id}/shell.stl", params={"max_faces": 500})
    assert dec.status_code == 200
    small = trimesh.load(io.BytesIO(dec.content), file_type="stl", force="mesh")
    assert len(small.faces) <= 500


def test_workspace_cached_and_wait(http):
    t0 = time.perf_counter()
    r1 = http.post(f"{V1}/workspace", params={"wait": 30}, json={"settings": {"voxel": 9}})
    t1 = time.perf_counter()
    r2 = http.post(f"{V1}/workspace", params={"wait": 30}, json={"settings": {"voxel": 9}})
    t2 = time.perf_counter()
    print(f"workspace h=9: first {1e3 * (t1 - t0):.0f} ms, cached {1e3 * (t2 - t1):.0f} ms")
    assert r1.status_code == 200 and r2.status_code == 200
    assert r1.json()["cached"] is False and r2.json()["cached"] is True
    assert r1.json()["result"]["volume"] == r2.json()["result"]["volume"] > 0


def test_workspace_over_voxel_limit_refused(http):
    r = http.post(f"{V1}/workspace", json={"settings": {"voxel": 1}})
    assert r.status_code == 413
    assert "max_voxels = 3000000" in r.json()["detail"]
    r = http.post(f"{V1}/workspace", json={"settings": {"voxel": 0.5, "bounds": {"lo": [-500, -500, 0],
                                                                                 "hi": [500, 500, 500]}}})
    assert r.status_code == 413
    assert http.get(f"{V1}/jobs").json()["jobs"] == []  # nothing was queued


def test_bad_settings_422(http):
    r = http.post(f"{V1}/workspace", json={"settings": {"voxel": 0.1}})
    assert r.status_code == 422
    d = r.json()["detail"][0]
    assert d["field"] == "settings.voxel" and "[0.25, 100]" in d["message"]
    r = http.post(f"{V1}/workspace", json={"settings": {"bounds": {"lo": [0, 0, 0], "hi": [0, 10, 10]}}})
    assert r.status_code == 422 and r.json()["detail"][0]["field"] == "settings.bounds"


def test_orientation_job(http):
    r = http.post(f"{V1}/orientation", params={"wait": 60},
                  json={"settings": {"angle_step": 3, "position_step": 5}})
    assert r.status_code in (200, 202), r.text
    st = _poll(http, r.json()["job_id"])
    assert st["status"] == "done"
    res = http.get(f"{V1}/jobs/{st['id']}/result").json()["result"]
    assert res["TI_1"] > 0 and res["TI_2"] > 0 and len(res["regions"]) == 9
    r = http.post(f"{V1}/orientation", json={"settings": {"angle_step": 0.01, "position_step": 0.01}})
    assert r.status_code == 413 and "max_orientation_samples" in r.json()["detail"]
    r = http.post(f"{V1}/orientation", json={"settings": {"delta": "volume"}})
    assert r.status_code == 422 and "extent" in r.json()["detail"][0]["message"]


def test_sweep_1d_and_2d(http):
    pytest.importorskip("paraspace.kinematics.sweep")
    r = http.post(f"{V1}/sweep", params={"wait": 60},
                  json={"settings": {"voxel": 10}, "x": {"param": "a", "values": [40, 50, 60]}})
    assert r.status_code in (200, 202), r.text
    st = _poll(http, r.json()["job_id"], 120)
    assert st["status"] == "done", st
    res = http.get(f"{V1}/jobs/{st['id']}/result").json()["result"]
    assert res["mode"] == "1d" and len(res["points"]) == 3
    r = http.post(f"{V1}/sweep", params={"wait": 60},
                  json={"settings": {"voxel": 12}, "x": {"param": "a", "n": 2}, "y": {"param": "l_s", "n": 2}})
    assert r.status_code in (200, 202), r.text
    st = _poll(http, r.json()["job_id"], 120)
    assert st["status"] == "done", st
    res = http.get(f"{V1}/jobs/{st['id']}/result").json()["result"]
    assert res["mode"] == "2d" and res["param_x"] == "a" and res["param_y"] == "l_s"
    # limits and bad input
    r = http.post(f"{V1}/sweep", json={"x": {"param": "a", "n": 5}, "y": {"param": "b", "n": 5}})
    assert r.status_code == 413 and "max_sweep_points = 12" in r.json()["detail"]
    r = http.post(f"{V1}/sweep", json={"x": {"param": "a", "values": [50, -1]}})
    assert r.status_code == 422
    assert r.json()["detail"][0]["field"] == "x.values[1]" and "valid range" in r.json()["detail"][0]["message"]
    r = http.post(f"{V1}/sweep", json={"x": {"param": "zz", "n": 3}})
    assert r.status_code == 422 and r.json()["detail"][0]["field"] == "x.param"


def test_jobs_cancel_and_unknown(http):
    # about 2.6M voxels with a fine arc sampling: several seconds, well below the limits
    r = http.post(f"{V1}/workspace", json={"settings": {"voxel": 2.0, "eta_step": 0.02, "method": "dense"}})
    assert r.status_code == 202, r.text
    job_id = r.json()["job_id"]
    _wait_running(http, job_id)
    d = http.delete(f"{V1}/jobs/{job_id}")
    assert d.status_code == 200 and d.json()["cancelled"] is True
    assert d.json()["status"] == "cancelled", "the DELETE answer reports the job as it ends, not 'running'"
    st = _poll(http, job_id)
    assert st["status"] == "cancelled"
    res = http.get(f"{V1}/jobs/{job_id}/result")
    assert res.status_code == 409 and "cancelled" in res.json()["detail"]
    assert http.get(f"{V1}/jobs/0123456789abcdef").status_code == 404
    assert http.delete(f"{V1}/jobs/0123456789abcdef").status_code == 404
    assert http.get(f"{V1}/workspace/0123456789abcdef").status_code == 404
    assert http.get(f"{V1}/health").status_code == 200


def test_per_client_job_limit_429(server):
    """Five slow jobs from one client: the fifth is refused at once with 429; cancel frees them."""
    with httpx.Client(base_url=server.url, timeout=30) as c:
        ids = []
        codes = []
        for i in range(5):
            r = c.post(f"{V1}/workspace", json={"settings": {"voxel": 2.01 + 0.01 * i, "eta_step": 0.02, "method": "dense"}})
            codes.append(r.status_code)
            if r.status_code == 202:
                ids.append(r.json()["job_id"])
            else:
                assert r.status_code == 429
                assert "max_jobs_per_client = 4" in r.json()["detail"]
                assert r.headers.get("retry-after")
        assert codes == [202, 202, 202, 202, 429]
        for j in ids:
            c.delete(f"{V1}/jobs/{j}")
        for j in ids:
            assert _poll(c, j)["status"] == "cancelled"


def test_short_links(http):
    r = http.get("/s", params={"a": 60, "z": 120}, follow_redirects=False)
    assert r.status_code == 307
    assert r.headers["location"] == "http://127.0.0.1:9999/?a=60&z=120"
    r = http.get("/s?a=-60", follow_redirects=False)
    assert r.status_code == 422 and any(d["field"] == "a" for d in r.json()["detail"])
    made = http.post(f"{V1}/links", json={"query": "a=60&l_s=40"}).json()
    assert made["path"].startswith("/s/")
    r = http.get(made["path"], follow_redirects=False)
    assert r.status_code == 307 and r.headers["location"] == "http://127.0.0.1:9999/?a=60&l_s=40"
    assert http.get("/s/not-a-token", follow_redirects=False).status_code == 404
    q = "a=60&b=14&d_s=40&r=100&l_min=114.5&l_s=50&eta_s=30&x=0&y=0&z=130&psi=0&theta=0&phi=0"
    assert decode_link_token(encode_link_token(q)) == q


def test_body_too_large_413(http):
    big = {"x": {"param": "a", "values": [50.0] * 300_000}}  # 1.5 MB, over the default 1 MB + 64 KiB
    r = http.post(f"{V1}/sweep", json=big)
    assert r.status_code == 413 and "max_body_bytes" in r.json()["detail"]
    assert http.get(f"{V1}/health").status_code == 200


@pytest.mark.slow
def test_serve_starts_explorer_and_api_and_stops():
    """serve(block=False): both servers answer on loopback, short links point at the explorer's real
    port, stop() closes both ports."""
    from paraspace.app.serve import serve

    running = serve("127.0.0.1", 0, 0, block=False, quiet=True)
    try:
        assert running.explorer_url and running.api_url.startswith("http://127.0.0.1:")
        assert httpx.get(f"{running.api_url}{V1}/health", timeout=10).status_code == 200
        page = httpx.get(running.explorer_url, timeout=10)
        assert page.status_code == 200 and "<html" in page.text.lower()
        r = httpx.get(f"{running.api_url}/s", params={"a": 60}, follow_redirects=False, timeout=10)
        assert r.status_code == 307 and r.headers["location"] == running.explorer_url.rstrip("/") + "/?a=60"
        # explorer and API share one JobManager
        assert running.explorer.jobs is running.jobs
    finally:
        running.stop()
        running.stop()  # idempotent
    with pytest.raises(httpx.HTTPError):
        httpx.get(f"{running.api_url}{V1}/health", timeout=2)


def test_result_cache_bounds_memory():
    """With a result cache of ~one coarse grid the older workspace loses its voxel grid (shell: 409
    with the reason) but keeps its measures."""
    jobs = JobManager(max_workers=1)
    srv = start_api(create_api(jobs, limits=ApiLimits(cache_bytes=30_000)), "127.0.0.1", 0)
    try:
        with httpx.Client(base_url=srv.url, timeout=60) as c:
            a = c.post(f"{V1}/workspace", params={"wait": 30}, json={"settings": {"voxel": 13}}).json()
            b = c.post(f"{V1}/workspace", params={"wait": 30}, json={"settings": {"voxel": 14}}).json()
            assert a["status"] == b["status"] == "done"
            assert c.get(f"{V1}/workspace/{b['job_id']}/shell.stl").status_code == 200
            old = c.get(f"{V1}/workspace/{a['job_id']}/shell.stl")
            assert old.status_code == 409 and "evicted" in old.json()["detail"]
            assert c.get(f"{V1}/workspace/{a['job_id']}").json()["volume"] > 0
    finally:
        jobs.shutdown()
        srv.stop()


def test_limits_hold_under_concurrent_submissions(server):
    """10 simultaneous submissions of distinct slow jobs by one client: exactly 4 accepted."""
    import concurrent.futures

    def post(i: int) -> httpx.Response:
        with httpx.Client(base_url=server.url, timeout=30) as c:
            return c.post(f"{V1}/workspace", json={"settings": {"voxel": 2.2 + 0.01 * i, "eta_step": 0.02, "method": "dense"}})

    with concurrent.futures.ThreadPoolExecutor(10) as ex:
        responses = list(ex.map(post, range(10)))
    codes = sorted(r.status_code for r in responses)
    assert codes == [202] * 4 + [429] * 6, codes
    with httpx.Client(base_url=server.url, timeout=30) as c:
        for r in responses:
            if r.status_code == 202:
                c.delete(f"{V1}/jobs/{r.json()['job_id']}")
        for r in responses:
            if r.status_code == 202:
                assert _poll(c, r.json()["job_id"])["status"] == "cancelled"


def test_serve_busy_api_port_is_a_clear_error():
    import socket

    from paraspace.app.serve import serve
    from paraspace.kinematics.design import ParameterError

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        busy = s.getsockname()[1]
        with pytest.raises(ParameterError) as e:
            serve("127.0.0.1", 0, busy, block=False, explorer=False, quiet=True)
        assert e.value.field == "api-port" and "free TCP port" in str(e.value)


def test_root_serves_landing_page_to_browsers_and_json_to_scripts(http):
    page = http.get("/", headers={"accept": "text/html"})
    assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
    assert "Open the explorer" in page.text and "{{" not in page.text and 'href="/docs"' in page.text
    assert 'href="http://127.0.0.1:9999"' in page.text
    index = http.get("/", headers={"accept": "application/json"}).json()
    assert index["docs"] == "/docs"


def test_joint_options_over_http(http):
    """Joint cones and leg interference reach the engine through the API: the result echoes them, the
    cones shrink the volume, ik reports the joint angles, and a bad value is a 422 with the one range."""
    plain = http.post(f"{V1}/workspace", params={"wait": 60}, json={"settings": {"voxel": 6}})
    joints = {"theta_u": 45, "theta_s": 45, "cone_axis": "home", "leg_diameter": 10, "clearance": 1}
    coned = http.post(f"{V1}/workspace", params={"wait": 60}, json={"settings": {"voxel": 6, "joints": joints}})
    vols = []
    for r in (plain, coned):
        st = _poll(http, r.json()["job_id"])
        assert st["status"] == "done", st
        res = http.get(f"{V1}/jobs/{st['id']}/result").json()["result"]
        vols.append(res["volume"])
        last = res
    assert last["settings"]["joints"] == {**joints, "theta_u": 45.0, "theta_s": 45.0, "leg_diameter": 10.0,
                                          "clearance": 1.0}
    assert 0 < vols[1] < vols[0]
    r = http.post(f"{V1}/ik", json={"joints": {"theta_u": 30, "leg_diameter": 10}})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["joints"]["theta_u"] == 30.0 and body["min_leg_distance"] > 10.0
    assert max(max(a[0] for a in leg) for leg in body["cone_angles"]) <= 30.0
    for bad, field, rng in (({"theta_u": 0}, "joints.theta_u", "(0, 90] degrees"),
                            ({"theta_s": 120}, "joints.theta_s", "(0, 90] degrees"),
                            ({"leg_diameter": -2}, "joints.leg_diameter", "[0, 100]"),
                            ({"cone_axis": "up"}, "joints.cone_axis", "normal")):
        r = http.post(f"{V1}/ik", json={"joints": bad})
        assert r.status_code == 422, r.text
        hit = [d for d in r.json()["detail"] if d["field"] == field]
        assert hit and rng in hit[0]["message"], r.text
    r = http.post(f"{V1}/orientation", params={"wait": 60},
                  json={"settings": {"angle_step": 3, "position_step": 5, "joints": {"theta_s": 30, "theta_u": 30}}})
    st = _poll(http, r.json()["job_id"])
    res = http.get(f"{V1}/jobs/{st['id']}/result").json()["result"]
    assert set(res["saturated"]) == set(res["deltas"]) - {k for k in res["deltas"] if k.startswith("P(")}
    assert res["settings"]["joints"]["theta_s"] == 30.0
