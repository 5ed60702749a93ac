"""Mechanism descriptions (kinematics/mechanism.py) and presets (kinematics/presets.py).

Checked against independent computations: the paper preset's joints and leg lengths against the
paper's own equations (kinematics/geometry.py, inverse.py); the Gough-Stewart preset against the
paper's model with d_s = eta_s = 0 where the geometries coincide (the paper model's reachability,
an exact 6-UPS test there, decides the same poses as the description's brute force); the TOML
round trip; and every refusal names its field.
"""

from __future__ import annotations

import json
import math
import subprocess

import numpy as np
import pytest
from cli_inprocess import run_cli  # tests/ (pytest's prepend import mode)

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.geometry import base_points, platform_points
from paraspace.kinematics.inverse import leg_lengths
from paraspace.kinematics.mechanism import (
    dumps_mechanism,
    loads_mechanism,
    parse_mechanism,
    reachable_brute_force,
)
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.presets import PRESETS, gough_stewart, paper, preset, six_pss, six_pups
from paraspace.kinematics.rotation import euler_zyx_deg
from paraspace.kinematics.workspace import reachable

ISSUE_EXAMPLE = """
name = "narrow-pair hexapod"
[[chains]]
carriage = [
  { type = "revolute", axis = [0, 0, 1], range = [-15.0, 15.0] },
  { type = "prismatic", axis = [-1, 0, 0], range = [0.0, 50.0] },
]
legs = [
  { base = [100.0, 7.0, 0.0], platform = [43.3, 25.0, 0.0], length = [114.5, 164.5] },
]
"""


@pytest.mark.parametrize("eta_range", ["centered", "from-zero"])
def test_paper_preset_is_the_papers_equations(eta_range: str) -> None:
    rng = np.random.default_rng(1)
    design = Design(a=37.0, b=20.0, d_s=60.0, r=110.0, l_min=120.0, l_s=40.0, eta_s=50.0, eta_range=eta_range)
    mech = paper(a=37.0, b=20.0, d_s=60.0, r=110.0, l_min=120.0, l_s=40.0, eta_s=50.0, eta_range=eta_range)
    lo, hi = design.eta_limits
    for chain in mech.chains:
        assert chain.carriage[0].range == (lo, hi) and chain.carriage[1].range == (0.0, 60.0)
    for _ in range(20):
        d = rng.uniform(0, 60, 3)
        eta = rng.uniform(lo, hi, 3)
        pose = Pose(*rng.uniform(-30, 30, 2), rng.uniform(100, 150), *rng.uniform(-20, 20, 3))
        q = [(eta[i], d[i]) for i in range(3)]
        np.testing.assert_allclose(mech.base_points(q), base_points(design, d, eta).reshape(6, 3), atol=1e-9)
        np.testing.assert_allclose(mech.platform_points(pose.position, pose.rotation),
                                   platform_points(design, pose.position, pose.rotation).reshape(6, 3), atol=1e-9)
        np.testing.assert_allclose(mech.leg_lengths(q, pose.position, pose.rotation),
                                   leg_lengths(design, pose, d, eta).reshape(6), atol=1e-9)


def test_gough_stewart_equals_the_paper_without_carriage_strokes() -> None:
    """The paper's mechanism with d_s = eta_s = 0 is a 6-UPS: base pairs at gamma_i +- atan(b/2r) on
    radius sqrt(r^2 + b^2/4), platform joints at gamma_i +- 30 on radius a."""
    design = Design(a=50.0, b=14.0, d_s=0.0, r=100.0, l_min=114.5, l_s=50.0, eta_s=0.0)
    gs = gough_stewart(base_radius=math.hypot(100.0, 7.0), base_half_angle=math.degrees(math.atan2(7.0, 100.0)),
                       platform_radius=50.0, platform_half_angle=30.0, l_min=114.5, l_max=164.5)
    np.testing.assert_allclose(gs.base_points([[]] * 6), base_points(design, np.zeros(3), np.zeros(3)).reshape(6, 3),
                               atol=1e-9)
    rng = np.random.default_rng(2)
    pts = np.column_stack([rng.uniform(-40, 40, 300), rng.uniform(-40, 40, 300), rng.uniform(90, 170, 300)])
    for orientation in [(0.0, 0.0, 0.0), (10.0, -15.0, 5.0)]:
        rot = euler_zyx_deg(*orientation)
        paper_says = reachable(design, pts, orientation)
        brute = reachable_brute_force(gs, pts, rot)
        assert 20 < paper_says.sum() < len(pts) - 20, "the sample straddles the workspace boundary"
        np.testing.assert_array_equal(brute, paper_says)


