"""No option is dropped on the way: every path (CLI, REST models, explorer, optimiser) that computes
TI_1/TI_2 with joint options gives the numbers of the direct core call with those options.

The reference is ``orientation_workspace`` called directly; the check that the option matters at
all is that the strokes-only call (the paper's model) gives other numbers.
"""

from __future__ import annotations

import dataclasses
import json

import pytest

from paraspace.app import cli, optimize_cli
from paraspace.app.api import models
from paraspace.app.api.errors import FieldError
from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.optimize import OptimizeSettings
from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace
from paraspace.kinematics.sweep import evaluate_design
from paraspace.kinematics.workspace import WorkspaceSettings

CONES = Joints(theta_u=30.0, theta_s=30.0, cone_axis="home")
CONES_JSON = {"theta_u": 30.0, "theta_s": 30.0, "cone_axis": "home"}


@pytest.fixture(scope="module")
def direct() -> dict[str, float]:
    """TI_1 of the paper's design at the default scan, with and without the cones (direct calls)."""
    return {"cones": orientation_workspace(Design(), OrientationSettings(joints=CONES)).ti1,
            "strokes": orientation_workspace(Design(), OrientationSettings()).ti1}


def test_cones_matter(direct: dict[str, float]) -> None:
    assert direct["cones"] < 0.95 * direct["strokes"]


def test_cli_sweep_keeps_the_joint_flags(direct: dict[str, float], capsys: pytest.CaptureFixture[str]) -> None:
    base = ["sweep", "--param", "a", "--values", "50", "--voxel", "8", "--measure", "TI_1", "--json"]
    assert cli.main(base) == 0
    plain = json.loads(capsys.readouterr().out)[0]
    assert cli.main([*base, "--u-cone", "30", "--s-cone", "30", "--cone-axis", "home"]) == 0
    cones = json.loads(capsys.readouterr().out)[0]
    assert plain["TI_1"] == pytest.approx(direct["strokes"], rel=1e-12)
    assert cones["TI_1"] == pytest.approx(direct["cones"], rel=1e-12)
    # the rows say whether the index measures the scan (the strokes-only phi saturates)
    assert plain["TI_saturated"] is True and "TI_1" in plain["saturation_note"]


def test_rest_study_joints_reach_the_orientation(direct: dict[str, float]) -> None:
    body = {"design": {}, "settings": {"voxel": 8.0, "joints": CONES_JSON}, "x": {"param": "a", "values": [50]},
            "orientation": {}}
    req = models.SweepRequest.model_validate(body)
    ws, ori = models.study_settings(req.settings, req.orientation)
    assert ws.joints == CONES and ori.joints == CONES
    assert evaluate_design(Design(), ws, orientation=ori)["TI_1"] == pytest.approx(direct["cones"], rel=1e-12)
    # given only in orientation: the workspace takes them too
    req = models.SweepRequest.model_validate({**body, "settings": {"voxel": 8.0},
                                              "orientation": {"joints": CONES_JSON}})
    assert models.study_settings(req.settings, req.orientation)[0].joints == CONES
    # given in both places and different: refused, naming the field
    req = models.SweepRequest.model_validate({**body, "orientation": {"joints": {"theta_u": 20.0}}})
    with pytest.raises(FieldError) as err:
        models.study_settings(req.settings, req.orientation)
    assert err.value.field == "orientation.joints"


def test_rest_optimize_joints_reach_the_orientation() -> None:
    req = models.OptimizeRequest.model_validate({"settings": {"voxel": 8.0, "joints": CONES_JSON},
                                                 "objectives": ["TI_1"], "orientation": {"angle_step": 3.0}})
    s = req.build()
    assert s.workspace.joints == CONES and s.orientation_used is not None and s.orientation_used.joints == CONES


def test_optimiser_orientation_takes_the_workspace_joints() -> None:
    s = OptimizeSettings(workspace=WorkspaceSettings(voxel=8.0, joints=CONES), objectives=["TI_1"])
    assert s.orientation_used == OrientationSettings(joints=CONES)
    with pytest.raises(ParameterError, match="orientation.joints"):
        OptimizeSettings(workspace=WorkspaceSettings(voxel=8.0, joints=CONES), objectives=["TI_1"],
                         orientation=OrientationSettings())


def test_explorer_optimize_panel_uses_the_explorers_joints() -> None:
    from paraspace.app.explorer.optimize_panel import PANEL_ORIENTATION, OptimizePanel

    panel = OptimizePanel.__new__(OptimizePanel)  # only settings(): no GUI needed
    panel.get_design, panel.get_joints = Design, lambda: CONES
    panel._values = lambda: {"params": "a,d_s", "objectives": "TI_1", "constraints": "",  # type: ignore[method-assign]
                             "population": 4, "generations": 1, "voxel": 8.0, "seed": 1}
    s = panel.settings()
    assert s.workspace.joints == CONES
    assert s.orientation_used == dataclasses.replace(PANEL_ORIENTATION, joints=CONES)


def test_cli_optimize_takes_joint_and_scan_flags() -> None:
    ns = cli.build_parser().parse_args(["optimize", "--objectives", "TI_1", "--voxel", "8", "--u-cone", "30",
                                        "--s-cone", "30", "--cone-axis", "home", "--angle-step", "3",
                                        "--position-step", "5", "--angle-range", "60", "--leg-diameter", "4"])
    s = optimize_cli.optimize_settings_from_args(ns)
    joints = dataclasses.replace(CONES, leg_diameter=4.0)
    assert s.workspace.joints == joints
    assert s.orientation_used == OrientationSettings(angle_range=60.0, angle_step=3.0, position_step=5.0, joints=joints)


def test_cli_orientation_scan_flags_give_the_direct_numbers(capsys: pytest.CaptureFixture[str]) -> None:
    flags = ["--angle-range", "45", "--angle-step", "3", "--position-step", "5"]
    assert cli.main(["orientation", *flags, "--u-cone", "30", "--cone-axis", "home", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    want = orientation_workspace(Design(), OrientationSettings(angle_range=45.0, angle_step=3.0, position_step=5.0,
                                                               joints=Joints(theta_u=30.0, cone_axis="home")))
    assert got["TI_1"] == want.ti1 and got["TI_2"] == want.ti2 and got["scan"]["angle_range"] == [-45.0, 45.0]
    # a scan flag where no scan runs is refused, not ignored
    assert cli.main(["orientation", "--at", "0,0,130", "--angle-step", "3"]) == 2
    assert "angle-step" in capsys.readouterr().err
    assert cli.main(["sweep", "--param", "a", "--values", "50", "--angle-step", "3"]) == 2
    assert "only with --measure TI_1/TI_2" in capsys.readouterr().err


def test_dask_sweep_keeps_the_joints() -> None:
    """The CLI's --workers path: the orientation settings (with their joints) reach the workers."""
    pytest.importorskip("distributed")
    from paraspace.kinematics.distributed import sweep_grid

    ori = OrientationSettings(angle_step=3.0, position_step=5.0, joints=CONES)
    rows = sweep_grid(Design(), {"a": [50.0]}, WorkspaceSettings(voxel=8.0, joints=CONES), orientation=ori,
                      n_workers=1)
    assert rows[0]["TI_1"] == orientation_workspace(Design(), ori).ti1
    assert rows[0]["TI_1"] != orientation_workspace(Design(), dataclasses.replace(ori, joints=Joints())).ti1
