"""One rule per setting: the core tables of kinematics.settings are read by every entry point.

A bound changed in the table (monkeypatched) must change the core's validation, the URL parser, the
CLI flag, the explorer's slider spec and the REST model (built in a fresh process so the model is
derived from the patched table), all with the same range text.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
import textwrap

import pytest

from paraspace.app import cli, optimize_cli
from paraspace.app.api import models
from paraspace.app.urlstate import SETTING_RANGES, SETTING_SLIDERS, Range, parse_query
from paraspace.kinematics.design import ParameterError
from paraspace.kinematics.optimize import OptimizeSettings
from paraspace.kinematics.orientation import OrientationSettings
from paraspace.kinematics.settings import OPTIMIZE, ORIENTATION, WORKSPACE
from paraspace.kinematics.workspace import WorkspaceSettings


def _patched_voxel(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(WORKSPACE, "voxel", dataclasses.replace(WORKSPACE["voxel"], hi=50.0, slider=(1.0, 8.0, 0.25)))


def test_patched_voxel_bound_reaches_core_url_cli_and_slider(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    # before the patch, 60 is a valid voxel everywhere
    assert parse_query("voxel=60")[1] == []
    assert WorkspaceSettings(voxel=60.0).voxel == 60.0
    _patched_voxel(monkeypatch)
    with pytest.raises(ParameterError, match=r"voxel = 60.0 is invalid: valid range \[0.25, 50\]"):
        WorkspaceSettings(voxel=60.0)
    state, msgs = parse_query("voxel=60")
    assert state.voxel == 2.0 and len(msgs) == 1 and "valid range [0.25, 50]" in msgs[0]
    assert parse_query("voxel=50")[0].voxel == 50.0
    assert SETTING_RANGES["voxel"] == Range(0.25, 50.0, 0.25)
    assert SETTING_SLIDERS["voxel"] == Range(1.0, 8.0, 0.25)
    assert cli.main(["workspace", "--voxel", "60"]) == 2
    assert "[0.25, 50]" in capsys.readouterr().err
    assert cli.main(["sweep", "--param", "a", "--values", "50", "--voxel", "x"]) == 2
    assert "voxel = 'x' is invalid: valid range [0.25, 50] (a number)" in capsys.readouterr().err


def test_patched_orientation_bound_reaches_core_and_url(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(ORIENTATION, "z0", dataclasses.replace(ORIENTATION["z0"], lo=10.0, slider=(10.0, 300.0, 2.0)))
    with pytest.raises(ParameterError, match=r"z0 = 5.0 is invalid: valid range \[10, 10000\]"):
        OrientationSettings(z0=5.0)
    assert "valid range [10, 10000]" in parse_query("z0=5")[1][0]
    assert SETTING_SLIDERS["z0"] == Range(10.0, 300.0, 2.0)


_REST_SCRIPT = textwrap.dedent("""
    import dataclasses, json
    from paraspace.kinematics.settings import ORIENTATION, WORKSPACE
    WORKSPACE["voxel"] = dataclasses.replace(WORKSPACE["voxel"], hi=50.0)
    ORIENTATION["angle_step"] = dataclasses.replace(ORIENTATION["angle_step"], lo=0.1, hi=20.0)
    from paraspace.kinematics.settings import OPTIMIZE
    OPTIMIZE["population"] = dataclasses.replace(OPTIMIZE["population"], hi=200)
    from paraspace.app.api import errors, models
    w = models.WorkspaceSettingsIn.model_json_schema()["properties"]["voxel"]
    o = models.OrientationSettingsIn.model_json_schema()["properties"]["angle_step"]
    p = models.OptimizeRequest.model_json_schema()["properties"]["population"]
    print(json.dumps({"population": [p["minimum"], p["maximum"], errors.RANGES[("body", "population")]],
                      "voxel": [w["minimum"], w["maximum"], errors.RANGES[("settings", "voxel")]],
                      "angle_step": [o["minimum"], o["maximum"], errors.RANGES[("orientation", "angle_step")]]}))
