"""Tests of kinematics.orientation: eq. (27) R', the symmetry-line regions and eq. (28)."""

from __future__ import annotations

import json
import math
import threading

import numpy as np
import pytest
from scipy.linalg import expm

from paraspace.kinematics import Cancelled, Design, ParameterError, reachable
from paraspace.kinematics.geometry import base_points, platform_points
from paraspace.kinematics.orientation import (
    LINES,
    ROTATIONS,
    OrientationRegion,
    OrientationResult,
    OrientationSettings,
    line_points,
    make_region,
    orientation_workspace,
    rotation_matrix,
    select_region,
    tilt_indices,
)
from paraspace.kinematics.rotation import Y_PRIME_AXIS, axis_angle, rot_x, rot_z

# Coarse sampling keeps the tests fast; the structure is the same as the default.
COARSE = OrientationSettings(angle_range=70.0, angle_step=2.0, position_step=3.0)


@pytest.fixture(scope="module")
def coarse_centered() -> OrientationResult:
    return orientation_workspace(Design(), COARSE)


@pytest.fixture(scope="module")
def coarse_from_zero() -> OrientationResult:
    return orientation_workspace(Design(eta_range="from-zero"), COARSE)


# ---------------------------------------------------------------------------------------------
# eq. (27)


def _skew(n: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])


@pytest.mark.parametrize("tau_deg", [-170.0, -45.0, -7.5, 0.0, 12.0, 60.0, 135.0])
def test_axis_angle_is_rotation_and_matches_expm(tau_deg: float) -> None:
    tau = math.radians(tau_deg)
    r = axis_angle(Y_PRIME_AXIS, tau)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(r) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(r, expm(tau * _skew(Y_PRIME_AXIS)), atol=1e-12)
    np.testing.assert_allclose(r @ Y_PRIME_AXIS, Y_PRIME_AXIS, atol=1e-12)  # the axis is fixed
    np.testing.assert_allclose(rotation_matrix("tau_yprime", tau_deg), r, atol=1e-15)


def _paper_eq27(n: np.ndarray, tau: float) -> np.ndarray:
    """Eq. (27) exactly as printed, reading the undefined ``s_x, s_y, s_z`` of the diagonal as
    ``theta'_x, theta'_y, theta'_z`` (the charitable reading: it makes the diagonal right)."""
    tx, ty, tz = n
    sx, sy, sz = n
    c, s = math.cos(tau), math.sin(tau)
    return np.array([
        [tx ** 2 + (1 - sx ** 2) * c, tx * ty * (1 - c) - tz * s, tx * tz * (1 - c) - ty * s],
        [tx * ty * (1 - c) + tz * s, ty ** 2 + (1 - sy ** 2) * c, ty * tz * (1 - c) + tx * s],
        [tx * tz * (1 - c) - ty * s, ty * tz * (1 - c) + tx * s, tz ** 2 + (1 - sz ** 2) * c],
    ])


def test_paper_eq27_as_printed_is_not_orthogonal() -> None:
    tau = math.radians(30.0)
    printed = _paper_eq27(Y_PRIME_AXIS, tau)
    assert np.abs(printed @ printed.T - np.eye(3)).max() > 0.1  # the typo: not a rotation
    # it differs from the corrected matrix exactly in the s(tau) terms of entries (1,3) and (2,3)
    diff = printed - axis_angle(Y_PRIME_AXIS, tau)
    mask = np.zeros((3, 3), bool)
    mask[0, 2] = mask[1, 2] = True
    np.testing.assert_allclose(diff[~mask], 0.0, atol=1e-12)
    np.testing.assert_allclose(diff[mask], [-2 * Y_PRIME_AXIS[1] * math.sin(tau), 2 * Y_PRIME_AXIS[0] * math.sin(tau)])


def test_rotation_keys() -> None:
    np.testing.assert_allclose(rotation_matrix("phi_z", 33.0), rot_z(math.radians(33.0)))
    np.testing.assert_allclose(rotation_matrix("psi_x", -21.0), rot_x(math.radians(-21.0)))
    with pytest.raises(ParameterError, match="rotation"):
        rotation_matrix("phi", 1.0)


