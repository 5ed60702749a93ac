"""Multi-objective optimal design (kinematics.optimize): known answers against dense sweeps,
determinism, the shared result cache, failures, cancellation, hypervolume, validation, CLI."""

from __future__ import annotations

import dataclasses
import json
import os
import sys

import numpy as np
import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.distributed import close_clients, shared_client
from paraspace.kinematics.objectives import MEASURES, Constraint, Measure, parse_constraint, parse_objectives
from paraspace.kinematics.optimize import OptimizeSettings, non_dominated, normalised_hypervolume, optimize
from paraspace.kinematics.progress import Cancelled
from paraspace.kinematics.sweep import ResultCache, evaluate_design, sweep_1d, sweep_2d
from paraspace.kinematics.workspace import WorkspaceSettings, reach_box

COARSE = WorkspaceSettings(voxel=10.0)


def _strip_front(front: list[dict]) -> list[dict]:
    return [{"design": e["design"], "measures": {k: v for k, v in e["measures"].items()}} for e in front]


# ----- known answers ---------------------------------------------------------------------------


def test_volume_over_l_s_alone_is_maximised_at_the_upper_bound():
    """On a fixed grid the workspace with a longer leg stroke contains the one with a shorter
    stroke, so the volume is monotone in l_s and the single-objective optimum is l_s's upper
    bound (or a value with the same voxel count)."""
    lo, hi = reach_box(Design(l_s=100.0))
    ws = WorkspaceSettings(voxel=10.0, bounds=(tuple(lo), tuple(hi)))
    # independent: a plain sweep of the same unit of work
    rows = sweep_1d(Design(), "l_s", [10.0, 50.0, 90.0, 100.0], ws)
    vols = [r["volume"] for r in rows]
    assert vols == sorted(vols) and vols[2] < vols[3]
    s = OptimizeSettings(params=("l_s",), objectives="volume", workspace=ws, population=8, generations=8, seed=5)
    res = optimize(s)
    assert len(res.front) == 1
    best = res.front[0]
    assert best["measures"]["volume"] == vols[3]
    assert 90.0 < best["design"]["l_s"] <= 100.0
    # the other fields are the base design's
    assert {k: v for k, v in best["design"].items() if k != "l_s"} == {
        k: v for k, v in Design().to_dict().items() if k != "l_s"}


def test_two_objective_front_matches_dense_sweep_and_reuses_its_cache():
    """volume vs -footprint over (a, l_s): the optimiser (192 evaluations) against the
    non-dominated set of a dense 19 x 19 sweep (361 designs) of the same grid.

    Tolerance: the additive epsilon indicator in objective space normalised by the sweep front's
    ranges is <= 0.08 (every sweep-front design is within 8 % of the ranges of some optimiser
    design), the largest volume is found exactly, and every optimiser design is on the sweep's
    front or within that epsilon of it. The optimiser's designs lie on the sweep's grid
    (step = 5), so with the sweep's cache it computes nothing."""
    cache = ResultCache(max_entries=1000)
    vals = [float(v) for v in np.arange(10, 101, 5)]
    sw = sweep_2d(Design(), "a", vals, "l_s", vals, COARSE, cache=cache)
    footprint = lambda d: d["r"] + d["l_min"] + d["l_s"]  # noqa: E731 - the documented definition
    F_sweep = np.array([[-p["volume"], footprint(p["design"])] for p in sw["points"]])
    sweep_front = F_sweep[non_dominated(F_sweep)]
    assert len(sweep_front) >= 10

    s = OptimizeSettings(params=("a", "l_s"), objectives="volume,-footprint", workspace=COARSE, population=16,
                         generations=12, step=5.0, seed=1)
    res = optimize(s, cache=cache)
    assert res.computed == 0 and res.evaluations == 16 * 12
    F_opt = np.array([[-e["measures"]["volume"], e["measures"]["footprint"]] for e in res.front])
    span = sweep_front.max(axis=0) - sweep_front.min(axis=0)
    eps = max(min(np.max((fo - fs) / span) for fo in F_opt) for fs in sweep_front)
    assert eps <= 0.08
    assert F_opt[:, 0].min() == sweep_front[:, 0].min()
    for fo in F_opt:
        # never better than the true front (the grid holds every design it tried) ...
        assert any(np.all(fs <= fo) for fs in sweep_front)
        # ... and close to it
        assert min(np.max((fo - fs) / span) for fs in sweep_front) <= 0.08


# ----- determinism, cache, failures, cancellation ------------------------------------------------


