"""Total-orientation workspace (issue 9): the intersection of constant-orientation workspaces over
a stated orientation sample set."""

from __future__ import annotations

import numpy as np
import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.dexterous import orientation_samples, total_orientation_workspace
from paraspace.kinematics.measures import measure_workspace
from paraspace.kinematics.rotation import euler_zyx_from_matrix
from paraspace.kinematics.tilt_torsion import tt_rotations
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

DESIGN = Design()


@pytest.fixture(scope="module")
def plain():
    return compute_workspace(DESIGN, WorkspaceSettings(voxel=8.0))


def run(tilt, torsion, step, plain):
    return total_orientation_workspace(DESIGN, tilt, torsion, step, WorkspaceSettings(voxel=8.0), position=plain)


def _key(rows):
    R = tt_rotations(rows[:, 0], rows[:, 1], rows[:, 2]).reshape(-1, 9)
    return {tuple(np.round(r, 9)) for r in R}


def test_zero_tilt_and_torsion_is_the_position_workspace(plain):
    r = total_orientation_workspace(DESIGN, 0.0, 0.0, 5.0, WorkspaceSettings(voxel=8.0))  # computes its own
    assert r.samples.shape == (1, 3)
    assert r.result.grid == plain.grid and np.array_equal(r.occupancy, plain.occupancy)


def test_is_the_intersection_of_constant_orientation_workspaces(plain):
    """The literal definition, computed by the workspace engine once per sampled orientation."""
    r = run(6.0, 6.0, 6.0, plain)
    lo, hi = plain.grid.lo, plain.grid.hi
    inter = plain.occupancy.copy()
    for R in tt_rotations(r.samples[:, 0], r.samples[:, 1], r.samples[:, 2]):
        psi, theta, phi = np.degrees(euler_zyx_from_matrix(R))
        w = compute_workspace(DESIGN, WorkspaceSettings(voxel=8.0, orientation=(psi, theta, phi), bounds=(lo, hi)))
        assert w.grid.shape == plain.grid.shape
        inter &= w.occupancy
    assert np.array_equal(r.occupancy, inter)
    assert 0 < r.voxels < plain.voxels


def test_subset_and_monotone_in_tilt_and_torsion(plain):
    prev = plain.occupancy
    prev_samples = None
    for tilt in (0.0, 8.0, 16.0, 32.0):  # step 4: the sample sets nest
        r = run(tilt, 0.0, 4.0, plain)
        if prev_samples is not None:
            assert _key(prev_samples) <= _key(r.samples)
        assert not np.any(r.occupancy & ~prev), tilt
        prev, prev_samples = r.occupancy, r.samples
    prev = plain.occupancy
    for torsion in (0.0, 8.0, 16.0):
        r = run(0.0, torsion, 4.0, plain)
        assert not np.any(r.occupancy & ~prev), torsion
        prev = r.occupancy
    assert r.voxels < plain.voxels


def test_denser_sampling_only_removes_voxels(plain):
    sparse = run(12.0, 10.0, 8.0, plain)
    dense = run(12.0, 10.0, 2.0, plain)
    assert _key(sparse.samples) < _key(dense.samples)
    assert not np.any(dense.occupancy & ~sparse.occupancy)
    assert not np.any(sparse.occupancy & ~plain.occupancy)


@pytest.mark.parametrize("tilt,torsion,step", [(15.0, 15.0, 5.0), (30.0, 7.0, 2.0), (3.0, 90.0, 10.0)])
def test_sample_set_spacing_is_as_stated(tilt, torsion, step):
    s = orientation_samples(tilt, torsion, step)
    assert s[:, 1].max() == pytest.approx(tilt) and s[:, 1].min() == 0.0
    assert s[:, 2].min() == pytest.approx(-torsion) and s[:, 2].max() == pytest.approx(torsion)
    assert np.any(np.all(s == 0.0, axis=1))  # the identity
    tors = np.unique(s[:, 2])
    assert np.all(np.diff(tors) <= step + 1e-9)
    rings = np.unique(s[:, 1])
    assert np.all(np.diff(rings) <= step + 1e-9)
    for th in rings[1:]:
        az = np.unique(s[s[:, 1] == th, 0])
        normals = tt_rotations(az, np.full_like(az, th), 0 * az)[:, :, 2]
        nxt = np.roll(normals, -1, axis=0)
        gaps = np.degrees(np.arccos(np.clip(np.sum(normals * nxt, axis=1), -1, 1)))
        assert np.all(gaps <= step + 1e-9)
        assert az.min() == 0.0 and len(az) >= 4