""")


def test_patched_bounds_reach_the_rest_model() -> None:
    out = subprocess.run([sys.executable, "-c", _REST_SCRIPT], capture_output=True, text=True, timeout=300, check=True)
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got == {"voxel": [0.25, 50.0, "[0.25, 50]"], "angle_step": [0.1, 20.0, "[0.1, 20] degrees"],
                   "population": [4, 200, "[4, 200]"]}


@pytest.mark.parametrize(("model", "section", "table"), [
    (models.WorkspaceSettingsIn, "settings", WORKSPACE), (models.OrientationSettingsIn, "orientation", ORIENTATION)])
def test_every_table_entry_is_the_rest_field(model, section: str, table: dict) -> None:
    props = model.model_json_schema()["properties"]
    for name, spec in table.items():
        p = props[name]
        assert p["default"] == spec.default and p["maximum"] == spec.hi
        assert p[("exclusiveMinimum" if spec.lo_open else "minimum")] == spec.lo
        assert models.RANGES[(section, name)] == spec.range_text()


def test_documented_ranges_unchanged() -> None:
    """The ranges the README and the OpenAPI document state (written here independently)."""
    assert (WORKSPACE["voxel"].lo, WORKSPACE["voxel"].hi) == (0.25, 100.0)
    assert ORIENTATION["angle_range"].range_text() == "(0, 180] degrees"
    assert WORKSPACE["bracket_refine"].range_text() == "[0, 3]"


def test_table_defaults_are_the_dataclass_defaults() -> None:
    for cls, table in ((WorkspaceSettings, WORKSPACE), (OrientationSettings, ORIENTATION)):
        defaults = {f.name: f.default for f in dataclasses.fields(cls)}
        for name, spec in table.items():
            assert defaults[name] == spec.default, (cls.__name__, name)


def test_patched_scan_bound_reaches_the_cli_flags(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    monkeypatch.setitem(ORIENTATION, "angle_range", dataclasses.replace(ORIENTATION["angle_range"], hi=60.0))
    assert cli.main(["orientation", "--angle-range", "70"]) == 2
    assert "angle_range = 70.0 is invalid: valid range (0, 60] degrees" in capsys.readouterr().err
    assert "(0, 60] degrees" in cli.build_parser()._subparsers._group_actions[0].choices["sweep"].format_help()


def test_patched_optimiser_bound_reaches_core_and_cli(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    assert OptimizeSettings(population=500).population == 500
    monkeypatch.setitem(OPTIMIZE, "population", dataclasses.replace(OPTIMIZE["population"], hi=200))
    with pytest.raises(ParameterError, match=r"population = 500 is invalid: valid range \[4, 200\] \(an integer\)"):
        OptimizeSettings(population=500)
    ns = cli.build_parser().parse_args(["optimize", "--population", "500"])
    with pytest.raises(ParameterError, match=r"\[4, 200\]"):
        optimize_cli.optimize_settings_from_args(ns)
    assert "[4, 200]" in cli.build_parser()._subparsers._group_actions[0].choices["optimize"].format_help()


def test_patched_total_orientation_bounds_reach_core_cli_and_sliders(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    from paraspace.kinematics.dexterous import check_step, orientation_samples
    from paraspace.kinematics.settings import TILT_TORSION, TOTAL_ORIENTATION
    from paraspace.kinematics.tilt_torsion import TiltTorsionSettings

    assert check_step(20.0) == 20.0 and TiltTorsionSettings(azimuth_step=60.0).azimuth_step == 60.0
    monkeypatch.setitem(TOTAL_ORIENTATION, "angle_step",
                        dataclasses.replace(TOTAL_ORIENTATION["angle_step"], hi=10.0, slider=(1.0, 9.0, 1.0)))
    monkeypatch.setitem(TOTAL_ORIENTATION, "tilt", dataclasses.replace(TOTAL_ORIENTATION["tilt"], hi=30.0))
    monkeypatch.setitem(TILT_TORSION, "azimuth_step", dataclasses.replace(TILT_TORSION["azimuth_step"], hi=45.0))
    with pytest.raises(ParameterError, match=r"angle_step = 20.0 is invalid: valid range \[0.25, 10\] degrees"):
        check_step(20.0)
    with pytest.raises(ParameterError, match=r"tilt = 40.0 is invalid: valid range \[0, 30\] degrees"):
        orientation_samples(40.0, 10.0, 5.0)
    with pytest.raises(ParameterError, match=r"azimuth_step = 60.0 is invalid: valid range \[0.1, 45\] degrees"):
        TiltTorsionSettings(azimuth_step=60.0)
    assert cli.main(["workspace", "--voxel", "8", "--tilt", "40", "--torsion", "5"]) == 2
    assert "tilt = 40.0 is invalid: valid range [0, 30] degrees" in capsys.readouterr().err

    class Gui:  # records the explorer's slider specs
        def __init__(self) -> None:
            self.sliders: dict[str, dict] = {}

        def add_slider(self, label: str, **kw):
            self.sliders[label] = kw
            return Handle()

    class Handle:  # a slider handle: the explorer widens its track on updates (app/explorer/typed_values.py)
        def on_update(self, callback) -> None:
            pass

    from paraspace.app.explorer.dexterous_panel import _slider

    gui = Gui()
    _slider(gui, "angle step (deg)", TOTAL_ORIENTATION["angle_step"])
    spec = gui.sliders["angle step (deg)"]
    assert (spec["min"], spec["max"], spec["step"]) == (1.0, 9.0, 1.0) and "[0.25, 10] degrees" in spec["hint"]