def test_brute_force_agrees_with_the_paper_engine_with_carriages() -> None:
    """The description's brute force (sampled carriage joints) against the paper model's engine:
    a pose the engine finds reachable has a carriage grid point nearby, so with a fine grid the
    two agree away from the boundary; every disagreement lies within the grid's resolution."""
    design = Design()
    mech = paper()
    rng = np.random.default_rng(3)
    pts = np.column_stack([rng.uniform(-120, 120, 150), rng.uniform(-120, 120, 150), rng.uniform(20, 180, 150)])
    engine = reachable(design, pts, (0.0, 0.0, 0.0))
    brute = reachable_brute_force(mech, pts, np.eye(3), samples=61)
    assert 20 < engine.sum() < len(pts) - 20
    # the grid can only miss a reachable pose (a sample that passes proves reachability)
    assert not np.any(brute & ~engine)
    assert (engine != brute).sum() <= 3


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_every_preset_round_trips_through_toml_and_json(name: str) -> None:
    mech = preset(name)
    text = dumps_mechanism(mech)
    again = loads_mechanism(text)
    assert again == mech
    assert loads_mechanism(json.dumps(mech.to_dict())) == mech
    assert sum(len(c.legs) for c in mech.chains) == 6


def test_presets_take_their_named_parameters() -> None:
    assert six_pups(lift=30.0).chains[0].carriage[0].range == (0.0, 30.0)
    legs = six_pss(leg_length=140.0).chains[3].legs
    assert legs[0].length == (140.0, 140.0)
    with pytest.raises(ParameterError, match=r"lift = -1 is invalid: valid range \[0, 1000\]"):
        six_pups(lift=-1)
    with pytest.raises(ParameterError, match="a parameter of preset 'gough-stewart'"):
        preset("gough-stewart", {"a": 3})
    with pytest.raises(ParameterError, match="one of the presets"):
        preset("tripod")


def test_six_pups_lift_reaches_higher_than_its_gough_stewart() -> None:
    gs, pups = gough_stewart(), six_pups(lift=50.0)
    top = (0.0, 0.0, 180.0)  # the 6-UPS reaches about z = 147 here
    assert not reachable_brute_force(gs, top, np.eye(3))
    assert reachable_brute_force(pups, top, np.eye(3))


def test_issue_example_parses_and_needs_six_legs() -> None:
    with pytest.raises(ParameterError) as err:
        loads_mechanism(ISSUE_EXAMPLE)
    assert err.value.field == "chains" and "exactly 6 legs" in str(err.value)
    six = ISSUE_EXAMPLE + "\n".join(
        ["[[chains]]\ncarriage = []\nlegs = [ { base = [100.0, 7.0, 0.0], platform = [43.3, 25.0, 0.0], "
         "length = [114.5, 164.5] } ]"] * 5)
    mech = loads_mechanism(six)
    assert mech.name == "narrow-pair hexapod" and len(mech.chains) == 6