def test_result_has_workspace_measures(plain):
    r = run(10.0, 10.0, 5.0, plain)
    m = measure_workspace(r.result)
    assert m.volume == pytest.approx(r.volume) == pytest.approx(r.voxels * 8.0 ** 3)
    s = r.summary()
    assert s["position_volume"] == pytest.approx(plain.volume)
    assert s["orientations"] == len(r.samples) and 0 < s["fraction_of_position"] < 1


@pytest.mark.parametrize("kw,field", [({"tilt": 91.0}, "tilt"), ({"torsion": -1.0}, "torsion"),
                                      ({"step": 0.0}, "angle_step"), ({"tilt": "x"}, "tilt")])
def test_bad_input(kw, field):
    args = {"tilt": 10.0, "torsion": 10.0, "step": 5.0, **kw}
    with pytest.raises(ParameterError, match=field):
        orientation_samples(**args)


def test_nonzero_base_orientation_is_refused():
    with pytest.raises(ParameterError, match="orientation"):
        total_orientation_workspace(DESIGN, 5.0, 5.0, settings=WorkspaceSettings(voxel=8.0, orientation=(0, 5, 0)))


def cli(*args: str):
    from cli_inprocess import run_cli  # the command line through main(), in this process

    return run_cli(*args)


def test_cli_workspace_total_orientation_json(plain):
    import json

    proc = cli("workspace", "--voxel", "8", "--tilt", "10", "--torsion", "10", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    ref = run(10.0, 10.0, 5.0, plain)
    t = out["total_orientation"]
    assert t["volume"] == pytest.approx(ref.volume) and t["voxels"] == ref.voxels
    assert t["orientations"] == len(ref.samples) and t["tilt"] == 10.0 and t["torsion"] == 10.0
    assert t["measures"]["volume"] == pytest.approx(ref.volume)
    assert out["volume"] == pytest.approx(plain.volume)  # the position workspace stays the top level


@pytest.mark.parametrize("args,field,rng", [(("--tilt", "100"), "tilt", "[0, 90]"),
                                            (("--torsion", "-1"), "torsion", "[0, 180]"),
                                            (("--tilt", "5", "--angle-step", "0"), "angle_step", "[0.25, 30]"),
                                            (("--tilt", "nan"), "tilt", "[0, 90]")])
def test_cli_total_orientation_bad_input(args, field, rng):
    proc = cli("workspace", "--voxel", "8", *args, "--json")
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"paraspace: error: {field} = ") and rng in lines[0]


@pytest.mark.parametrize("design,tilt,torsion,step,first,top", [
    (DESIGN, 15.0, 15.0, 5.0, None, None),  # the 657 orientations, the defaults (hardest 32 / 8 first)
    (DESIGN, 15.0, 15.0, 5.0, 32, 8),  # the former hardest 32 leading the blocks, small top blocks
    (Design(a=30, b=20, eta_s=60), 20.0, 10.0, 5.0, 0, 4),  # the tree decides every sample; small top blocks
    (Design(a=60, b=10, d_s=70, l_s=70, eta_range="from-zero"), 10.0, 20.0, 5.0, 8, 2),
    (DESIGN, 10.0, 20.0, 3.0, None, None),  # 1,241 orientations: the top nodes' centres by the chordal mean
])
def test_tree_is_voxel_identical_to_testing_every_orientation(design, tilt, torsion, step, first, top, monkeypatch):
    """Issue 24 target 5: blocks of positions excluded by one orientation and voxels certified by
    groups of orientations (kinematics/orientation_blocks.py, the default), and the per-voxel tree
    (kinematics/orientation_tree.py), give the voxels of the exact per-pair test at every sample
    (method="pairs", the former path)."""
    from paraspace.kinematics import dexterous, orientation_blocks

    if first is not None:
        monkeypatch.setattr(dexterous, "FIRST", first)
        monkeypatch.setattr(dexterous, "FIRST_BLOCKS", first)
    if top is not None:
        monkeypatch.setattr(orientation_blocks, "TOP_BLOCK", top)
    ws = WorkspaceSettings(voxel=10.0)
    pos = compute_workspace(design, ws)
    blocks = total_orientation_workspace(design, tilt, torsion, step, ws, position=pos)
    tree = total_orientation_workspace(design, tilt, torsion, step, ws, position=pos, method="tree")
    pairs = total_orientation_workspace(design, tilt, torsion, step, ws, position=pos, method="pairs")
    assert blocks.samples.shape[0] > 100
    assert np.array_equal(blocks.occupancy, pairs.occupancy)
    assert np.array_equal(tree.occupancy, pairs.occupancy)
    assert 0 < blocks.voxels < pos.voxels


