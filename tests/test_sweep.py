"""Tests of kinematics.sweep: parameter studies (paper Figs. 4 and 5), cache, cancellation."""

from __future__ import annotations

import json
import pickle
import threading

import pytest

from paraspace.kinematics import Cancelled, Design, ParameterError, WorkspaceSettings, compute_workspace, sweep
from paraspace.kinematics.orientation import OrientationSettings
from paraspace.kinematics.sweep import (
    ResultCache,
    cache_key,
    evaluate_design,
    study_values,
    sweep_1d,
    sweep_2d,
)

COARSE = WorkspaceSettings(voxel=8.0)
ORI = OrientationSettings(angle_range=60.0, angle_step=5.0, position_step=8.0)


@pytest.fixture
def counted(monkeypatch):
    """Count the calls of the unit of work made by the sweeps."""
    calls: list[Design] = []
    real = sweep.evaluate_design

    def wrapper(design, settings, **kw):
        calls.append(design)
        return real(design, settings, **kw)

    monkeypatch.setattr(sweep, "evaluate_design", wrapper)
    return calls


def test_sweep_volume_equals_compute_workspace() -> None:
    values = [30.0, 60.0]
    rows = sweep_1d(Design(), "a", values, COARSE)
    assert [r["param"] for r in rows] == ["a", "a"] and [r["value"] for r in rows] == values
    for row, a in zip(rows, values):
        direct = compute_workspace(Design(a=a), COARSE)
        assert row["volume"] == pytest.approx(direct.volume)
        assert row["voxels"] == direct.voxels and row["design"]["a"] == a
        assert row["compute_seconds"] >= 0.0
    json.dumps(rows)


@pytest.mark.parametrize("param,values", [("l_s", [20.0, 50.0, 80.0]), ("eta_s", [10.0, 30.0, 60.0])])
def test_volume_grows_with_strokes(param: str, values: list[float]) -> None:
    vols = [r["volume"] for r in sweep_1d(Design(), param, values, COARSE)]
    assert all(b >= a for a, b in zip(vols, vols[1:])), vols
    assert vols[-1] > vols[0]


def test_result_cache_memory_is_bounded_by_bytes() -> None:
    row = {"ok": True, "volume": 1.0, "note": "x" * 1000}  # about 1.2 kB each
    cache = ResultCache(max_entries=100, max_bytes=5_000)
    for i in range(20):
        cache.put(f"k{i}", row)
    assert 1 <= len(cache) < 5  # 20 rows are about 24 kB: the byte budget, not the count, binds
    assert cache.get("k19") == row and cache.get("k0") is None
    with pytest.raises(ParameterError, match="max_bytes"):
        ResultCache(max_bytes=-1)


def test_cache_hit_returns_equal_results_without_recomputation(counted, tmp_path) -> None:
    cache = ResultCache(max_entries=8, directory=tmp_path)
    first = sweep_1d(Design(), "d_s", [20.0, 40.0], COARSE, cache=cache)
    assert len(counted) == 2
    again = sweep_1d(Design(), "d_s", [40.0, 20.0, 40.0], COARSE, cache=cache)
    assert len(counted) == 2  # all three from the cache
    assert again[0] == first[1] and again[1] == first[0] and again[2] == first[1]
    assert cache.hits == 3 and cache.misses == 2
    # a fresh cache on the same directory serves from disk
    disk = ResultCache(max_entries=8, directory=tmp_path)
    assert sweep_1d(Design(), "d_s", [20.0], COARSE, cache=disk) == first[:1]
    assert len(counted) == 2
    # other settings, other orientation settings or another code version are other keys
    k = cache_key(Design(d_s=20.0), COARSE)
    assert k == cache_key(Design(d_s=20), WorkspaceSettings(voxel=8))  # ints and floats alike
    assert k != cache_key(Design(d_s=20.0), WorkspaceSettings(voxel=10.0))
    assert k != cache_key(Design(d_s=20.0), COARSE, ORI)
    assert k != cache_key(Design(d_s=20.0, eta_range="from-zero"), COARSE)
    assert k != cache_key(Design(d_s=20.0), COARSE, version="other")
    # the values handed out are copies
    got = cache.get(k)
    got["volume"] = -1.0
    assert cache.get(k)["volume"] == first[0]["volume"]