@pytest.mark.parametrize("edit, field, expected", [
    (lambda d: d["chains"][0]["carriage"][0].update(type="helical"), "chains[0].carriage[0].type", "'revolute' or"),
    (lambda d: d["chains"][0]["carriage"][0].update(axis=[0, 0, 0]), "chains[0].carriage[0].axis", "non-zero axis"),
    (lambda d: d["chains"][0]["carriage"][0].update(range=[10, -10]), "chains[0].carriage[0].range", "low <= high"),
    (lambda d: d["chains"][0]["carriage"][0].update(range=[-200, 10]), "chains[0].carriage[0].range[0]",
     "[-180, 180]"),
    (lambda d: d["chains"][1]["legs"][0].update(length=[0, 10]), "chains[1].legs[0].length", "0 < l_min"),
    (lambda d: d["chains"][1]["legs"][1].update(length=[150, 150]), "chains[1].legs[1].length", "fixed-length"),
    (lambda d: d["chains"][2]["legs"][0].update(base=[1, 2]), "chains[2].legs[0].base", "three numbers"),
    (lambda d: d["chains"][2]["legs"][0].update(colour="red"), "chains[2].legs[0].colour", "unknown key"),
    (lambda d: d["chains"][2]["legs"][0].update(u_cone={"axis": [0, 0, 1], "angle": 120}),
     "chains[2].legs[0].u_cone.angle", "[0, 90]"),
    (lambda d: d["chains"][0]["carriage"].append(dict(d["chains"][0]["carriage"][0])), "chains[0].carriage",
     "at most one revolute"),
    (lambda d: d["chains"][0]["legs"][0]["base"].__setitem__(0, float("nan")), "chains[0].legs[0].base[0]",
     "a number"),
])
def test_every_refusal_names_its_field(edit, field: str, expected: str) -> None:
    data = paper().to_dict()
    # a fixed-length leg is refused only where no prismatic joint carries it: take chain 1's away
    data["chains"][1]["carriage"] = [c for c in data["chains"][1]["carriage"] if c["type"] == "revolute"]
    edit(data)
    with pytest.raises(ParameterError) as err:
        parse_mechanism(data)
    assert err.value.field == field
    assert expected in str(err.value)


def test_oversized_or_malformed_text_is_refused_by_name() -> None:
    with pytest.raises(ParameterError, match="at most 65,536 bytes"):
        loads_mechanism("#" * 70_000)
    with pytest.raises(ParameterError, match="valid TOML"):
        loads_mechanism("[[chains]\n")
    with pytest.raises(ParameterError, match="valid JSON"):
        loads_mechanism("{ nope")


def test_cones_restrict_the_brute_force() -> None:
    """A 5-degree U cone about z on every leg of the Gough-Stewart platform: only poses whose legs
    stand almost upright pass; with 89 degrees the cone changes nothing at a centred pose."""
    base = gough_stewart().to_dict()
    for chain in base["chains"]:
        for leg in chain["legs"]:
            leg["u_cone"] = {"axis": [0, 0, 1], "angle": 5.0}
    narrow = parse_mechanism(base)
    assert reachable_brute_force(gough_stewart(), (0, 0, 140), np.eye(3))
    assert not reachable_brute_force(narrow, (0, 0, 140), np.eye(3))
    for chain in base["chains"]:
        for leg in chain["legs"]:
            leg["u_cone"]["angle"] = 89.0
    assert reachable_brute_force(parse_mechanism(base), (0, 0, 140), np.eye(3))


def _cli(*args: str) -> subprocess.CompletedProcess:
    return run_cli("mechanism", *args)  # through main(), in this process (tests/cli_inprocess.py)


def test_cli_exports_a_preset_that_show_reads_back(tmp_path) -> None:
    out = tmp_path / "pups.toml"
    r = _cli("export", "6-pups", "--param", "lift=40", "-o", str(out))
    assert r.returncode == 0, r.stderr
    shown = _cli("show", str(out), "--json")
    assert shown.returncode == 0, shown.stderr
    assert parse_mechanism(json.loads(shown.stdout)) == six_pups(lift=40.0)


def test_cli_names_the_bad_field_of_a_file(tmp_path) -> None:
    data = gough_stewart().to_dict()
    data["chains"][4]["legs"][0]["length"] = [150.0, 120.0]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data))
    r = _cli("show", str(bad))
    assert r.returncode == 2 and r.stdout == ""
    assert "chains[4].legs[0].length" in r.stderr and "low <= high" in r.stderr and "Traceback" not in r.stderr
    r = _cli("show", "gough-stewart", "--param", "lift=3")
    assert r.returncode == 2 and "a parameter of preset 'gough-stewart'" in r.stderr