@pytest.mark.parametrize("shape,size", [((98, 98, 43), 64), ((178, 178, 84), 64), ((5, 7, 3), 2), ((65, 1, 130), 64),
                                        ((1, 1, 1), 64)])
def test_top_blocks_tile_the_grid_once_with_even_parts_in_x_and_y(shape, size):
    """The total-orientation blocks' top blocks (kinematics/orientation_blocks._even_top_blocks): every
    voxel in exactly one block, no edge above ``size``, x and y cut into ceil(n / size) parts that
    differ by at most one voxel, z cut as the engine cuts it (``size`` from the bottom)."""
    from paraspace.kinematics.orientation_blocks import _even_top_blocks

    b0, bn = _even_top_blocks(shape, size)
    cover = np.zeros(shape, int)
    for o, n in zip(b0, bn):
        cover[o[0]:o[0] + n[0], o[1]:o[1] + n[1], o[2]:o[2] + n[2]] += 1
    assert (cover == 1).all() and (bn >= 1).all() and (bn <= size).all()
    for k in (0, 1):
        widths = np.unique(bn[:, k])
        assert widths.max() - widths.min() <= 1 and len(np.unique(b0[:, k])) == -(-shape[k] // size)
    assert sorted(set(b0[:, 2].tolist())) == list(range(0, shape[2], size))


@pytest.mark.parametrize("tilt,torsion,step", [(15.0, 15.0, 5.0), (20.0, 0.0, 5.0), (0.0, 30.0, 10.0), (45.0, 60.0, 10.0)])
def test_sample_sets_are_closed_under_the_mirror(tilt, torsion, step):
    """(phi, theta, sigma) -> (-phi, theta, -sigma) maps the sample set onto itself (azimuths q 360 / 2^n,
    torsions symmetric about 0), which is what lets the blocks decide half the grid; a set turned by
    an azimuth offset, or cut to its first half, is not closed."""
    from paraspace.kinematics.orientation_blocks import mirror_closed
    from paraspace.kinematics.tilt_torsion import tt_rotations

    s = orientation_samples(tilt, torsion, step)
    assert mirror_closed(tt_rotations(s[:, 0], s[:, 1], s[:, 2]))
    if tilt > 0:
        assert not mirror_closed(tt_rotations(s[:, 0] + 3.0, s[:, 1], s[:, 2]))
    if torsion > 0:
        keep = s[:, 2] >= 0  # torsions >= 0 only: their mirrors are missing
        assert not mirror_closed(tt_rotations(s[keep, 0], s[keep, 1], s[keep, 2]))


def _grid_and_samples(design: Design) -> tuple:
    """The h = 8 workspace of ``design`` and the 15/10/5 orientation samples, their rotations and the
    arc samples: ``(settings, result, samples, rotations, n_eta)``."""
    from paraspace.kinematics.tilt_torsion import tt_rotations
    from paraspace.kinematics.workspace import default_n_eta

    ws = WorkspaceSettings(voxel=8.0)
    s = orientation_samples(15.0, 10.0, 5.0)
    return ws, compute_workspace(design, ws), s, tt_rotations(s[:, 0], s[:, 1], s[:, 2]), \
        default_n_eta(design, ws.eta_step)


@pytest.mark.parametrize("design", [DESIGN, Design(a=30, b=20, eta_s=60), Design(a=70, d_s=80, l_s=80)])
def test_the_mirrored_half_gives_the_voxels_of_the_whole_grid(design):
    """Issue 24 target 5: deciding the rows j >= ny // 2 and copying the others from their mirror
    rows gives the voxels of deciding every row (and of every orientation per pair); where the
    candidates are not symmetric the mirror is not used."""
    from paraspace.kinematics.orientation_blocks import reachable_on_grid

    ws, pos, s, rots, n_eta = _grid_and_samples(design)
    g = pos.grid
    occ = np.asarray(pos.occupancy, bool)
    assert np.array_equal(occ, occ[:, ::-1])
    half = reachable_on_grid(design, occ, g.axes(), g.h, s, rots, n_eta, 8, mirror=True)
    whole = reachable_on_grid(design, occ, g.axes(), g.h, s, rots, n_eta, 8, mirror=False)
    assert 0 < half.sum() < occ.sum() and np.array_equal(half, whole)
    pairs = total_orientation_workspace(design, 15.0, 10.0, 5.0, ws, position=pos, method="pairs")
    assert np.array_equal(half, pairs.occupancy)
    lopsided = occ.copy()
    lopsided[:, : occ.shape[1] // 2 - 1] = False  # no longer symmetric: every row is decided
    assert np.array_equal(reachable_on_grid(design, lopsided, g.axes(), g.h, s, rots, n_eta, 8, mirror=True),
                          whole & lopsided)


def test_launches_shrink_with_the_orientation_count_and_change_no_voxel(monkeypatch):
    """A kernel launch (between which a Stop is seen) holds about LAUNCH_WORK block-orientations: 16
    top blocks at the default 657 orientations, one per thread at the panel's largest sets (a Stop
    waited 15 s for 16 blocks of 352,557 orientations before). The launch size changes no voxel."""
    import numba

    from paraspace.kinematics import orientation_blocks as ob

    assert ob.launch_blocks(657, 2) == ob.LAUNCH == 16
    sizes = [ob.launch_blocks(n, 2) for n in (1, 657, 1_241, 5_000, 74_425, 352_557)]
    assert sizes == sorted(sizes, reverse=True) and sizes[-1] == 2 and ob.launch_blocks(352_557, 1) == 1
    assert all(ob.launch_blocks(n, 2) * n <= ob.LAUNCH_WORK for n in (1_241, 5_000))
    design = DESIGN
    ws, pos, s, rots, n_eta = _grid_and_samples(design)
    g = pos.grid
    occ = np.asarray(pos.occupancy, bool)
    monkeypatch.setattr(ob, "TOP_BLOCK", 8)  # many top blocks on this small grid
    steps: dict[int, list[float]] = {}
    out = {}
    for work in (ob.LAUNCH_WORK, rots.shape[0]):  # 16 blocks a launch, then one per thread
        monkeypatch.setattr(ob, "LAUNCH_WORK", work)
        steps[work] = []
        out[work] = ob.reachable_on_grid(design, occ, g.axes(), g.h, s, rots, n_eta, 8,
                                         progress=lambda f, m, k=work: steps[k].append(f))
    few, many = steps[ob.LAUNCH * 657], steps[rots.shape[0]]
    per = ob.launch_blocks(rots.shape[0], numba.get_num_threads())
    n_top = round(per / many[0])  # one progress report per launch, at the blocks done so far
    assert per < 16 < n_top and many[-1] == few[-1] == 1.0
    assert len(many) == -(-n_top // per) and len(few) == -(-n_top // 16)
    assert np.array_equal(out[ob.LAUNCH * 657], out[rots.shape[0]]) and out[rots.shape[0]].any()


def test_unknown_method_is_refused(plain):
    with pytest.raises(ParameterError, match="method"):
        total_orientation_workspace(DESIGN, 5.0, 5.0, 5.0, WorkspaceSettings(voxel=8.0), position=plain,
                                    method="fast")


def test_orientation_tree_build_in_steps_is_the_same_tree_and_honours_a_stop(monkeypatch):
    """The tree's build runs in steps of bounded work with the cancel token checked between them
    (kinematics/orientation_tree._build): cut into steps of any size it is the same tree, node for
    node, as built in one step; and a Stop pressed during the build ends it at the next step, here
    after exactly as many steps as the token allowed, not at the end of the build."""
    from paraspace.kinematics import orientation_tree as ot
    from paraspace.kinematics.progress import Cancelled

    samples = orientation_samples(10.0, 20.0, 3.0)  # 1,241: both centre rules, several hundred nodes
    rots = tt_rotations(samples[:, 0], samples[:, 1], samples[:, 2])
    az, th = np.radians(samples[:, 0]), samples[:, 1]
    coords = np.ascontiguousarray(np.stack([th * np.cos(az), th * np.sin(az), samples[:, 2]], axis=1))
    flat = np.ascontiguousarray(rots.reshape(-1, 9))
    whole = ot._build(coords, flat, None, 1 << 62)
    assert whole[0].size == 2 * samples.shape[0] - 1
    for work in (1, 5_000, 300_000, ot.BUILD_WORK):
        steps = []
        tree = ot._build(coords, flat, lambda steps=steps: steps.append(1) and False, work)
        assert all(np.array_equal(a, b) for a, b in zip(tree, whole)), work
        if work == 1:  # one node a step: a step per node
            assert len(steps) == whole[0].size
    calls = []

    def stop_after_three() -> bool:
        calls.append(1)
        return len(calls) > 3

    monkeypatch.setattr(ot, "BUILD_WORK", 5_000)  # steps small enough that this set takes many
    with pytest.raises(Cancelled):
        ot.build_tree(samples, rots, 0, stop_after_three)
    assert len(calls) == 4  # three steps ran, the fourth check stopped the build


@pytest.mark.parametrize("tilt,torsion,step", [(15.0, 15.0, 5.0), (20.0, 10.0, 5.0), (10.0, 20.0, 5.0),
                                                (10.0, 20.0, 3.0)])  # 1,241: the root's centre by the mean
def test_orientation_tree_groups_and_slack(tilt, torsion, step):
    """The compiled tree build (kinematics/orientation_tree.py): each inner node's members are its two
    children's, disjoint, split into halves; leaves are single samples; the centre is a member whose
    largest angle to the others is the smallest (checked against every angle), in a node of more than
    CENTRE_EXACT members the member nearest their chordal mean; and the vectorized
    slack is, node by node and chain by chain, the largest |R u - R0 u| over the members (the same
    value as the former per-node expression)."""
    from paraspace.kinematics.joints import Joints
    from paraspace.kinematics.orientation_tree import CENTRE_EXACT, build_tree, node_slack
    from paraspace.kinematics.workspace import rotation_tables

    samples = orientation_samples(tilt, torsion, step)
    rots = tt_rotations(samples[:, 0], samples[:, 1], samples[:, 2])
    left, right, leaf, centre, perm, lo, hi = build_tree(samples, rots)
    members = [perm[a:b] for a, b in zip(lo, hi)]
    assert left.size == 2 * samples.shape[0] - 1 and set(members[0].tolist()) == set(range(samples.shape[0]))
    assert sorted(leaf[leaf >= 0].tolist()) == list(range(samples.shape[0]))
    for k in range(left.size):
        mem = members[k]
        assert centre[k] in mem
        if leaf[k] >= 0:
            assert left[k] == right[k] == -1 and mem.tolist() == [leaf[k]]
            continue
        a, b = members[left[k]], members[right[k]]
        assert sorted(np.concatenate([a, b]).tolist()) == sorted(mem.tolist()) and abs(a.size - b.size) <= 1
        assert a.min() < b.min()  # children in sample order (hardest first)
        if mem.size > CENTRE_EXACT:  # the member nearest the chordal mean (one pass)
            near = np.einsum("aij,ij->a", rots[mem], rots[mem].mean(axis=0))
            assert near[list(mem).index(centre[k])] >= near.max() - 1e-9
            continue
        tr = np.einsum("aij,bij->ab", rots[mem], rots[mem])
        worst = np.arccos(np.clip(0.5 * (tr - 1.0), -1.0, 1.0)).max(axis=0)
        assert worst[list(mem).index(centre[k])] <= worst.min() + 1e-9
    us, _ = rotation_tables(DESIGN, rots, Joints())
    slack = node_slack(us, perm, lo, hi, centre)
    for k in range(left.size):
        for i in range(3):
            assert slack[k, i] == np.linalg.norm(us[members[k], i] - us[centre[k], i], axis=-1).max()  # former
    # numbered as the whole set when the tree leaves out the first samples
    left8, right8, leaf8, centre8, perm8, lo8, hi8 = build_tree(samples, rots, 8)
    ref = build_tree(samples[8:], rots[8:])
    assert np.array_equal(left8, ref[0]) and np.array_equal(perm8, ref[4] + 8) and np.array_equal(centre8, ref[3] + 8)
    assert np.array_equal(leaf8, np.where(ref[2] >= 0, ref[2] + 8, -1)) and np.array_equal(lo8, ref[5])
