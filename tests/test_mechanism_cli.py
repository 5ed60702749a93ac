"""``--mechanism FILE|PRESET`` and ``--param NAME=VALUE`` on ``paraspace workspace`` and ``ik``.

The numbers are checked against independent computations: the paper's engine for the paper preset,
the description's brute force (kinematics/mechanism.reachable_brute_force) for a general mechanism's
voxels and its forward model for the IK's carriage values. Refusals name the flag.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from paraspace.app.cli import main
from paraspace.kinematics.design import Design
from paraspace.kinematics.mechanism import dumps_mechanism
from paraspace.kinematics.mechanism_workspace import compute_mechanism_workspace
from paraspace.kinematics.presets import six_pups
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "paraspace.app.cli", *args], capture_output=True, text=True,
                          timeout=300)


def test_workspace_of_a_preset_file_is_its_brute_force(tmp_path) -> None:
    path = tmp_path / "pups.toml"
    path.write_text(dumps_mechanism(six_pups(lift=40.0)))
    r = run("workspace", "--mechanism", str(path), "--voxel", "8", "--json", "--export", str(tmp_path / "s.stl"))
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    assert data["engine"] == "general" and data["voxels"] > 100
    assert data["volume"] == pytest.approx(data["voxels"] * 8.0 ** 3)
    assert data["export"]["faces"] > 0
    # the same as --mechanism 6-pups --param lift=40
    r2 = run("workspace", "--mechanism", "6-pups", "--param", "lift=40", "--voxel", "8", "--json")
    assert json.loads(r2.stdout)["voxels"] == data["voxels"]
    # the general engine's result (tested voxel by voxel against the brute force in
    # test_mechanism_workspace.py) on the same grid
    res = compute_mechanism_workspace(six_pups(lift=40.0), WorkspaceSettings(voxel=8.0))
    assert res.grid.to_dict() == data["grid"] and res.voxels == data["voxels"]


def test_paper_preset_is_the_paper_engine() -> None:
    r = run("workspace", "--mechanism", "paper", "--param", "a=60", "--voxel", "8", "--json")
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    ref = compute_workspace(Design(a=60.0), WorkspaceSettings(voxel=8.0))
    assert data["engine"] == "paper" and data["voxels"] == ref.voxels and data["design"]["a"] == 60.0


def test_ik_of_a_general_mechanism(capsys) -> None:
    assert main(["ik", "--mechanism", "6-pups", "--pose", "5,10,160,0,8,0", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    mech = six_pups()
    assert data["feasible"] is True and len(data["chains"]) == 6
    from paraspace.kinematics.rotation import euler_zyx_deg

    lengths = mech.leg_lengths([c["q"] for c in data["chains"]], (5.0, 10.0, 160.0), euler_zyx_deg(0.0, 8.0, 0.0))
    np.testing.assert_allclose(lengths, [c["lengths"][0] for c in data["chains"]], atol=1e-9)
    assert np.all((lengths >= 114.5) & (lengths <= 164.5))
    assert main(["ik", "--mechanism", "6-pups", "--pose", "0,0,400,0,0,0", "--strict"]) == 1
    assert "unreachable" in capsys.readouterr().out


@pytest.mark.parametrize("args, message", [
    (["workspace", "--mechanism", "6-pups", "--a", "40"], "--a = '40' is invalid: expected not with --mechanism"),
    (["workspace", "--mechanism", "gough-stewart", "--bracket", "--bracket-refine", "7"], "bracket_refine = 7 is "
                                                                                          "invalid"),
    (["workspace", "--mechanism", "6-pss", "--dexterity"], "--dexterity"),
    (["workspace", "--mechanism", "6-pss", "--u-cone", "30"], "a description carries its own cones"),
    (["workspace", "--param", "lift=3"], "--param = 'lift=3' is invalid: expected only with --mechanism"),
    (["workspace", "--mechanism", "6-pups", "--param", "a=3"], "a parameter of preset '6-pups'"),
    (["workspace", "--mechanism", "6-pups", "--length-step", "0"], "length_step = 0.0 is invalid: valid range"),
    (["workspace", "--mechanism", "nope.toml"], "one of the presets"),
    (["ik", "--mechanism", "6-pups", "--pose", "0,0,150,0,0,0", "--carriage", "0,0,0,0,0,0"], "--carriage"),
])
def test_flags_that_do_not_apply_are_refused_by_name(args, message, capsys) -> None:
    assert main(args) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_paper_preset_keeps_the_paper_options(capsys) -> None:
    """With the paper preset the paper's options apply (the bracket here); a file equal to it too."""
    assert main(["workspace", "--mechanism", "paper", "--voxel", "8", "--bracket", "--bracket-refine", "0",
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["volume_inner"] <= data["volume"] <= data["volume_outer"]


def test_sweep_over_a_preset_parameter(capsys) -> None:
    assert main(["sweep", "--mechanism", "6-pups", "--param", "lift", "--values", "0,40", "--set",
                 "platform_half_angle=20", "--voxel", "8", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    for row, lift in zip(rows, (0.0, 40.0)):
        ref = compute_mechanism_workspace(six_pups(lift=lift, platform_half_angle=20.0), WorkspaceSettings(voxel=8.0))
        assert row["lift"] == lift and row["voxels"] == ref.voxels and row["engine"] == "general"
    assert rows[0]["voxels"] < rows[1]["voxels"]
    assert main(["sweep", "--mechanism", "6-pups", "--param", "lift", "--values", "0", "--plot", "lift.png"]) == 2
    assert "--plot" in capsys.readouterr().err
    assert main(["sweep", "--mechanism", "my.toml", "--param", "lift", "--values", "0"]) == 2
    assert "a sweep varies a preset's parameter" in capsys.readouterr().err


def test_bracket_of_a_general_mechanism(capsys) -> None:
    assert main(["workspace", "--mechanism", "6-pups", "--voxel", "8", "--bracket", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert 0 < data["volume_inner"] <= data["volume"] <= data["volume_outer"]
