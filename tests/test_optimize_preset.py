"""The optimiser over a preset's parameters (kinematics.optimize with ``preset``): the front's designs
are feasible and non-dominated, their measures are those of a direct compute_mechanism_workspace of
each design, and what does not exist for a general mechanism is refused by name."""

from __future__ import annotations

import numpy as np
import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.measures import measure_workspace
from paraspace.kinematics.mechanism_workspace import compute_mechanism_workspace
from paraspace.kinematics.objectives import MEASURES
from paraspace.kinematics.optimize import OptimizeSettings, optimize
from paraspace.kinematics.presets import PRESETS, PresetDesign, preset
from paraspace.kinematics.workspace import WorkspaceSettings

#: coarse voxels: each 6-PUPS evaluation costs a few tens of milliseconds
WS = WorkspaceSettings(voxel=16.0)


def test_front_of_a_preset_is_feasible_non_dominated_and_measured_like_a_direct_computation():
    s = OptimizeSettings(preset="6-pups", preset_values={"platform_half_angle": 20.0},
                         params=("lift", "platform_radius"), bounds={"platform_radius": (30.0, 70.0)},
                         objectives="volume,-lift", constraints=["volume>=1e5", "boundary_closed_stable"],
                         workspace=WS, population=6, generations=2, seed=3)
    res = optimize(s)
    assert res.front and res.evaluations == 12
    points = []
    for entry in res.front:
        d = entry["design"]
        assert d["preset"] == "6-pups" and d["platform_half_angle"] == 20.0 and d["l_max"] == 164.5
        assert 0.0 <= d["lift"] <= 100.0 and 30.0 <= d["platform_radius"] <= 70.0
        assert round(d["lift"] / 0.01) * 0.01 == pytest.approx(d["lift"], abs=1e-9)
        values = {k: v for k, v in d.items() if k != "preset"}
        # independent: the preset built by hand and its workspace computed directly
        direct = compute_mechanism_workspace(preset("6-pups", values), WS)
        m = measure_workspace(direct).to_dict()
        got = entry["measures"]
        assert got["engine"] == direct.engine == "general"
        for key in ("volume", "voxels", "components", "hollowness", "genus", "boundary_closed_stable"):
            assert got[key] == m[key], key
        assert got["volume"] >= 1e5 and m["boundary_closed_stable"]  # the constraints hold
        assert got["lift"] == d["lift"] and got["l_max"] == 164.5
        points.append((-got["volume"], got["lift"]))
    F = np.array(points)
    for i in range(len(F)):  # brute-force non-domination among the front
        dominated = np.all(F <= F[i], axis=1) & np.any(F < F[i], axis=1)
        assert not dominated.any()


def test_paper_preset_is_the_paper_design_with_every_measure():
    s = OptimizeSettings(preset="paper", preset_values={"r": 90.0}, params=("l_s",), objectives="volume,-footprint")
    assert s.design == Design(r=90.0) and not s.general
    assert s.bounds_of("l_s") == (PRESETS["paper"].params[5].study_range)
    assert s.to_dict()["mechanism"] == "paper"


def test_preset_design_round_trip_and_l_max_measure():
    d = PresetDesign.of("6-pss", {"leg_length": 130})
    assert PresetDesign.from_dict(d.to_dict()) == d and d.mechanism() == preset("6-pss", {"leg_length": 130.0})
    assert MEASURES["l_max"].value({"design": d.to_dict()}) == 130.0
    assert MEASURES["l_max"].value({"design": Design().to_dict()}) == Design().l_min + Design().l_s
    with pytest.raises(ParameterError) as ei:
        d.replace(leg_length=-1.0)
    assert ei.value.field == "leg_length"


@pytest.mark.parametrize("kwargs, field, words", [
    ({"preset": "hexapod"}, "mechanism", "gough-stewart"),
    ({"preset": "6-pups", "params": ("a", "lift")}, "params", "lift"),
    ({"preset": "6-pups", "params": ("lift",), "preset_values": {"lifts": 3.0}}, "lifts", "lift"),
    ({"preset": "6-pups", "params": ("lift",), "bounds": {"lift": (0.0, 2000.0)}}, "lift", "[0, 1000]"),
    ({"preset": "6-pups", "params": ("lift",), "objectives": "volume,TI_1"}, "objectives", "TI_1"),
    ({"preset": "6-pups", "params": ("lift",), "objectives": "volume,-footprint"}, "objectives", "footprint"),
    ({"preset": "6-pups", "params": ("lift",), "objectives": "volume,-leg_length"}, "objectives", "lift"),
    ({"preset": "6-pups", "params": ("lift",), "objectives": "volume", "constraints": ["gci>=0.1"]},
     "constraints", "gci"),
    ({"preset": "6-pups", "params": ("lift",), "length_step": 0.0}, "length_step", "[0.01, 100]"),
    ({"preset": "6-pups", "params": ("lift",), "design": Design(a=40.0)}, "design", "preset_values"),
    ({"preset": "6-pss", "params": ("leg_length",),
      "workspace": WorkspaceSettings(voxel=16.0, joints=Joints(theta_u=40.0))}, "workspace.joints", "u_cone"),
    ({"preset_values": {"lift": 3.0}}, "preset_values", "preset"),
    ({"params": ("a",), "objectives": "volume,-lift"}, "objectives", "a parameter of the paper's design"),
])
def test_what_a_preset_does_not_have_is_refused_by_name(kwargs, field, words):
    with pytest.raises(ParameterError) as ei:
        OptimizeSettings(**kwargs)
    assert ei.value.field == field
    assert words in str(ei.value)


def test_cli_optimize_a_preset_json_equals_the_core(capsys):
    import json

    from paraspace.app.cli import main

    rc = main(["optimize", "--mechanism", "6-pups", "--param", "platform_half_angle=20", "--params",
               "lift,platform_radius", "--objectives", "volume,-lift", "--population", "4", "--generations", "2",
               "--seed", "3", "--voxel", "16", "--json"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    core = optimize(OptimizeSettings(preset="6-pups", preset_values={"platform_half_angle": 20.0},
                                     params=("lift", "platform_radius"), objectives="volume,-lift",
                                     population=4, generations=2, seed=3, workspace=WS))
    assert [e["design"] for e in out["front"]] == [e["design"] for e in core.front]
    assert out["settings"]["mechanism"] == "6-pups" and out["settings"]["preset_values"]["platform_half_angle"] == 20


@pytest.mark.parametrize("args, field", [
    (["--mechanism", "6-pups", "--params", "a"], "params"),
    (["--mechanism", "6-pups", "--params", "lift", "--objectives", "volume,TI_2"], "objectives"),
    (["--mechanism", "6-pups", "--params", "lift", "--bounds", "a=1:2"], "bounds"),
    (["--mechanism", "6-pups", "--param", "lifts=3"], "lifts"),
    (["--mechanism", "6-pups", "--a", "40"], "--a"),
    (["--mechanism", "6-pss", "--u-cone", "30"], "--u-cone"),
    (["--mechanism", "hexapod.toml"], "--mechanism"),
    (["--param", "lift=3"], "--param"),
])
def test_cli_optimize_a_preset_bad_input_is_one_line_exit_2(args, field, capsys):
    from paraspace.app.cli import main

    rc = main(["optimize", "--population", "4", "--generations", "1", "--voxel", "16", *args])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and f"error: {field} = " in err, err
