"""Studies over a preset's parameters (kinematics/sweep.py on a PresetDesign): 1-D and 2-D sweeps,
the Dask grid and REST sweeps give, at every point, the measures of a direct
compute_mechanism_workspace of that preset; bad names are refused naming the field."""

from __future__ import annotations

import functools
import json

import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.measures import measure_workspace
from paraspace.kinematics.mechanism_workspace import compute_mechanism_workspace
from paraspace.kinematics.presets import PresetDesign, preset
from paraspace.kinematics.sweep import ResultCache, evaluate_design, study_values, sweep_1d, sweep_2d, sweep_preset
from paraspace.kinematics.workspace import WorkspaceSettings

WS = WorkspaceSettings(voxel=16.0)
KEYS = ("volume", "voxels", "components", "hollowness", "genus", "boundary_closed_stable")


def _direct(name: str, values: dict) -> dict:
    """Independent: the preset built by hand, its workspace and measures computed directly."""
    return measure_workspace(compute_mechanism_workspace(preset(name, values), WS)).to_dict()


def test_2d_sweep_of_a_preset_equals_direct_computations_and_is_cached():
    base = PresetDesign.of("6-pups", {"platform_half_angle": 20.0})
    cache = ResultCache()
    out = sweep_2d(base, "lift", [0.0, 40.0], "platform_radius", [40.0, 60.0], WS, cache=cache)
    assert out["values_x"] == [0.0, 40.0] and out["values_y"] == [40.0, 60.0] and len(out["points"]) == 4
    for p in out["points"]:
        ref = _direct("6-pups", {"platform_half_angle": 20.0, "lift": p["x"], "platform_radius": p["y"]})
        assert p["engine"] == "general" and p["design"]["lift"] == p["x"] and p["design"]["platform_radius"] == p["y"]
        assert {k: p[k] for k in KEYS} == {k: ref[k] for k in KEYS}
    assert out["volume"][1][0] == out["points"][2]["volume"]  # rows: platform_radius, columns: lift
    misses = cache.misses
    again = sweep_1d(base.replace(platform_radius=60.0), "lift", [0.0, 40.0], WS, cache=cache)
    assert cache.misses == misses and [r["volume"] for r in again] == [p["volume"] for p in out["points"][2:]]
    # another length_step is another key (it may change a sampled prismatic joint's answer)
    assert cache.key(base, WS, length_step=1.0) != cache.key(base, WS, length_step=2.0)


def test_sweep_preset_is_a_thin_layer_and_study_values_span_the_study_range():
    rows = sweep_preset("6-pss", "rail_stroke", [100.0, 150.0], {"leg_length": 140.0}, WS)
    for row, stroke in zip(rows, (100.0, 150.0)):
        assert row["rail_stroke"] == stroke and row["engine"] == "general" and "design" not in row
        assert row["voxels"] == _direct("6-pss", {"leg_length": 140.0, "rail_stroke": stroke})["voxels"]
    assert study_values("lift", 3, PresetDesign.of("6-pups")) == [0.0, 50.0, 100.0]


@pytest.mark.parametrize("call, field", [
    (lambda: sweep_1d(PresetDesign.of("6-pups"), "a", [1.0], WS), "param"),
    (lambda: sweep_2d(PresetDesign.of("6-pups"), "lift", [1.0], "lift", [2.0], WS), "param_y"),
    (lambda: sweep_1d(PresetDesign.of("6-pups"), "lift", [-1.0], WS), "lift"),
    (lambda: sweep_1d(PresetDesign.of("6-pups"), "lift", [1.0], WS, length_step=0.0), "length_step"),
    (lambda: sweep_1d(Design(), "a", [50.0], WS, length_step=2.0), "length_step"),
    (lambda: evaluate_design(PresetDesign.of("6-pups"), WS, dexterity=True), "dexterity"),
])
def test_bad_input_names_the_field(call, field):
    with pytest.raises(ParameterError) as ei:
        call()
    assert ei.value.field == field


