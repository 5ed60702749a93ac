"""The certified volume bracket (kinematics.bracket) against independent computations: the voxel
estimates at h and h/2 lie inside it, random points of "inside" cubes are reachable by the plain
numpy brute force, and random points of "outside" cubes are unreachable for it even with a 20x
finer arc sampling."""

from __future__ import annotations

import re

import numpy as np
import pytest

from paraspace.kinematics.bracket import BOUNDARY, INSIDE, OUTSIDE, _half, cube_classes
from paraspace.kinematics.design import Design
from paraspace.kinematics.kernel_args import kernel_args
from paraspace.kinematics.reference import reference_reachable
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


@pytest.mark.parametrize("design", [Design(), Design(a=10), Design(eta_range="from-zero", l_s=80)])
def test_bracket_contains_the_estimates_and_shrinks(design):
    coarse = compute_workspace(design, WorkspaceSettings(voxel=6.0, bracket=True))
    fine = compute_workspace(design, WorkspaceSettings(voxel=3.0, bracket=True))
    for r in (coarse, fine):
        assert r.volume_inner <= r.volume <= r.volume_outer
    # the finer bracket is narrower and both contain the finer estimate
    assert fine.volume_outer - fine.volume_inner < coarse.volume_outer - coarse.volume_inner
    assert coarse.volume_inner <= fine.volume <= coarse.volume_outer


@pytest.mark.parametrize("symmetric", [False, True])
def test_cube_classes_against_the_brute_force(symmetric):
    """Every class checked by the brute force, on all cubes; with ``symmetric`` the cubes with y > 0 take
    their mirror image's class (module doc, *Mirror*), which the brute force checks on its own."""
    design = Design()
    res = compute_workspace(design, WorkspaceSettings(voxel=8.0))
    grid = res.grid
    assert _half(grid, True)  # an exactly symmetric grid: the mirror is used
    cls = cube_classes(design, grid, kernel_args(design, (0.0, 0.0, 0.0), res.n_eta), res.n_eta, 0.0,
                       symmetric=symmetric)
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
    near = near[rng.choice(len(near), size=min(400, len(near)), replace=False)]  # 400 of about 1360
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
    from paraspace.app.api.workspace import workspace_payload as _workspace_payload

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
        text = re.sub(r"<[^>]+>", "", s.panels.numbers.content)  # the names' hover-text markup
        assert "certified:" in text and "continuous workspace" in text
        b.close()
    finally:
        exp.stop()


# ---------------------------------------------------------------------------------------------
# an independent interval oracle: codac (test-only dependency), run in its own process because
# importing it changes the process's floating-point rounding mode (interval arithmetic rounds
# outward), which would change every later float parse and sum in the test session


@pytest.fixture(scope="module")
def codac_verdicts() -> tuple:
    """The h = 16 workspace and codac's verdict per cube of a quarter of its grid (y >= 0): ``(res,
    quarter, verdicts)``. The oracle sees the cubes alone, so one run serves both tests below."""
    import importlib.util
    import json
    import pathlib
    import subprocess
    import sys

    if importlib.util.find_spec("codac") is None:  # never import it here (see above)
        pytest.skip("codac is not installed")
    design = Design()
    res = compute_workspace(design, WorkspaceSettings(voxel=16.0))
    grid = res.grid
    centres = grid.points()
    quarter = np.argwhere((centres[..., 0] >= 0) & (centres[..., 1] >= 0))
    cubes = []
    for ix, iy, iz in quarter:
        c = centres[ix, iy, iz]
        cube = [[float(c[k] - grid.h / 2), float(c[k] + grid.h / 2)] for k in range(3)]
        cube[2][0] = max(cube[2][0], 0.0)  # the grid's floor: only z >= 0 belongs to the workspace
        cubes.append(cube)
    job = {"design": design.to_dict(), "cubes": cubes}
    oracle = pathlib.Path(__file__).with_name("codac_oracle.py")
    out = subprocess.run([sys.executable, str(oracle)], input=json.dumps(job), capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr
    verdicts = json.loads(out.stdout)  # per cube: "in", "out" or "?"
    assert len(verdicts) == len(cubes)
    return res, quarter, verdicts


@pytest.mark.slow
@pytest.mark.parametrize("symmetric", [False, True])
def test_bracket_agrees_with_an_independent_interval_oracle(symmetric, codac_verdicts):
    """codac's interval arithmetic classifies the same cubes (a quarter of the h = 16 grid) on its own:
    no cube is proven inside by one tool and outside by the other, codac confirms most of our
    decided cubes, and the two certified brackets of that region overlap (both enclose the truth).
    The quarter has y >= 0: with ``symmetric`` its cubes off the middle row take their mirror image's
    class."""
    res, quarter, verdicts = codac_verdicts
    design, grid = res.design, res.grid
    centres = grid.points()
    cls = cube_classes(design, grid, kernel_args(design, (0.0, 0.0, 0.0), res.n_eta), res.n_eta, 0.0,
                       symmetric=symmetric)
    ours = {INSIDE: 0, OUTSIDE: 0, BOUNDARY: 0}
    agree = {INSIDE: 0, OUTSIDE: 0}
    for (ix, iy, iz), v in zip(quarter, verdicts):
        k = int(cls[ix, iy, iz])
        ours[k] += 1
        assert not (k == INSIDE and v == "out"), centres[ix, iy, iz]
        assert not (k == OUTSIDE and v == "in"), centres[ix, iy, iz]
        if k == INSIDE:
            agree[INSIDE] += v == "in"
        elif k == OUTSIDE:
            agree[OUTSIDE] += v == "out"
    assert agree[INSIDE] >= 0.7 * ours[INSIDE] and agree[OUTSIDE] >= 0.9 * ours[OUTSIDE]
    v = grid.h ** 3
    c_in, c_out = verdicts.count("in"), verdicts.count("out")
    ours_bracket = (ours[INSIDE] * v, (ours[INSIDE] + ours[BOUNDARY]) * v)
    oracle_bracket = (c_in * v, (len(quarter) - c_out) * v)
    assert max(ours_bracket[0], oracle_bracket[0]) <= min(ours_bracket[1], oracle_bracket[1])


def test_the_bracket_progress_names_its_levels():
    """The bracket's progress says which stage and level it is at, out of how many, in the general
    engine's words ("certified bracket: ..."): the cube levels
    (at most the engine's), then each refinement ``k of refine``; the fraction never goes back."""
    from paraspace.kinematics.bracket import bracket_of

    res = compute_workspace(Design(), WorkspaceSettings(voxel=8.0))
    seen: list[tuple[float, str]] = []
    bracket_of(res, progress=lambda f, m: seen.append((f, m)), refine=3)
    cubes = [re.fullmatch(r"certified bracket: classifying the cubes, level (\d+) \(of at most (\d+)\)", m)
             for _, m in seen]
    levels = [int(c.group(1)) for c in cubes if c]
    assert levels == list(range(1, len(levels) + 1)) and len(levels) >= 3
    assert all(int(c.group(2)) >= len(levels) for c in cubes if c)
    assert [m for _, m in seen if "refining" in m] == [
        f"certified bracket: refining the boundary, level {k} of 3" for k in (1, 2, 3)]
    fracs = [f for f, _ in seen]
    assert fracs == sorted(fracs) and fracs[-1] == 1.0
