"""Every script of examples/ runs: its ``main()`` is called with fast settings (coarse voxels, the
explorer on a free port, stopped at once) and what it returns is checked."""

from __future__ import annotations

import math
import pathlib
import re
import runpy
from collections.abc import Callable
from typing import Any

import paraspace as ps

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("[0-9][0-9]_*.py"))


def _main(stem: str) -> Callable[..., Any]:
    path = ROOT / "examples" / f"{stem}.py"
    return runpy.run_path(str(path))["main"]  # run_name is not "__main__": main() is not called


def test_examples_are_numbered_scripts_with_a_main():
    assert len(EXAMPLES) >= 5
    for path in EXAMPLES:
        text = path.read_text()
        assert text.startswith('"""'), f"{path.name}: no docstring"
        assert "\ndef main(" in text, path.name
        assert "main(" in text.split('if __name__ == "__main__":')[1], path.name


def test_workspace_volume(capsys):
    m = _main("01_workspace_volume")(voxel=8.0)
    assert m.volume == m.voxels * 8.0 ** 3 > 0 and m.voids == 0
    assert f"voxels          {m.voxels} of 8^3" in capsys.readouterr().out


def test_inverse_and_forward_kinematics(capsys):
    pose = _main("02_inverse_and_forward_kinematics")(x=10.0, y=-5.0, z=130.0, psi=5.0)
    got = (pose.x, pose.y, pose.z, pose.psi, pose.theta, pose.phi)
    assert all(math.isclose(a, b, abs_tol=1e-8) for a, b in zip(got, (10.0, -5.0, 130.0, 5.0, 0.0, 0.0)))
    assert "converged" in capsys.readouterr().out


def test_design_sweep():
    rows = _main("03_design_sweep")(param="d_s", voxel=10.0, points=3)
    assert [r["value"] for r in rows] == [ps.PARAMS["d_s"].slider_min, 55.0, ps.PARAMS["d_s"].slider_max]
    # an independent computation of the middle point
    mid = ps.compute_workspace(ps.Design(d_s=55.0), ps.WorkspaceSettings(voxel=10.0))
    assert rows[1]["volume"] == mid.volume


def test_export_shell(tmp_path):
    from paraspace.kinematics.shell import load_shell

    path = _main("04_export_shell")(out=str(tmp_path / "w.stl"), voxel=8.0, max_faces=2000)
    mesh = load_shell(path.read_bytes(), "stl")
    assert mesh.is_watertight and 0 < len(mesh.faces) <= 2000


def test_explorer_starts_and_stops(capsys):
    url = _main("05_explorer")(port=0, serve=False)
    port = int(re.fullmatch(r"http://127\.0\.0\.1:(\d+)/", url).group(1))
    assert port > 0 and f"paraspace explorer: {url}" in capsys.readouterr().out


def test_design_for_a_task(capsys):
    region, traj = _main("06_design_for_a_task")(voxel=8.0, poses=20)
    assert 0.0 <= region.fraction <= 1.0 and len(traj.poses) == 20
    assert "fraction" in capsys.readouterr().out