def test_cache_lru_and_threads() -> None:
    cache = ResultCache(max_entries=3)
    for i in range(5):
        cache.put(f"k{i}", {"i": i})
    assert len(cache) == 3 and cache.get("k0") is None and cache.get("k4") == {"i": 4}

    def worker(j: int) -> None:
        for i in range(200):
            cache.put(f"t{j}-{i % 7}", {"v": i})
            cache.get(f"t{(j + 1) % 4}-{i % 7}")

    threads = [threading.Thread(target=worker, args=(j,)) for j in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(cache) == 3


def test_bad_parameter_names_it() -> None:
    with pytest.raises(ParameterError, match="bogus"):
        sweep_1d(Design(), "bogus", [1.0], COARSE)
    with pytest.raises(ParameterError, match="l_s"):
        sweep_1d(Design(), "l_s", [20.0, -5.0], COARSE)  # checked before any computation
    with pytest.raises(ParameterError) as err:
        sweep_1d(Design(), "d_s", [150.0], COARSE)
    assert err.value.field == "d_s"
    with pytest.raises(ParameterError, match="param_y"):
        sweep_2d(Design(), "a", [10.0], "a", [20.0], COARSE)
    with pytest.raises(ParameterError, match="nope"):
        study_values("nope")


def test_cancel_raises() -> None:
    ev = threading.Event()
    ev.set()
    with pytest.raises(Cancelled):
        sweep_1d(Design(), "a", [30.0, 40.0], COARSE, cancel=ev)
    with pytest.raises(Cancelled):
        sweep_2d(Design(), "a", [30.0], "d_s", [20.0], COARSE, cancel=ev)
    with pytest.raises(Cancelled):
        evaluate_design(Design(), COARSE, cancel=ev)
    # cancelled after the first point: progress stops, no result
    seen: list[float] = []
    later = threading.Event()

    def progress(f: float, msg: str) -> None:
        seen.append(f)
        if f > 0:
            later.set()

    with pytest.raises(Cancelled):
        sweep_1d(Design(), "a", [30.0, 40.0, 50.0], COARSE, progress=progress, cancel=later)
    assert seen and max(seen) < 1.0


def test_sweep_2d_layout_progress_and_orientation(counted) -> None:
    seen: list[float] = []
    out = sweep_2d(Design(), "a", [30.0, 60.0], "d_s", [20.0, 40.0, 60.0], COARSE,
                   orientation=ORI, progress=lambda f, m: seen.append(f))
    assert out["values_x"] == [30.0, 60.0] and out["values_y"] == [20.0, 40.0, 60.0]
    assert len(out["volume"]) == 3 and all(len(row) == 2 for row in out["volume"])
    assert len(out["points"]) == 6 and len(counted) == 6
    for p in out["points"]:
        assert out["volume"][p["iy"]][p["ix"]] == p["volume"]
        assert (p["x"], p["y"]) == (out["values_x"][p["ix"]], out["values_y"][p["iy"]])
        assert p["design"]["a"] == p["x"] and p["design"]["d_s"] == p["y"]
        assert p["TI_1"] > 0 and p["TI_2"] > 0 and "Δφ_z" in p["orientation_deltas"]
    assert out["grids"]["TI_1"][1][0] == out["points"][2]["TI_1"]
    assert seen[-1] == pytest.approx(1.0) and all(b >= a for a, b in zip(seen, seen[1:]))
    json.dumps(out)


def test_evaluate_design_is_deterministic_and_picklable() -> None:
    args = (Design(a=40.0), COARSE)
    pickle.loads(pickle.dumps((evaluate_design, args, ORI)))  # Dask/process workers can ship it
    r1 = evaluate_design(*args, orientation=ORI)
    r2 = evaluate_design(*args, orientation=ORI)
    r1.pop("compute_seconds"), r2.pop("compute_seconds")
    assert r1 == r2
    assert json.loads(json.dumps(r1)) == r1


def test_study_values_follow_table_one() -> None:
    assert study_values("a") == [10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0]
    assert study_values("eta_s", 4) == [10.0, 40.0, 70.0, 100.0]
    with pytest.raises(ParameterError, match="n"):
        study_values("a", 0)