def test_same_seed_same_front_and_a_design_is_never_computed_twice():
    s = OptimizeSettings(params=("a", "d_s"), objectives="volume,-hollowness", workspace=COARSE,
                         population=8, generations=3, seed=11)
    cache = ResultCache(max_entries=500)
    r1 = optimize(s, cache=cache)
    r2 = optimize(s)  # fresh cache: computes everything again, same numbers
    assert _strip_front(r1.front) == _strip_front(r2.front)
    assert r1.hypervolume == r2.hypervolume
    r3 = optimize(s, cache=cache)  # same cache: nothing is computed again
    assert r3.computed == 0 and _strip_front(r3.front) == _strip_front(r1.front)
    other = optimize(dataclasses.replace(s, seed=12))
    assert [e["design"] for e in other.front] != [e["design"] for e in r1.front]


def test_front_entries_are_feasible_non_dominated_and_measured_like_evaluate_design():
    s = OptimizeSettings(params=("a", "l_s"), objectives="volume,-footprint", constraints=["boundary_complete"],
                         workspace=COARSE, population=8, generations=3, seed=2)
    res = optimize(s)
    assert res.front
    e = res.front[len(res.front) // 2]
    ref = evaluate_design(Design.from_dict(e["design"]), COARSE)
    for k in ("volume", "hollowness", "genus", "boundary_complete"):
        assert e["measures"][k] == ref[k]
    d = e["design"]
    assert e["measures"]["footprint"] == pytest.approx(d["r"] + d["l_min"] + d["l_s"])
    assert all(x["measures"]["boundary_complete"] is True for x in res.front)
    F = np.array([[-x["measures"]["volume"], x["measures"]["footprint"]] for x in res.front])
    assert len(non_dominated(F)) == len(F)
    # hypervolume of an archive never decreases
    assert all(b >= a - 1e-12 for a, b in zip(res.hypervolume, res.hypervolume[1:]))
    assert len(res.hypervolume) == 3 and [g["generation"] for g in res.generations] == [1, 2, 3]


def test_invalid_designs_are_infeasible_and_reported_not_fatal():
    """d_s and r both free with d_s's range above r's: the model rejects d_s > r; those points
    are reported in ``failed`` (naming d_s) and the front holds only valid designs."""
    s = OptimizeSettings(params=("d_s", "r"), bounds={"d_s": (40.0, 100.0), "r": (50.0, 80.0)},
                         objectives="volume,-footprint", workspace=COARSE, population=8, generations=2, seed=3)
    res = optimize(s)
    assert res.failed and all("d_s" in f["error"] for f in res.failed)
    assert res.front and all(e["design"]["d_s"] <= e["design"]["r"] for e in res.front)


def evaluate_or_raise(design, settings, *, orientation=None):
    """The real unit of work, except that it raises for a > 50."""
    if design.a > 50.0:
        raise ArithmeticError("injected failure")
    return evaluate_design(design, settings, orientation=orientation)


def test_failing_points_cost_their_points_only():
    s = OptimizeSettings(params=("a", "l_s"), objectives="volume,-footprint", workspace=COARSE,
                         population=8, generations=2, seed=4)
    res = optimize(s, evaluate=evaluate_or_raise)
    assert res.failed and all("injected failure" in f["error"] and f["design"]["a"] > 50 for f in res.failed)
    assert res.front and all(e["design"]["a"] <= 50.0 for e in res.front)


def test_progress_reports_generations_and_cancel_stops():
    s = OptimizeSettings(params=("a", "l_s"), objectives="volume,-footprint", workspace=COARSE,
                         population=6, generations=5, seed=1)
    messages: list[tuple[float, str]] = []
    gens: list[dict] = []

    class StopAfterTwo:
        def is_set(self) -> bool:
            return len(gens) >= 2

    with pytest.raises(Cancelled):
        optimize(s, progress=lambda f, m: messages.append((f, m)), on_generation=gens.append,
                 cancel=StopAfterTwo())
    assert [g["generation"] for g in gens] == [1, 2]
    assert gens[1]["evaluations"] == 12 and gens[1]["front"] and "volume" in gens[1]["best"]
    ends = [m for f, m in messages if "evaluations" in m]
    assert ends[0].startswith("generation 1/5, 6 evaluations, best: volume")
    fr = [f for f, _ in messages]
    assert fr == sorted(fr) and 0.0 <= fr[0] and fr[-1] <= 0.4 + 1e-9


def test_three_objectives_use_nsga3():
    s = OptimizeSettings(params=("a", "l_s"), objectives="volume,-footprint,-hollowness", workspace=COARSE,
                         population=6, generations=2, seed=1)
    assert s.algorithm_used == "nsga3"
    res = optimize(s)
    assert res.front and res.settings.to_dict()["algorithm"] == "nsga3"


# ----- pieces checked against independent computations ---------------------------------------------


def test_non_dominated_matches_pymoo_sorting():
    from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

    rng = np.random.default_rng(0)
    for m in (1, 2, 3):
        F = rng.integers(0, 6, size=(40, m)).astype(float)
        ours = set(non_dominated(F).tolist())
        theirs = NonDominatedSorting().do(F, only_non_dominated_front=True)
        # ours keeps one of equal rows; theirs keeps all
        assert {tuple(F[i]) for i in ours} == {tuple(F[i]) for i in theirs}
        assert len(ours) == len({tuple(F[i]) for i in ours})


def test_hypervolume_of_a_staircase_by_hand():
    """Fronts {(0,1),(1,0)} and {(0,1),(0.5,0.5),(1,0)} with reference 1.1 after normalisation
    (ideal (0,0), nadir (1,1)): rectangles summed by hand."""
    a = np.array([[0.0, 1.0], [1.0, 0.0]])
    b = np.array([[0.0, 1.0], [0.5, 0.5], [1.0, 0.0]])
    hv, norm = normalised_hypervolume([a, b])
    assert norm["ideal"] == [0.0, 0.0] and norm["nadir"] == [1.0, 1.0]
    hv_a = 1.1 * 0.1 + 0.1 * 1.0  # x in [0,1): height 0.1; x in [1, 1.1): height 1.1
    hv_b = 0.5 * 0.1 + 0.5 * 0.6 + 0.1 * 1.1
    assert hv[0] == pytest.approx(hv_a) and hv[1] == pytest.approx(hv_b)


# ----- validation --------------------------------------------------------------------------------


@pytest.mark.parametrize("kwargs, field", [
    ({"params": ("a", "zz")}, "params"),
    ({"params": ("a", "a")}, "params"),
    ({"bounds": {"l_s": (50.0, 20.0)}}, "l_s"),
    ({"bounds": {"b": (1.0, 2.0)}}, "bounds"),
    ({"bounds": {"eta_s": (10.0, 400.0)}}, "eta_s"),
    ({"objectives": "volume,-nope"}, "objectives"),
    ({"objectives": "boundary_complete"}, "objectives"),
    ({"objectives": "volume,-volume"}, "objectives"),
    ({"objectives": ""}, "objectives"),
    ({"constraints": ["volume"]}, "constraint"),
    ({"constraints": ["boundary_complete>=1"]}, "constraint"),
    ({"population": 2}, "population"),
    ({"generations": 0}, "generations"),
    ({"seed": -1}, "seed"),
    ({"step": 0.0}, "step"),
    ({"algorithm": "pso"}, "algorithm"),
])
def test_bad_settings_name_the_field(kwargs, field):
    with pytest.raises(ParameterError) as ei:
        OptimizeSettings(**kwargs)
    assert ei.value.field == field


def test_parsers_and_registry():
    objs = parse_objectives("volume, TI_1,-footprint")
    assert [(o.measure, o.minimize) for o in objs] == [("volume", False), ("TI_1", False), ("footprint", True)]
    assert OptimizeSettings(objectives="volume,TI_1").needs_orientation
    assert not OptimizeSettings(objectives="volume,-hollowness").needs_orientation
    c = parse_constraint("volume>=2e6")
    assert (c.measure, c.op, c.bound) == ("volume", ">=", 2e6)
    assert c.violation(3e6) < 0 < c.violation(1e6)
    assert parse_constraint("hollowness<=0.3").violation(0.5) > 0
    assert Constraint("boundary_complete").violation(1.0) == 0.0
    assert Constraint("boundary_complete").violation(0.0) == 1.0
    # a new measure is one entry
    from paraspace.kinematics.objectives import register_measure

    register_measure(Measure("test_volume_per_voxel", "test only", derive=lambda row: row["volume"] / row["voxels"]))
    try:
        assert parse_objectives("-test_volume_per_voxel")[0].minimize
    finally:
        MEASURES.pop("test_volume_per_voxel")


def test_workers_and_scheduler_together_rejected():
    with pytest.raises(ParameterError) as ei:
        optimize(OptimizeSettings(workspace=COARSE, population=4, generations=1), scheduler="tcp://x:1", workers=2)
    assert ei.value.field == "workers"


# ----- Dask ------------------------------------------------------------------------------------


def evaluate_or_die(design, settings, *, orientation=None):
    """Kills its worker process for a > 80, else the real unit of work."""
    if design.a > 80.0:
        os._exit(13)
    return evaluate_design(design, settings, orientation=orientation)


@pytest.fixture(scope="module")
def cluster():
    import cloudpickle
    import dask
    from distributed import LocalCluster

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        c = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                         dashboard_address=None, silence_logs=50)
        yield c
        close_clients()  # the warm clients kept by the runs, before their scheduler goes
        c.close()


