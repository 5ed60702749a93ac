"""The certified volume bracket (kinematics.bracket) against independent computations: the voxel
estimates at h and h/2 lie inside it, random points of "inside" cubes are reachable by the plain
numpy brute force, and random points of "outside" cubes are unreachable for it even with a 20x
finer arc sampling."""

from __future__ import annotations

import numpy as np
import pytest

from paraspace.kinematics.bracket import BOUNDARY, INSIDE, OUTSIDE, cube_classes
from paraspace.kinematics.design import Design
from paraspace.kinematics.reference import reference_reachable
from paraspace.kinematics.workspace import WorkspaceSettings, _kernel_args, compute_workspace


@pytest.mark.parametrize("design", [Design(), Design(a=10), Design(eta_range="from-zero", l_s=80)])
def test_bracket_contains_the_estimates_and_shrinks(design):
    coarse = compute_workspace(design, WorkspaceSettings(voxel=6.0, bracket=True))
    fine = compute_workspace(design, WorkspaceSettings(voxel=3.0, bracket=True))
    for r in (coarse, fine):
        assert r.volume_inner <= r.volume <= r.volume_outer
    # the finer bracket is narrower and both contain the finer estimate
    assert fine.volume_outer - fine.volume_inner < coarse.volume_outer - coarse.volume_inner
    assert coarse.volume_inner <= fine.volume <= coarse.volume_outer


def test_cube_classes_against_the_brute_force():
    design = Design()
    res = compute_workspace(design, WorkspaceSettings(voxel=8.0))
    grid = res.grid
    cls = cube_classes(design, grid, _kernel_args(design, (0.0, 0.0, 0.0), res.n_eta), res.n_eta, 0.0)
    assert {INSIDE, OUTSIDE, BOUNDARY} <= set(np.unique(cls).tolist())
    rng = np.random.default_rng(3)
    centres = grid.points()

    def sample(which: int, n_cubes: int = 60, per: int = 6) -> np.ndarray:
        idx = np.argwhere(cls == which)
        pick = idx[rng.choice(len(idx), size=min(n_cubes, len(idx)), replace=False)]
        c = centres[pick[:, 0], pick[:, 1], pick[:, 2]]
        off = rng.uniform(-0.5, 0.5, size=(len(c), per, 3)) * grid.h
        return (c[:, None, :] + off).reshape(-1, 3)

    inside = sample(INSIDE)
    assert reference_reachable(design, inside).all()
    outside = sample(OUTSIDE)
    # outside cubes near the boundary are the informative ones: take those next to a non-outside cube
    assert not reference_reachable(design, outside, eta_step=0.025).any()
    near = np.argwhere((cls == OUTSIDE) & (np.roll(cls, 1, axis=2) != OUTSIDE))
    c = centres[near[:, 0], near[:, 1], near[:, 2]]
    pts = (c[:, None, :] + rng.uniform(-0.5, 0.5, size=(len(c), 4, 3)) * grid.h).reshape(-1, 3)
    assert not reference_reachable(design, pts, eta_step=0.025).any()


def test_cli_and_api_report_the_bracket():
    import json
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "paraspace.app.cli", "workspace", "--voxel", "8", "--bracket", "--json"],
                         capture_output=True, text=True, timeout=300, check=True)
    doc = json.loads(out.stdout)
    assert doc["volume_inner"] <= doc["volume"] <= doc["volume_outer"]
    from paraspace.app.api import _workspace_payload

    r = compute_workspace(Design(), WorkspaceSettings(voxel=8.0, bracket=True))
    payload = _workspace_payload(r)
    assert payload["volume_inner"] == r.volume_inner and payload["volume_outer"] == r.volume_outer


def test_explorer_shows_the_certified_bracket():
    from explorer_client import FakeBrowser, wait_idle  # tests/ (pytest's prepend import mode)

    from paraspace.app.explorer import Explorer

    exp = Explorer("127.0.0.1", 0).start()
    try:
        b = FakeBrowser(exp, "voxel=6")
        s = b.session
        wait_idle(exp, s)
        br = s.bundle.bracket
        assert br is not None and br.volume_inner <= s.bundle.result.volume <= br.volume_outer
        text = s.panels.numbers.content
        assert "certified:" in text and "continuous workspace" in text
        b.close()
    finally:
        exp.stop()


# ---------------------------------------------------------------------------------------------
# an independent interval oracle: codac (test-only dependency)