def test_dask_grid_of_a_preset_equals_the_serial_sweep():
    from paraspace.kinematics.distributed import grid_designs, sweep_grid

    base = PresetDesign.of("6-pups")
    with pytest.raises(ParameterError) as ei:
        grid_designs(base, {"a": [1.0]})
    assert ei.value.field == "params" and "lift" in str(ei.value)
    rows = sweep_grid(base, {"lift": [0.0, 40.0]}, WS, n_workers=1,
                      evaluate=functools.partial(evaluate_design, length_step=1.0))
    serial = sweep_1d(base, "lift", [0.0, 40.0], WS)
    assert [r["ok"] for r in rows] == [True, True]
    for r, s in zip(rows, serial):
        assert r["params"] == {"lift": s["value"]} and r["design"] == s["design"]
        assert {k: r[k] for k in KEYS} == {k: s[k] for k in KEYS}


def test_cli_2d_sweep_of_a_preset(capsys):
    from paraspace.app.cli import main

    assert main(["sweep", "--mechanism", "6-pups", "--param", "lift", "--values", "0,40", "--param2",
                 "platform_radius", "--values2", "40", "--set", "platform_half_angle=20", "--voxel", "16",
                 "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [(r["lift"], r["platform_radius"]) for r in rows] == [(0.0, 40.0), (40.0, 40.0)]
    for r in rows:
        ref = _direct("6-pups", {"platform_half_angle": 20.0, "lift": r["lift"], "platform_radius": 40.0})
        assert r["voxels"] == ref["voxels"] and r["volume"] == ref["volume"]
    assert main(["sweep", "--mechanism", "6-pups", "--param", "lift", "--values", "0", "--param2", "a",
                 "--values2", "3"]) == 2
    assert "param_y = 'a'" in capsys.readouterr().err
    assert main(["sweep", "--mechanism", "6-pups", "--param", "lift", "--values", "0", "--z0", "130"]) == 2
    assert "--z0" in capsys.readouterr().err


@pytest.fixture(scope="module")
def http():
    import httpx

    from paraspace.app.api import ApiLimits, create_api
    from paraspace.app.jobs import JobManager
    from paraspace.app.serve import start_api

    jobs = JobManager(max_workers=1, max_jobs_total=8, max_jobs_per_client=8, max_seconds=120)
    srv = start_api(create_api(jobs, limits=ApiLimits(max_voxels=200_000)), "127.0.0.1", 0)
    with httpx.Client(base_url=srv.url, timeout=60.0) as c:
        yield c
    jobs.shutdown(wait=False)
    srv.stop()


def test_rest_sweep_of_a_preset(http):
    from paraspace.app.api import API_PREFIX

    body = {"mechanism": {"preset": "6-pups", "params": {"platform_half_angle": 20}}, "settings": {"voxel": 16},
            "x": {"param": "lift", "values": [0, 40]}, "y": {"param": "platform_radius", "n": 2}}
    r = http.post(f"{API_PREFIX}/sweep", params={"wait": 60}, json=body)
    assert r.status_code == 200, r.text
    res = r.json()["result"]
    assert res["mode"] == "2d" and res["values_y"] == [25.0, 100.0]  # n values over the study range
    for p in res["points"]:
        ref = _direct("6-pups", {"platform_half_angle": 20.0, "lift": p["x"], "platform_radius": p["y"]})
        assert p["voxels"] == ref["voxels"]
    for patch, field in (({"x": {"param": "a", "n": 2}}, "x.param"),
                         ({"x": {"param": "lift", "values": [2000]}}, "x.values[0]"),
                         ({"mechanism": {"preset": "6-pups", "params": {"lifts": 1}}}, "mechanism.lifts"),
                         ({"mechanism": {"description": {"chains": []}}}, "mechanism.preset"),
                         ({"orientation": {}}, "orientation")):
        r = http.post(f"{API_PREFIX}/sweep", json={**body, **patch})
        assert r.status_code == 422 and any(d["field"] == field for d in r.json()["detail"]), (patch, r.text)
    r = http.post(f"{API_PREFIX}/sweep", json={**body, "settings": {"voxel": 0.5}})
    assert r.status_code == 413 and "max_voxels" in r.json()["detail"], r.text