@pytest.mark.slow
def test_dask_same_front_as_serial(cluster):
    s = OptimizeSettings(params=("a", "l_s"), objectives="volume,-footprint", workspace=COARSE,
                         population=8, generations=3, seed=21)
    serial = optimize(s)
    dask_run = optimize(s, scheduler=cluster.scheduler_address)
    assert dask_run.backend.startswith("dask")
    assert _strip_front(dask_run.front) == _strip_front(serial.front)
    assert dask_run.hypervolume == serial.hypervolume


@pytest.mark.slow
def test_two_runs_reuse_one_warm_local_cluster_and_match_serial():
    """optimize(workers=2) twice in one process: one client, the same two worker processes, the
    fronts identical to the serial run's."""
    s = OptimizeSettings(params=("a", "l_s"), objectives="volume,-footprint", workspace=COARSE,
                         population=6, generations=2, seed=23)
    close_clients()
    serial = optimize(s)
    try:
        first = optimize(s, workers=2)
        client = shared_client(None, 2)
        pids = sorted(client.run(os.getpid).values())
        second = optimize(dataclasses.replace(s, seed=24), workers=2)
        assert shared_client(None, 2) is client and sorted(client.run(os.getpid).values()) == pids
        assert first.backend.startswith("dask") and second.backend == first.backend
        assert _strip_front(first.front) == _strip_front(serial.front)
        assert first.hypervolume == serial.hypervolume
        assert _strip_front(second.front) == _strip_front(optimize(dataclasses.replace(s, seed=24)).front)
    finally:
        close_clients()