@pytest.mark.parametrize("field,value", [("angle_step", 0.0), ("angle_range", 200.0), ("delta", "volume"),
                                         ("region", "some"), ("position_step", -1.0), ("z0", float("nan"))])
def test_settings_validation_names_field(field: str, value) -> None:
    with pytest.raises(ParameterError, match=field) as err:
        OrientationSettings(**{field: value})
    assert err.value.field == field


def test_lines_geometry() -> None:
    s = np.array([-2.0, 0.0, 4.0])
    np.testing.assert_allclose(line_points("x", s, 130.0), [[-2, 0, 130], [0, 0, 130], [4, 0, 130]])
    np.testing.assert_allclose(line_points("z", s), [[0, 0, -2], [0, 0, 0], [0, 0, 4]])
    yp = line_points("y_prime", s, 130.0)
    np.testing.assert_allclose(yp[:, :2], s[:, None] * Y_PRIME_AXIS[None, :2])
    np.testing.assert_allclose(yp[:, 2], 130.0)


# ---------------------------------------------------------------------------------------------
# regions against independent computations


def test_zero_angle_agrees_with_reachable(coarse_centered: OrientationResult) -> None:
    d = Design()
    for (line, rot), reg in coarse_centered.regions.items():
        zero = int(np.flatnonzero(reg.angles == 0.0)[0])
        pts = line_points(line, reg.positions, COARSE.z0)
        np.testing.assert_array_equal(reg.feasible[:, zero], reachable(d, pts, np.eye(3)), err_msg=f"{line}/{rot}")
        np.testing.assert_array_equal(reg.feasible[:, zero], reachable(d, pts, (0.0, 0.0, 0.0)))
    # the home pose is reachable on every line (the default design has z0 = 130 in the workspace)
    assert all(reg.feasible[:, reg.angles == 0.0].any() for reg in coarse_centered.regions.values())


def _brute_force_reachable(design: Design, position: np.ndarray, rotation: np.ndarray,
                           n_eta: int = 121, n_d: int = 401) -> bool:
    """Slow numpy test independent of the compiled kernel: sample (eta, d) of each chain finely,
    accept if some sample puts both legs of the chain inside [l_min, l_max]."""
    b = platform_points(design, position, rotation)  # (3, 2, 3)
    lo, hi = design.eta_limits
    frac = np.linspace(0.0, 1.0, n_d)
    ok = np.zeros(3, bool)
    for eta in np.linspace(lo, hi, n_eta):
        d0 = base_points(design, np.zeros(3), np.full(3, eta))  # D is affine in d
        d1 = base_points(design, np.full(3, design.d_s), np.full(3, eta))
        dd = d0[None] + frac[:, None, None, None] * (d1 - d0)[None]  # (n_d, 3, 2, 3)
        length = np.linalg.norm(b[None] - dd, axis=-1)  # (n_d, 3, 2)
        good = ((length >= design.l_min) & (length <= design.l_max)).all(axis=-1)  # (n_d, 3)
        ok |= good.any(axis=0)
        if ok.all():
            return True
    return bool(ok.all())


def _interior_samples(reg: OrientationRegion, margin: int, want: bool) -> np.ndarray:
    """Indices (k, m) whose whole (2 margin + 1)^2 neighbourhood has feasibility ``want``."""
    f = reg.feasible if want else ~reg.feasible
    nk, nm = f.shape
    acc = np.zeros_like(f)
    acc[margin:nk - margin, margin:nm - margin] = True
    for dk in range(-margin, margin + 1):
        for dm in range(-margin, margin + 1):
            acc[margin:nk - margin, margin:nm - margin] &= f[margin + dk:nk - margin + dk, margin + dm:nm - margin + dm]
    return np.argwhere(acc)


