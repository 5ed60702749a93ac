"""The `paraspace` command line as outside scripts call it (JSON contract, exit codes, one-line errors).

The JSON contract runs in a real subprocess (`python -m paraspace.app.cli`, as an outside script
calls it); the other commands run in-process through the same ``main()`` (tests/cli_inprocess.py):
the same parser, commands, output and exit codes, without a fresh interpreter per call."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from cli_inprocess import run_cli  # tests/ (pytest's prepend import mode)

from paraspace.kinematics.design import Design
from paraspace.kinematics.inverse import leg_lengths
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


def run(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    """``paraspace ARGS...`` in this process (the same main(); see the module's docstring)."""
    proc = run_cli(*args)
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


def run_process(*args: str) -> subprocess.CompletedProcess:
    """``paraspace ARGS...`` as a real subprocess: the entry point as outside scripts call it."""
    proc = subprocess.run([sys.executable, "-m", "paraspace.app.cli", *args], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr
    return proc


def test_workspace_json_contract(tmp_path):
    out = tmp_path / "shell.stl"
    data = json.loads(run_process("workspace", "--voxel", "8", "--a", "60", "--json", "--export", str(out)).stdout)
    for key in ("volume", "voxel_size", "voxels", "compute_seconds", "components", "void_volume", "void_ratio",
                "hollowness", "boundary_closed", "genus", "bounds"):
        assert key in data, key
    ref = compute_workspace(Design(a=60), WorkspaceSettings(voxel=8.0))
    assert data["volume"] == pytest.approx(ref.volume)
    assert data["voxels"] == ref.voxels and data["voxel_size"] == 8.0
    assert data["volume"] == pytest.approx(data["voxels"] * 8.0 ** 3)
    assert 0 < data["compute_seconds"] < 60
    import trimesh

    mesh = trimesh.load(out)
    assert mesh.is_watertight and mesh.volume == pytest.approx(ref.volume, rel=0.1)


def test_ik_json_matches_core():
    data = json.loads(run("ik", "--pose", "10,-5,135,3,-2,4", "--json").stdout)
    assert data["feasible"] is True
    lengths = leg_lengths(Design(), Pose(10, -5, 135, 3, -2, 4), data["d"], data["eta"])
    assert np.allclose(lengths, data["lengths"])
    assert data["condition_number"] > 1
    bad = json.loads(run("ik", "--pose", "0,0,60,0,0,0", "--json").stdout)
    assert bad["feasible"] is False and "too short" in bad["message"]
    assert run("ik", "--pose", "0,0,60,0,0,0", "--strict", check=False).returncode == 1


def test_sweep_json_csv_plot(tmp_path):
    csv_path, png = tmp_path / "s.csv", tmp_path / "s.png"
    data = json.loads(run("sweep", "--param", "l_s", "--values", "30,60", "--voxel", "10", "--json",
                          "--csv", str(csv_path), "--plot", str(png)).stdout)
    assert [row["value"] for row in data] == [30, 60]
    assert data[1]["volume"] > data[0]["volume"] > 0
    for row, ls in zip(data, (30, 60)):
        assert row["volume"] == pytest.approx(compute_workspace(Design(l_s=ls), WorkspaceSettings(voxel=10.0)).volume)
    lines = csv_path.read_text().strip().splitlines()
    assert len(lines) == 3 and "volume" in lines[0]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("args,field", [
    (["workspace", "--a", "-5"], "a = "),
    (["workspace", "--d-s", "150"], "d_s"),
    (["workspace", "--voxel", "0"], "voxel"),
    (["workspace", "--eta-range", "left"], "eta_range"),
    (["workspace", "--export", "x.doc"], "export"),
    (["ik", "--pose", "1,2"], "pose"),
    (["sweep", "--param", "zeta", "--values", "1,2"], "param"),
    (["sweep", "--param", "a", "--values", "1,x"], "values"),
    (["serve", "--port", "99999"], "port"),
])
def test_bad_input_one_line_naming_field(args, field):
    proc = run(*args, check=False)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and field in lines[0] and "Traceback" not in proc.stderr


def test_workspace_diagnostics_names_chains_and_limits():
    data = json.loads(run("workspace", "--voxel", "8", "--diagnostics", "--json").stdout)
    assert [c["chain"] for c in data["limit_binding"]["per_chain"]] == [1, 2, 3]
    assert sum(data["limit_binding"]["fractions"].values()) == pytest.approx(1.0)
    assert "summary" in data["chain_binding"]
    text = run("workspace", "--voxel", "8", "--diagnostics").stdout
    assert "l_max" in text and "chain" in text


def test_more_workers_than_cores_says_so_and_runs_serially():
    import os

    n = (os.cpu_count() or 1) + 8
    proc = run("sweep", "--param", "a", "--values", "40,60", "--voxel", "10", "--workers", str(n), "--json")
    assert proc.returncode == 0
    assert f"--workers {n} exceeds" in proc.stderr and "serially" in proc.stderr
    rows = __import__("json").loads(proc.stdout)
    assert [r["value"] for r in rows] == [40.0, 60.0] and all(r["volume"] > 0 for r in rows)


def test_ik_and_the_pose_table_never_print_negative_zero():
    from paraspace.app.numfmt import fixed

    assert fixed(-1e-15, 3) == "0.000" and fixed(-0.0) == "0.00" and fixed(-0.004, 2) == "0.00"
    assert fixed(-0.006, 2) == "-0.01" and fixed(2.5, 1, 6) == "   2.5"
    out = run("ik", "--pose", "0,0,130,0,0,0").stdout
    assert "eta =    0.000" in out and "-0.000" not in out


def test_significant_digits_read_the_same_everywhere():
    from paraspace.app.numfmt import significant

    assert significant(29400.0) == "29,400" and significant(13579.333) == "13,580"
    # trailing zeros kept: a value and its bracket show the same number of digits
    assert significant(5.1201e6) == "5.120e+06" and significant(4.9049e6) == "4.905e+06"
    assert significant(0.402) == "0.4020" and significant(12.5, 3) == "12.5"
    assert significant(0.0) == "0" and significant(-2.5e-5) == "-2.500e-05"


def test_cli_joint_flags_echo_and_one_message():
    r = run_cli("workspace", "--voxel", "8", "--u-cone", "45", "--s-cone", "40", "--cone-axis", "home",
            "--leg-diameter", "6", "--json")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["joints"] == {"theta_u": 45.0, "theta_s": 40.0, "cone_axis": "home", "leg_diameter": 6.0,
                             "clearance": 0.0}
    for flag, value, text in (("--u-cone", "0", "theta_u"), ("--s-cone", "x", "theta_s"),
                              ("--leg-diameter", "-1", "leg_diameter")):
        r = run_cli("ik", "--pose", "0,0,130,0,0,0", flag, value)
        assert r.returncode == 2 and text in r.stderr and "valid range" in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1
    r = run_cli("orientation", "--json", "--u-cone", "30", "--s-cone", "30")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert "saturated" in out and out["settings"]["joints"]["theta_u"] == 30.0


def test_workspace_text_leads_with_the_stable_measures():
    """Issue 21 item 4: pieces, stable genus and fragments come first (labelled stable in h); the raw
    voxel counts come after them, labelled as such; the numbers are the measures' own."""
    from paraspace.kinematics.measures import measure_workspace

    lines = run("workspace", "--voxel", "8", "--a", "15").stdout.splitlines()
    keys = [ln.split()[0] for ln in lines]
    assert keys.index("pieces") < keys.index("stable_genus") < keys.index("fragments") < keys.index("voxel-level")
    m = measure_workspace(compute_workspace(Design(a=15.0), WorkspaceSettings(voxel=8.0)))
    text = dict((ln.split()[0], ln) for ln in lines)
    assert text["pieces"].split()[1] == str(m.pieces) and "stable in h" in text["pieces"]
    assert text["stable_genus"].split()[1] == str(m.stable_genus)
    assert f"components {m.components}, genus {m.genus}" in text["voxel-level"]
    assert "change with h" in text["voxel-level"]
