"""``--mechanism FILE|PRESET`` and ``--param NAME=VALUE`` on ``paraspace workspace`` (with ``--tilt/--torsion``
and ``--dexterity``), ``orientation`` and ``ik``.

The numbers are checked against independent computations: the paper's engine for the paper preset,
the description's brute force (kinematics/mechanism.reachable_brute_force) for a general mechanism's
voxels and its forward model for the IK's carriage values. Refusals name the flag.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_inprocess import run_cli  # tests/ (pytest's prepend import mode)

from paraspace.app.cli import main
from paraspace.kinematics.design import Design
from paraspace.kinematics.mechanism import dumps_mechanism
from paraspace.kinematics.mechanism_workspace import compute_mechanism_workspace
from paraspace.kinematics.presets import six_pups
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

run = run_cli  # the command line through main(), in this process (tests/cli_inprocess.py)


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
    (["workspace", "--mechanism", "6-pss", "--dexterity", "--dexterity-mode", "best"],
     "dexterity_mode = 'best' is invalid: expected 'resolved' for a general mechanism"),
    (["workspace", "--mechanism", "6-pups", "--tilt", "100"], "tilt"),
    (["orientation", "--mechanism", "6-pups", "--at", "0,0,150"], "--at = '0,0,150' is invalid: expected only for "
                                                                   "the paper's mechanism"),
    (["orientation", "--mechanism", "6-pups", "--u-cone", "30"], "a description carries its own cones"),
    (["orientation", "--mechanism", "6-pups", "--angle-step", "0"], "angle_step"),
    (["orientation", "--param", "lift=3"], "--param = 'lift=3' is invalid: expected only with --mechanism"),
    (["workspace", "--mechanism", "gough-stewart", "--bracket", "--bracket-refine", "7"], "bracket_refine = 7 is "
                                                                                          "invalid"),
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


SCAN_ARGS = ["--angle-range", "60", "--angle-step", "10", "--position-step", "12", "--z0", "150"]


def test_orientation_of_a_general_mechanism_is_the_cores(capsys) -> None:
    """The command's numbers are the core's (tested per sample against the brute force in
    test_mechanism_orientation.py), in the paper path's output shape plus the lines it scanned."""
    from paraspace.kinematics.mechanism_orientation import mechanism_orientation_workspace
    from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace

    assert main(["orientation", "--mechanism", "6-pups", "--param", "lift=40", *SCAN_ARGS, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    scan = OrientationSettings(angle_range=60.0, angle_step=10.0, position_step=12.0, z0=150.0)
    ref = mechanism_orientation_workspace(six_pups(lift=40.0), scan)
    assert data["engine"] == "general" and data["symmetry_order"] == 3 and data["second_line_azimuth"] == 60.0
    assert (data["TI_1"], data["TI_2"]) == (ref.ti1, ref.ti2) and data["TI_1"] > 0
    assert set(data["regions"]) == {f"{ln}/{rt}" for ln, rt in ref.regions}
    paper = orientation_workspace(Design(), scan)
    assert main(["orientation", "--mechanism", "paper", *SCAN_ARGS, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["engine"] == "paper" and (data["TI_1"], data["TI_2"]) == (paper.ti1, paper.ti2)
    assert main(["orientation", "--mechanism", "gough-stewart", *SCAN_ARGS]) == 0
    assert "symmetry order 3" in capsys.readouterr().out


def test_total_orientation_and_dexterity_of_a_general_mechanism(capsys) -> None:
    from paraspace.kinematics.mechanism_dexterity import mechanism_dexterity_field
    from paraspace.kinematics.mechanism_orientation import mechanism_total_orientation

    assert main(["workspace", "--mechanism", "6-pups", "--voxel", "16", "--tilt", "10", "--angle-step", "10",
                 "--dexterity", "--kappa-min", "0.3", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    settings = WorkspaceSettings(voxel=16.0)
    dx = mechanism_total_orientation(six_pups(), 10.0, 0.0, 10.0, settings)
    field = mechanism_dexterity_field(dx.position, 0.3)
    t = data["total_orientation"]
    assert t["voxels"] == dx.voxels and 0 < t["voxels"] < data["voxels"]
    assert data["gci"] == pytest.approx(field.gci) and data["kappa_min"] == 0.3
    assert data["well_conditioned_volume"] == field.well_conditioned_volume


def test_a_general_mechanism_prints_the_measures_as_the_paper_path_does() -> None:
    """The text output names the same measures, in the same words, for a general mechanism as for the
    paper's (one printer for both), and its numbers are those of ``--json``."""
    from paraspace.app.numfmt import significant

    def labels(text: str) -> list[str]:
        return [line.split()[0] for line in text.splitlines() if line.strip()]

    args = ("--voxel", "8", "--bracket", "--bracket-refine", "0")
    text = run("workspace", "--mechanism", "gough-stewart", *args)
    data = json.loads(run("workspace", "--mechanism", "gough-stewart", *args, "--json").stdout)
    paper = run("workspace", "--mechanism", "paper", *args)
    assert text.returncode == 0 and paper.returncode == 0, text.stderr + paper.stderr
    lines = dict(line.split(None, 1) for line in text.stdout.splitlines() if line.strip())
    shared = ["volume", "certified", "pieces", "stable_genus", "fragments", "boundary", "hollowness", "voids",
              "voxel-level", "bounds", "compute_seconds"]
    assert [w for w in labels(text.stdout) if w in shared] == shared
    assert [w for w in labels(paper.stdout) if w in shared] == shared
    assert lines["volume"].startswith(f"{significant(data['volume'], 4)} units³  ({data['voxels']:,} voxels of edge 8")
    assert lines["certified"].startswith(f"{significant(data['volume_inner'], 4)} <= V <= "
                                         f"{significant(data['volume_outer'], 4)}")
    verdict = "complete" if data["boundary_complete"] else f"incomplete  ({data['completeness_reason']})"
    assert lines["boundary"] == verdict
    assert lines["pieces"].startswith(f"{data['pieces']} ")
    assert lines["stable_genus"].startswith(f"{data['stable_genus']} ")
    lo, hi = data["bounds"]["min"], data["bounds"]["max"]
    assert lines["bounds"] == ", ".join(f"{ax} [{significant(a, 4)}, {significant(b, 4)}]"
                                        for ax, a, b in zip("xyz", lo, hi))
