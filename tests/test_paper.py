"""The paper comparison (kinematics/paper.py, `paraspace paper`, the explorer's Paper tab): every
number is recomputed here with the ordinary functions, independently of the comparison's code."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from paraspace.kinematics.design import Design
from paraspace.kinematics.measures import measure_workspace
from paraspace.kinematics.paper import PAPER_CLAIMS, PAPER_REPORTED, paper_comparison
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


@pytest.fixture(scope="module")
def comparison():
    return paper_comparison(voxel=8.0)


def test_reported_values_are_the_papers(comparison):
    assert comparison["reported"] == {"volume": 3.47e6, "TI_1": 2789.17, "TI_2": 4853.13} == PAPER_REPORTED


def test_volumes_and_closest_convention(comparison):
    rows = {r["convention"]: r["volume"] for r in comparison["volume"]["ours"]}
    s = WorkspaceSettings(voxel=8.0)
    assert rows["centered arc range (default)"] == compute_workspace(Design(), s).volume
    assert rows["from-zero arc range"] == compute_workspace(Design(eta_range="from-zero"), s).volume
    closest = min(rows, key=lambda k: abs(rows[k] - 3.47e6))
    assert comparison["volume"]["closest"] == closest


def test_claims_are_recomputed_independently(comparison):
    assert len(comparison["claims"]) == len(PAPER_CLAIMS) == 24
    s = WorkspaceSettings(voxel=8.0)
    ref = measure_workspace(compute_workspace(Design(), s))
    for (param, value, measure, expect), c in zip(PAPER_CLAIMS, comparison["claims"]):
        m = measure_workspace(compute_workspace(Design().replace(**{param: value}), s))
        ours = getattr(m, measure)
        holds = (bool(ours) == expect) if isinstance(expect, bool) else (
            ours < getattr(ref, measure) if expect == "<" else ours > getattr(ref, measure))
        assert c["holds"] == holds, c
    assert comparison["summary"].startswith(f"{sum(c['holds'] for c in comparison['claims'])} of 24")


def test_indices_flag_the_scan_limit_without_joint_limits(comparison):
    rows = comparison["indices"]["ours"]
    assert rows[0]["saturation_note"]  # the paper's model: φ twists through the whole scan
    assert rows[2]["TI_1"] < rows[0]["TI_1"]  # tight cones about the home directions limit the twist


def test_cli_paper_json():
    r = subprocess.run([sys.executable, "-m", "paraspace.app.cli", "paper", "--voxel", "10", "--json"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["reported"]["TI_1"] == 2789.17 and len(out["claims"]) == 24 and out["voxel"] == 10.0
    r = subprocess.run([sys.executable, "-m", "paraspace.app.cli", "paper", "--voxel", "0"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "voxel" in r.stderr