@pytest.mark.parametrize("convention", ["centered", "from-zero"])
def test_regions_agree_with_brute_force_away_from_boundary(convention, coarse_centered, coarse_from_zero) -> None:
    res = coarse_centered if convention == "centered" else coarse_from_zero
    design = Design(eta_range=convention)
    rng = np.random.default_rng(7)
    checked = 0
    for key in [("z", "phi_z"), ("z", "tau_yprime"), ("x", "psi_x"), ("y_prime", "phi_z"), ("x", "tau_yprime")]:
        reg = res.regions[key]
        for want in (True, False):
            idx = _interior_samples(reg, margin=2, want=want)  # >= 4 deg and >= 6 length inside
            assert len(idx) > 0, (key, want)
            for k, m in idx[rng.choice(len(idx), size=min(3, len(idx)), replace=False)]:
                pos = line_points(reg.line, reg.positions[k:k + 1], COARSE.z0)[0]
                rot = rotation_matrix(reg.rotation, reg.angles[m])
                assert _brute_force_reachable(design, pos, rot) is want, (key, reg.positions[k], reg.angles[m])
                checked += 1
    assert checked >= 25


def test_mirror_symmetry_centered(coarse_centered: OrientationResult) -> None:
    """With the centered arc range the mechanism is mirror-symmetric about the xz plane (and, by the
    3-fold symmetry, about the y'z plane): rotations about z, and about a line in the mirror, flip sign."""
    r = coarse_centered.regions
    for key in [("z", "phi_z"), ("x", "phi_z"), ("x", "psi_x"), ("y_prime", "phi_z"), ("y_prime", "tau_yprime")]:
        f = r[key].feasible
        assert np.array_equal(f, f[:, ::-1]), key
        np.testing.assert_allclose(r[key].angles, -r[key].angles[::-1])
    reg = r[("z", "phi_z")]
    assert reg.angle_interval[0] == pytest.approx(-reg.angle_interval[1])


@pytest.mark.parametrize("convention", ["centered", "from-zero"])
def test_three_fold_symmetry_maps_x_line_onto_y_prime_line(convention, coarse_centered, coarse_from_zero) -> None:
    """Rotating the mechanism by 240 deg (exact for both arc conventions) maps P = (s, 0, z0) to
    -s on the y' line and a rotation psi about x to a rotation -psi about y'."""
    r = (coarse_centered if convention == "centered" else coarse_from_zero).regions
    np.testing.assert_allclose(r[("x", "psi_x")].positions, -r[("y_prime", "tau_yprime")].positions[::-1])
    assert np.array_equal(r[("x", "psi_x")].feasible, r[("y_prime", "tau_yprime")].feasible[::-1, ::-1])
    assert np.array_equal(r[("x", "phi_z")].feasible, r[("y_prime", "phi_z")].feasible[::-1, :])


def test_larger_leg_stroke_never_shrinks_a_region() -> None:
    s = OrientationSettings(angle_range=60.0, angle_step=3.0, position_step=4.0, z_max=220.0, s_max=300.0)
    small = orientation_workspace(Design(l_s=30.0), s)
    large = orientation_workspace(Design(l_s=60.0), s)
    grew = False
    for key, reg in small.regions.items():
        big = large.regions[key]
        np.testing.assert_array_equal(reg.positions, big.positions)
        assert not (reg.feasible & ~big.feasible).any(), key
        grew |= bool((big.feasible & ~reg.feasible).any())
        assert big.area >= reg.area and big.delta_angle >= reg.delta_angle
    assert grew
    assert large.ti1 >= small.ti1 and large.ti2 >= small.ti2


# ---------------------------------------------------------------------------------------------
# the Δ definitions and eq. (28) on hand-built regions


def _rect_region(line: str, rot: str, k0: int, k1: int, m0: int, m1: int, hs: float = 2.0, ha: float = 1.0):
    pos = np.arange(-20, 21) * hs
    ang = np.arange(-30, 31) * ha
    f = np.zeros((pos.size, ang.size), bool)
    f[k0:k1 + 1, m0:m1 + 1] = True
    return make_region(line, rot, pos, ang, f, position_step=hs, angle_step=ha,
                       position_range=(-41.0, 41.0), angle_range=(-30.5, 30.5))