def _codac_legs(design, chain):
    """codac functions L_j(x, y, z, varpi, rho) of the two legs of ``chain`` at zero orientation."""
    codac = pytest.importorskip("codac")
    from paraspace.kinematics.geometry import LEG_SIGN, platform_points_local

    u = platform_points_local(design)[chain]
    v = codac.VectorVar(5)
    out = []
    for j in range(2):
        lat = LEG_SIGN[j] * design.b / 2.0
        dx = v[4] * codac.cos(v[3]) - lat * codac.sin(v[3])
        dy = v[4] * codac.sin(v[3]) + lat * codac.cos(v[3])
        expr = codac.sqrt(codac.sqr(v[0] + float(u[j, 0]) - dx) + codac.sqr(v[1] + float(u[j, 1]) - dy)
                          + codac.sqr(v[2] + float(u[j, 2])))
        out.append(codac.AnalyticFunction([v], expr))
    return out


def _codac_chain(codac, legs, cube, varpi, rho, lmin, lmax, samples, depth=9):
    """'in' when an arc sample and a rail value keep both legs in [lmin, lmax] over the whole cube
    (interval evaluation), 'out' when a bisection of the carriage box (varpi x rho) proves that no
    carriage pose serves any point of the cube, '?' otherwise."""
    for w in samples:
        for r in np.linspace(rho[0], rho[1], 5):
            box = codac.IntervalVector([*cube, [w, w], [r, r]])
            if all(lmin <= f.eval(box).lb() and f.eval(box).ub() <= lmax for f in legs):
                return "in"
    stack = [(varpi, rho, 0)]
    while stack:
        (w0, w1), (r0, r1), d = stack.pop()
        box = codac.IntervalVector([*cube, [w0, w1], [r0, r1]])
        if any(f.eval(box).ub() < lmin or f.eval(box).lb() > lmax for f in legs):
            continue
        if d >= depth:
            return "?"
        if (w1 - w0) * 150.0 > (r1 - r0):  # split the longer side (angles weighted by a lever of 150)
            m = 0.5 * (w0 + w1)
            stack += [((w0, m), (r0, r1), d + 1), ((m, w1), (r0, r1), d + 1)]
        else:
            m = 0.5 * (r0 + r1)
            stack += [((w0, w1), (r0, m), d + 1), ((w0, w1), (m, r1), d + 1)]
    return "out"


@pytest.mark.slow
def test_bracket_agrees_with_an_independent_interval_oracle():
    """codac's interval arithmetic classifies the same cubes (a quarter of the h = 16 grid) on its own:
    no cube is proven inside by one tool and outside by the other, codac confirms most of our
    decided cubes, and the two certified brackets of that region overlap (both enclose the truth)."""
    codac = pytest.importorskip("codac")
    from paraspace.kinematics.geometry import GAMMA

    design = Design()
    res = compute_workspace(design, WorkspaceSettings(voxel=16.0))
    grid = res.grid
    args = _kernel_args(design, (0.0, 0.0, 0.0), res.n_eta)
    cls = cube_classes(design, grid, args, res.n_eta, 0.0)
    centres = grid.points()
    lo, hi = np.radians(design.eta_limits)
    quarter = np.argwhere((centres[..., 0] >= 0) & (centres[..., 1] >= 0))
    legs = [_codac_legs(design, i) for i in range(3)]
    ours = {INSIDE: 0, OUTSIDE: 0, BOUNDARY: 0}
    agree = {INSIDE: 0, OUTSIDE: 0}
    c_in = c_out = 0
    for ix, iy, iz in quarter:
        c = centres[ix, iy, iz]
        cube = [[c[k] - grid.h / 2, c[k] + grid.h / 2] for k in range(3)]
        if cube[2][0] < 0.0:
            cube[2][0] = 0.0  # the grid's floor: only z >= 0 belongs to the workspace
        verdicts = []
        for i in range(3):
            varpi = (GAMMA[i] + lo, GAMMA[i] + hi)
            samples = np.linspace(varpi[0], varpi[1], 7)
            v = _codac_chain(codac, legs[i], cube, varpi, design.rho_limits, design.l_min, design.l_max, samples)
            verdicts.append(v)
            if v == "out":
                break
        k = cls[ix, iy, iz]
        ours[k] += 1
        oracle_in = all(v == "in" for v in verdicts) and len(verdicts) == 3
        oracle_out = "out" in verdicts
        c_in += oracle_in
        c_out += oracle_out
        assert not (k == INSIDE and oracle_out), c
        assert not (k == OUTSIDE and oracle_in), c
        if k in agree:
            agree[k] += (oracle_in if k == INSIDE else oracle_out)
    print("ours", ours, "codac agrees", agree, "codac in/out", c_in, c_out, "of", len(quarter))
    assert agree[INSIDE] >= 0.7 * ours[INSIDE] and agree[OUTSIDE] >= 0.9 * ours[OUTSIDE]
    v = grid.h ** 3
    ours_bracket = (ours[INSIDE] * v, (ours[INSIDE] + ours[BOUNDARY]) * v)
    oracle_bracket = (c_in * v, (len(quarter) - c_out) * v)
    assert max(ours_bracket[0], oracle_bracket[0]) <= min(ours_bracket[1], oracle_bracket[1])
