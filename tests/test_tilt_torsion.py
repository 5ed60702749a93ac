"""Tilt-and-torsion angles and the T&T report at a point (issue 9), against dense angle scans."""

from __future__ import annotations

import numpy as np
import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.redundancy import resolve_redundancy
from paraspace.kinematics.rotation import euler_zyx_from_matrix
from paraspace.kinematics.tilt_torsion import TiltTorsionSettings, tilt_torsion_at, tt_angles, tt_rotation, tt_rotations
from paraspace.kinematics.workspace import reachable_pairs

DESIGN = Design()
DENSE = 0.05  # degrees


def rz(a):
    a = np.radians(a)
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1.0]])


def ry(a):
    a = np.radians(a)
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1.0, 0], [-np.sin(a), 0, np.cos(a)]])


def test_tt_rotation_is_the_product_and_inverts():
    rng = np.random.default_rng(0)
    for _ in range(50):
        phi, theta, sigma = rng.uniform(-179, 179), rng.uniform(0.5, 170), rng.uniform(-179, 179)
        R = tt_rotation(phi, theta, sigma)
        np.testing.assert_allclose(R, rz(phi) @ ry(theta) @ rz(-phi) @ rz(sigma), atol=1e-12)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(R[:, 2], [np.cos(np.radians(phi)) * np.sin(np.radians(theta)),
                                             np.sin(np.radians(phi)) * np.sin(np.radians(theta)),
                                             np.cos(np.radians(theta))], atol=1e-12)
        np.testing.assert_allclose(tt_angles(R), (phi, theta, sigma), atol=1e-9)
    np.testing.assert_allclose(tt_rotation(33.0, 0.0, 20.0), rz(20.0), atol=1e-12)
    # zero torsion is torsion-free: tilting about the horizontal axis perpendicular to the azimuth
    axis = np.array([-np.sin(np.radians(40.0)), np.cos(np.radians(40.0)), 0.0])
    R = tt_rotation(40.0, 25.0, 0.0)
    np.testing.assert_allclose(R @ axis, axis, atol=1e-12)
    batch = tt_rotations(np.array([10.0, 20.0]), np.array([5.0, 6.0]), np.array([1.0, 2.0]))
    np.testing.assert_allclose(batch[1], tt_rotation(20.0, 6.0, 2.0))


def dense_extent(design, p, rots_of_t, limit):
    """Last reachable angle of a dense scan from 0 before the first unreachable one (None if 0 fails)."""
    ts = np.arange(0.0, limit + 1e-9, DENSE)
    ok = reachable_pairs(design, np.asarray(p, float)[None, :], rots_of_t(ts))[0]
    if not ok[0]:
        return None
    bad = np.flatnonzero(~ok)
    return float(limit) if bad.size == 0 else float(ts[bad[0] - 1])


@pytest.mark.parametrize("design,pos", [(DESIGN, (0.0, 0.0, 130.0)), (DESIGN, (20.0, 10.0, 120.0)),
                                        (DESIGN, (0.0, -15.0, 155.0)), (Design(a=30, eta_s=60), (5.0, 5.0, 140.0))])
def test_max_tilt_and_torsion_match_a_dense_scan(design, pos):
    s = TiltTorsionSettings(azimuth_step=30.0)
    rep = tilt_torsion_at(design, pos, s)
    assert rep.reachable
    tol = s.tolerance + DENSE + 1e-9
    for phi, tmax in zip(rep.azimuths, rep.max_tilt):
        ref = dense_extent(design, pos, lambda ts: tt_rotations(np.full_like(ts, phi), ts, 0 * ts), 90.0)
        assert tmax is not None and abs(tmax - ref) <= tol, (phi, tmax, ref)
    lo = dense_extent(design, pos, lambda ts: tt_rotations(0 * ts, 0 * ts, -ts), 180.0)
    hi = dense_extent(design, pos, lambda ts: tt_rotations(0 * ts, 0 * ts, ts), 180.0)
    assert abs(-rep.torsion_min - lo) <= tol and abs(rep.torsion_max - hi) <= tol
    assert rep.min_max_tilt == min(rep.max_tilt)


def test_reported_extents_bracket_the_boundary():
    pos = np.array([20.0, 10.0, 120.0])
    s = TiltTorsionSettings(azimuth_step=45.0)
    rep = tilt_torsion_at(DESIGN, pos, s)
    for phi, tmax, sat in zip(rep.azimuths, rep.max_tilt, rep.tilt_saturated):
        assert reachable_pairs(DESIGN, pos[None], tt_rotation(phi, tmax, 0.0)[None])[0, 0]
        if not sat:
            assert not reachable_pairs(DESIGN, pos[None], tt_rotation(phi, tmax + s.tolerance, 0.0)[None])[0, 0]
    for t, inside in ((rep.torsion_max, True), (rep.torsion_max + s.tolerance, False),
                      (rep.torsion_min, True), (rep.torsion_min - s.tolerance, False)):
        assert reachable_pairs(DESIGN, pos[None], tt_rotation(0.0, 0.0, t)[None])[0, 0] == inside


def test_extents_agree_with_the_continuous_resolver():
    """An independent algorithm (the redundancy resolver searches eta continuously): well inside
    the reported tilt the pose is feasible, well beyond it it is not."""
    pos = (20.0, 10.0, 120.0)
    rep = tilt_torsion_at(DESIGN, pos, TiltTorsionSettings(azimuth_step=60.0))
    for phi, tmax in zip(rep.azimuths, rep.max_tilt):
        for t, expect in ((tmax - 0.5, True), (tmax + 0.5, False)):
            psi, theta, ph = np.degrees(euler_zyx_from_matrix(tt_rotation(phi, t, 0.0)))
            assert resolve_redundancy(DESIGN, Pose(*pos, psi, theta, ph)).feasible == expect, (phi, t)


def test_unreachable_position():
    rep = tilt_torsion_at(DESIGN, (0.0, 0.0, 400.0), TiltTorsionSettings(azimuth_step=90.0))
    d = rep.to_dict()
    assert not d["reachable"] and d["max_tilt"] == [None] * 4 and d["torsion_range"] == [None, None]
    assert d["min_max_tilt"] is None


@pytest.mark.parametrize("field,value", [("azimuth_step", 0.0), ("coarse_step", -1.0), ("tolerance", 5.0),
                                         ("tilt_limit", 200.0), ("torsion_limit", "x")])
def test_settings_are_validated(field, value):
    with pytest.raises(ParameterError, match=field):
        TiltTorsionSettings(**{field: value})


def cli(*args: str):
    from cli_inprocess import run_cli  # the command line through main(), in this process

    return run_cli(*args)


def test_cli_orientation_at_json():
    import json

    proc = cli("orientation", "--at", "20,10,120", "--azimuth-step", "30", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    ref = tilt_torsion_at(DESIGN, (20.0, 10.0, 120.0), TiltTorsionSettings(azimuth_step=30.0)).to_dict()
    assert out["max_tilt"] == pytest.approx(ref["max_tilt"]) and out["azimuths"] == ref["azimuths"]
    assert out["torsion_range"] == pytest.approx(ref["torsion_range"])
    assert out["min_max_tilt"] == pytest.approx(min(ref["max_tilt"])) and out["reachable"]


@pytest.mark.parametrize("args,field", [(("--at", "1,2"), "at"), (("--at", "1,2,x"), "at"),
                                        (("--at", "0,0,130", "--azimuth-step", "0"), "azimuth_step")])
def test_cli_orientation_at_bad_input(args, field):
    proc = cli("orientation", *args, "--json")
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"paraspace: error: {field} = ")