@pytest.mark.slow
def test_dead_worker_costs_its_points_not_the_run(cluster):
    s = OptimizeSettings(params=("a", "l_s"), objectives="volume,-footprint", workspace=COARSE,
                         population=8, generations=2, seed=22)
    res = optimize(s, scheduler=cluster.scheduler_address, evaluate=evaluate_or_die, retries=0)
    # the killer points fail; so may a point that was queued on the dying worker (Dask marks
    # every task held by a worker that dies as suspicious)
    assert any(f["design"]["a"] > 80.0 for f in res.failed)
    assert all("KilledWorker" in f["error"] for f in res.failed), [f["error"] for f in res.failed]
    assert res.front and all(e["design"]["a"] <= 80.0 for e in res.front)


# ----- command line ------------------------------------------------------------------------------


def test_cli_json_csv_plot(tmp_path, capsys):
    from paraspace.app.cli import main

    csv_path, png = tmp_path / "front.csv", tmp_path / "front.png"
    rc = main(["optimize", "--params", "a,l_s", "--objectives", "volume,-footprint", "--constraint",
               "boundary_complete", "--bounds", "l_s=20:100", "--population", "6", "--generations", "2",
               "--seed", "3", "--voxel", "10", "--json", "--csv", str(csv_path), "--plot", str(png)])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["settings"]["params"] == ["a", "l_s"] and out["settings"]["bounds"]["l_s"] == [20.0, 100.0]
    assert out["settings"]["objectives"] == ["volume", "-footprint"]
    assert out["settings"]["constraints"] == ["boundary_complete"]
    assert len(out["hypervolume"]) == 2 and out["front"]
    assert set(out["front"][0]) == {"design", "measures"}
    assert all(20.0 <= e["design"]["l_s"] <= 100.0 for e in out["front"])
    lines = csv_path.read_text().splitlines()
    assert len(lines) == 1 + len(out["front"]) and lines[0].startswith("index,a,l_s,")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # same command, same front
    main(["optimize", "--params", "a,l_s", "--objectives", "volume,-footprint", "--constraint",
          "boundary_complete", "--bounds", "l_s=20:100", "--population", "6", "--generations", "2",
          "--seed", "3", "--voxel", "10", "--json"])
    assert json.loads(capsys.readouterr().out)["front"] == out["front"]