def test_rectangle_region_gives_product_of_sides() -> None:
    reg = _rect_region("x", "psi_x", 5, 14, 20, 49)  # 10 positions x 30 angles
    assert reg.delta_position == pytest.approx(10 * 2.0)
    assert reg.delta_angle == pytest.approx(30 * 1.0)
    assert reg.area == pytest.approx(reg.delta_position * reg.delta_angle)
    assert reg.angle_interval == pytest.approx((-10.5, 19.5))
    assert reg.position_interval == pytest.approx((-31.0, -11.0))


def test_cells_are_clipped_to_the_scanned_box() -> None:
    pos = np.arange(0, 5) * 1.0
    ang = np.arange(-4, 5) * 1.0
    reg = make_region("z", "phi_z", pos, ang, np.ones((5, 9), bool), position_step=1.0, angle_step=1.0,
                      position_range=(0.0, 4.0), angle_range=(-4.0, 4.0))
    assert reg.delta_angle == pytest.approx(8.0) and reg.delta_position == pytest.approx(4.0)
    assert reg.area == pytest.approx(32.0)
    empty = make_region("z", "phi_z", pos, ang, np.zeros((5, 9), bool), position_step=1.0, angle_step=1.0)
    assert (empty.delta_angle, empty.delta_position, empty.area) == (0.0, 0.0, 0.0)


def test_tilt_indices_from_hand_built_regions() -> None:
    sides = {}
    regions = {}
    rng = np.random.default_rng(3)
    for line in LINES:
        for rot in ROTATIONS:
            k0, m0 = int(rng.integers(0, 10)), int(rng.integers(0, 20))
            k1, m1 = k0 + int(rng.integers(0, 25)), m0 + int(rng.integers(0, 35))
            regions[(line, rot)] = _rect_region(line, rot, k0, k1, m0, m1)
            sides[(line, rot)] = ((k1 - k0 + 1) * 2.0, (m1 - m0 + 1) * 1.0)
    prod = {k: a * b for k, (a, b) in sides.items()}
    ti1_expect = (prod[("z", "phi_z")] + prod[("y_prime", "phi_z")] + prod[("x", "phi_z")]) / 3
    ti2_expect = sum(prod[(ln, r)] for ln in LINES for r in ("tau_yprime", "psi_x")) / 6
    for delta in ("extent", "area"):  # rectangles: both definitions agree
        ti1, ti2, deltas = tilt_indices(regions, delta)
        assert ti1 == pytest.approx(ti1_expect) and ti2 == pytest.approx(ti2_expect)
    assert deltas["Δφ_z"] == pytest.approx(sides[("z", "phi_z")][1])
    assert deltas["Δz(φ)"] == pytest.approx(sides[("z", "phi_z")][0])
    assert deltas["Δτ_y'"] == pytest.approx(sides[("y_prime", "tau_yprime")][1])
    assert deltas["Δx(ψ)"] == pytest.approx(sides[("x", "psi_x")][0])
    assert sum(1 for k in deltas if not k.startswith("P(")) == 18
    # position_delta="line": one Δ per line, the union of its three regions' position intervals
    _, _, dl = tilt_indices(regions, "extent", "line")
    for ln, sym in (("z", "z"), ("y_prime", "y'"), ("x", "x")):
        ints = [regions[(ln, r)].position_interval for r in ROTATIONS]
        span = max(i[1] for i in ints) - min(i[0] for i in ints)
        assert dl[f"Δ{sym}(φ)"] == dl[f"Δ{sym}(τ)"] == dl[f"Δ{sym}(ψ)"] == pytest.approx(span)


def test_extent_versus_area_on_an_l_shaped_region() -> None:
    pos = np.arange(0, 10) * 1.0
    ang = np.arange(-5, 6) * 1.0
    f = np.zeros((10, 11), bool)
    f[:, 5] = True  # a column at zero angle, 10 x 1
    f[0, :] = True  # a row at position 0, 1 x 11
    reg = make_region("z", "phi_z", pos, ang, f, position_step=1.0, angle_step=1.0)
    assert reg.delta_angle * reg.delta_position == pytest.approx(110.0)
    assert reg.area == pytest.approx(20.0)