def test_cli_progress_is_the_same_bar_as_every_command(capsys):
    """--progress draws the progress bar of the other commands (app/progressline.py) even on a
    pipe; stdout keeps only the JSON."""
    from paraspace.app.cli import main

    rc = main(["optimize", "--params", "a", "--population", "4", "--generations", "2", "--voxel", "10",
               "--json", "--progress"])
    out = capsys.readouterr()
    assert rc == 0 and json.loads(out.out)["front"]
    # tqdm redraws at most every 0.1 s, so a fast second generation may not get its own frame
    assert "optimize [" in out.err and " %, generation 1/2" in out.err
    rc = main(["optimize", "--params", "a", "--population", "4", "--generations", "2", "--voxel", "10", "--json"])
    assert rc == 0 and capsys.readouterr().err == ""  # not a terminal, not asked: nothing drawn


@pytest.mark.parametrize("args, field", [
    (["--bounds", "l_s=20"], "bounds"),
    (["--bounds", "zz=1:2"], "bounds"),
    (["--bounds", "l_s=90:20"], "l_s"),
    (["--objectives", "volume,-nope"], "objectives"),
    (["--constraint", "volume>>3"], "constraint"),
    (["--population", "x"], "population"),
    (["--plot", "front.jpg"], "plot"),
    (["--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "workers"),
])
def test_cli_bad_input_is_one_line_exit_2(args, field, capsys):
    from paraspace.app.cli import main

    rc = main(["optimize", "--population", "4", "--generations", "1", "--voxel", "10", *args])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and f"error: {field} = " in err


def test_orientation_objective_uses_the_tilt_indices():
    """TI_1 as an objective: the front's TI_1 is orientation_workspace's for that design and the
    run's orientation settings."""
    from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace

    ori = OrientationSettings(angle_step=6.0, position_step=10.0)
    s = OptimizeSettings(params=("a", "eta_s"), objectives="volume,TI_1", workspace=COARSE, orientation=ori,
                         population=4, generations=2, seed=6)
    assert s.orientation_used == ori
    res = optimize(s)
    e = res.front[0]
    ref = orientation_workspace(Design.from_dict(e["design"]), ori)
    assert e["measures"]["TI_1"] == ref.ti1 and e["measures"]["TI_2"] == ref.ti2
    assert res.settings.to_dict()["orientation"]["angle_step"] == 6.0


@pytest.mark.parametrize("objectives, trace", [("volume", "scatter"), ("volume,-footprint", "scatter"),
                                               ("volume,-footprint,-hollowness", "parcoords")])
def test_front_pictures(tmp_path, objectives, trace):
    from paraspace.app.optimize_plots import front_csv, front_figure, front_png

    res = optimize(OptimizeSettings(params=("a", "l_s"), objectives=objectives, workspace=COARSE,
                                    population=4, generations=2, seed=1)).to_dict()
    png = tmp_path / "f.png"
    front_png(res, str(png))
    assert png.read_bytes()[:4] == b"\x89PNG"
    fig = front_figure(res)
    assert fig.data[0].type == trace
    if trace == "parcoords":  # one axis per objective plus the design index
        assert len(fig.data[0].dimensions) == 4
        assert list(fig.data[0].dimensions[1].values) == [e["measures"]["volume"] for e in res["front"]]
    assert front_csv(res).count("\n") == 1 + len(res["front"])


def test_evaluations_compute_only_the_named_measures_and_the_front_is_the_full_one():
    """Issue 24 target 2: an optimiser evaluation computes the measures its objectives and
    constraints name (a generation's front rows hold nothing else), and the final front is the one
    a run evaluating every measure gives (its entries completed with every measure)."""
    s = OptimizeSettings(params=("a", "l_s"), objectives="volume,-footprint", constraints=["hollowness<=0.9"],
                         workspace=COARSE, population=6, generations=2, seed=3)
    assert s.measure_fields == ("hollowness", "volume")
    seen: list[dict] = []
    fast = optimize(s, on_generation=lambda info: seen.extend(info["front"]))
    slow = optimize(s, evaluate=evaluate_design)  # a custom unit of work: every measure
    assert seen and all("genus" not in e["measures"] and "hollowness" in e["measures"] for e in seen)
    assert _strip_front(fast.front) == _strip_front(slow.front) and fast.hypervolume == slow.hypervolume
    assert all("genus" in e["measures"] for e in fast.front)
    assert OptimizeSettings(objectives="volume,-footprint", workspace=COARSE).measure_fields == ("volume",)
    assert OptimizeSettings(objectives="volume", constraints=["boundary_complete"]).measure_fields == (
        "boundary_complete", "volume")
    row = evaluate_design(Design(), COARSE, measures=["genus"])
    full = evaluate_design(Design(), COARSE)
    assert row["genus"] == full["genus"] and "hollowness" not in row
    with pytest.raises(ParameterError, match="measures"):
        evaluate_design(Design(), COARSE, measures=["nope"])