def test_connected_region_drops_islands() -> None:
    ang = np.arange(-5, 6) * 1.0
    f = np.zeros((8, 11), bool)
    f[2:5, 4:7] = True  # contains angle 0 (column 5)
    f[6:8, 0:2] = True  # island away from zero rotation
    sel = select_region(f, ang, "connected")
    assert sel[2:5, 4:7].all() and not sel[6:8, 0:2].any()
    np.testing.assert_array_equal(select_region(f, ang, "all"), f)
    reg = make_region("x", "phi_z", np.arange(8.0), ang, f, position_step=1.0, angle_step=1.0, region="connected")
    assert reg.area == pytest.approx(9.0) and reg.delta_angle == pytest.approx(3.0)


# ---------------------------------------------------------------------------------------------
# API: serialization, progress, cancellation


def test_result_to_dict_is_json(coarse_centered: OrientationResult) -> None:
    data = coarse_centered.to_dict()
    text = json.dumps(data)
    assert "TI_1" in data and "TI_2" in data and len(data["regions"]) == 9
    assert data["deltas"]["Δφ_z"] == coarse_centered.regions[("z", "phi_z")].delta_angle
    full = json.loads(json.dumps(coarse_centered.to_dict(include_grids=True)))
    reg = full["regions"]["x/psi_x"]
    assert np.array_equal(np.array(reg["feasible"]), coarse_centered.regions[("x", "psi_x")].feasible)
    assert len(text) < len(json.dumps(full))
    assert coarse_centered.ti1 > 0 and coarse_centered.ti2 > 0


def test_progress_and_cancel() -> None:
    seen: list[float] = []
    orientation_workspace(Design(), OrientationSettings(angle_range=10, angle_step=5, position_step=10),
                          progress=lambda f, m: seen.append(f))
    assert seen and seen[-1] == pytest.approx(1.0) and all(b >= a - 1e-12 for a, b in zip(seen, seen[1:]))
    ev = threading.Event()
    ev.set()
    with pytest.raises(Cancelled):
        orientation_workspace(Design(), COARSE, cancel=ev)
    calls = []

    def cancel_later() -> bool:
        calls.append(1)
        return len(calls) > 3

    with pytest.raises(Cancelled):
        orientation_workspace(Design(), COARSE, cancel=cancel_later)


def test_oversized_grid_is_refused() -> None:
    with pytest.raises(ParameterError, match="position_step"):
        orientation_workspace(Design(), OrientationSettings(angle_step=0.01, position_step=0.01))


def test_saturation_note_names_the_rotations_lines_and_bounds():
    """Issue 21 item 5: the note names, per index, each rotation and line whose angle Δ spans the whole
    scan (checked against the regions' own Δα = 2A), and the scan's bounds."""
    from paraspace.kinematics.orientation import LINE_SYMBOL, LINES, ROTATION_SYMBOL

    for a in (10.0, 90.0):
        o = orientation_workspace(Design(), OrientationSettings(angle_range=a, angle_step=2.0, position_step=6.0))
        note = o.saturation_note()
        for rt in ("phi_z", "tau_yprime", "psi_x"):
            lines = [LINE_SYMBOL[ln] for ln in LINES if o.regions[(ln, rt)].delta_angle == pytest.approx(2 * a)]
            if lines:
                assert f"{ROTATION_SYMBOL[rt]} on the {', '.join(lines)} line" in note
            else:
                assert f"{ROTATION_SYMBOL[rt]} on the" not in note
        assert (f"-{a:g}° and {a:g}°" in note) == bool(note)
    assert "τ on the" in orientation_workspace(Design(), OrientationSettings(angle_range=10.0, angle_step=2.0,
                                                                             position_step=6.0)).saturation_note()
