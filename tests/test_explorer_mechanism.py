"""The explorer's mechanism selector (issue 19), driven over the real websocket (tests/explorer_client.py).

Each volume the explorer shows is compared with ``compute_mechanism_workspace`` called directly on
the same mechanism and settings (the explorer must add nothing and drop nothing); the drawing's leg
states and rails against the leg lengths and joint ranges computed here from (M1)-(M2); links
round-trip. Coarse voxels (h = 6) keep them cheap.
"""

from __future__ import annotations

import json
import urllib.parse

import numpy as np
import pytest
from explorer_client import FakeBrowser, wait_for, wait_idle  # tests/ (pytest's prepend import mode)

from paraspace.app.explorer import Explorer
from paraspace.app.explorer.numbers_panel import fmt, ori_current
from paraspace.app.explorer.mechanism_scene import STATE_COLORS, joint_paths, leg_state
from paraspace.app.mechanism_link import MECH_PRESETS, file_link, preset_link, preset_params
from paraspace.app.urlstate import encode_query, parse_query
from paraspace.kinematics.design import Design
from paraspace.kinematics.mechanism import Cone, Leg, dumps_mechanism
from paraspace.kinematics.mechanism_orientation import mechanism_orientation_workspace
from paraspace.kinematics.mechanism_workspace import compute_mechanism_workspace
from paraspace.kinematics.presets import preset
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

H = 6.0


@pytest.fixture(scope="module")
def explorer():
    exp = Explorer("127.0.0.1", 0).start()
    exp.warm.wait(120)
    yield exp
    exp.stop()


@pytest.fixture
def browsers(explorer):
    opened: list[FakeBrowser] = []

    def open_(search: str = "") -> FakeBrowser:
        b = FakeBrowser(explorer, search)
        opened.append(b)
        return b

    yield open_
    for b in opened:
        b.close()


def wait_mechanism(exp: Explorer, session, timeout: float = 240.0) -> None:
    """Until the full, measured result of the session's current mechanism is on screen."""
    def idle() -> bool:
        b, s, info = session.bundle, session.state, session.ctx.ws_info
        return (not exp.jobs.active(session.job_client) and b is not None and b.mechanism == s.mechanism
                and b.result.settings.voxel == s.voxel and info is not None and not info.preview
                and info.measures is not None)
    wait_for(idle, timeout, "the mechanism's workspace")


def direct_volume(mech, h: float = H, orientation=(0.0, 0.0, 0.0)) -> float:
    return compute_mechanism_workspace(mech, WorkspaceSettings(voxel=h, orientation=orientation)).volume


@pytest.mark.parametrize("name", MECH_PRESETS)
def test_selecting_a_preset_shows_the_volume_of_compute_mechanism_workspace(explorer, browsers, name):
    b = browsers(f"voxel={H:g}")
    s = b.session
    wait_idle(explorer, s, 240)
    b.set(s.panels.mechanism.selector, name)
    wait_for(lambda: s.state.mechanism is not None and s.state.mechanism.preset == name, 30, "selection")
    wait_mechanism(explorer, s)
    assert s.bundle.result.volume == direct_volume(preset(name)) > 0
    # its parameters as sliders (defaults from PresetParam), the paper's design sliders hidden
    folder = s.panels.mechanism.folders[name]
    assert folder.visible and not s.panels.design["a"].visible
    for p in preset_params(name):
        assert s.panels.mechanism.sliders[name][p.name].value == p.default
    # the certified bracket of the mechanism's own workspace, as computed directly (its proof is tested
    # against the brute force in test_mechanism_workspace.py); a fixed-length leg's caveat said
    from paraspace.kinematics.mechanism_workspace import bracket_caveat, general_bracket_of

    direct = general_bracket_of(compute_mechanism_workspace(preset(name), WorkspaceSettings(voxel=H)), refine=1)
    line = f"{fmt(direct.volume_inner, 4)} ≤ V ≤ {fmt(direct.volume_outer, 4)} (continuous workspace, units³)"
    wait_for(lambda: line in s.panels.numbers.content.replace("\\", ""), 120, "the mechanism's bracket")
    assert direct.volume_inner <= s.bundle.result.volume <= direct.volume_outer
    assert direct.volume_inner > 0 and bracket_caveat(preset(name)) is None  # 6-pss: one leg per chain
    assert "inner bound 0" not in s.panels.numbers.content
    assert "bracket not for" not in s.panels.numbers.content.replace("\\", "")
    assert f"[{fmt(direct.volume_inner, 4)}, {fmt(direct.volume_outer, 4)}]" in s.panels.summary.content
    # the orientation maps and TI are the mechanism's own (its symmetry lines), as computed directly
    ori = wait_for(lambda: s.ctx.orientation if ori_current(s.state, s.ctx.orientation) else None, 120,
                   "the mechanism's orientation maps")
    ref = mechanism_orientation_workspace(preset(name), s.state.orientation_settings())
    assert (ori.ti1, ori.ti2) == (ref.ti1, ref.ti2) and ref.ti1 > 0
    # the status the user is left with says so too (waited for: once, in a fresh-clone run on a loaded
    # machine, it still read "computing... 0 %" when the maps of the state were already on screen; one
    # orientation job per selection when replayed here; the controller now starts no job for maps on
    # screen, tests/test_explorer_scan.py)
    wait_for(lambda: f"TI₁ = {fmt(ref.ti1, 4)}" in s.panels.orientation_status.content, 60, "TI in the status")
    wait_for(lambda: f"{fmt(ref.ti1, 4)}" in s.panels.summary.content, 10, "TI in the strip")
    assert s.compare.pin_button.disabled and s.tilt.run.disabled
    assert s.panels.pose["z"].max == 350.0  # every height (the paper design's reach is 165)
    s.share_controller.download_report()  # the paper design's report: said so, nothing computed
    assert f"not for the {name} mechanism yet" in s.panels.report_status.content.replace("\\", "")
    # the drawing: six legs, the paper's legs hidden
    assert s.pose_controller.general is not None and not s.mechanism.legs.visible


def test_a_parameter_slider_recomputes_with_that_value(explorer, browsers):
    b = browsers(f"voxel={H:g}&mech=gough-stewart")
    s = b.session
    wait_mechanism(explorer, s)
    before = s.bundle.result.volume
    b.set(s.panels.mechanism.sliders["gough-stewart"]["l_max"], 175.0)
    wait_for(lambda: dict(s.state.mechanism.params)["l_max"] == 175.0, 30, "the slider")
    wait_mechanism(explorer, s)
    expected = direct_volume(preset("gough-stewart", {"l_max": 175.0}))
    assert s.bundle.result.volume == expected
    assert expected > before  # a longer stroke reaches a superset
    assert "mp_l_max=175" in b.search or wait_for(lambda: "mp_l_max=175" in b.search, 5, "the link")


def test_a_refused_parameter_names_it_and_changes_nothing(explorer, browsers):
    b = browsers(f"voxel={H:g}&mech=gough-stewart")
    s = b.session
    wait_mechanism(explorer, s)
    state = s.state
    b.set(s.panels.mechanism.sliders["gough-stewart"]["l_min"], 170.0)  # above l_max = 164.5
    wait_for(lambda: s.panels.mechanism.message.visible, 30, "the message")
    text = s.panels.mechanism.message.content.replace("\\", "")
    assert "l_max" in text and "l_min < l_max" in text
    assert s.state == state


def test_a_bad_upload_is_named_and_leaves_the_state_unchanged(explorer, browsers):
    b = browsers(f"voxel={H:g}&mech=6-pups")
    s = b.session
    wait_mechanism(explorer, s)
    state, volume = s.state, s.bundle.result.volume
    bad = dumps_mechanism(preset("6-pss")).replace("length = [120.0, 120.0]", "length = [120.0, 110.0]", 1)
    assert not s.mechanism_controller.apply_upload("mine.toml", bad.encode())
    for text in (s.panels.status.content, s.panels.mechanism.message.content):
        text = text.replace("\\", "")
        assert "mine.toml" in text and "chains[0].legs[0].length" in text
    assert not s.mechanism_controller.apply_upload("big.json", b"{" + b" " * (64 * 1024 + 1) + b"}")
    assert f"{64 * 1024 + 3:,} bytes" in s.panels.mechanism.message.content.replace("\\", "")
    assert s.state == state and s.bundle.result.volume == volume and "uploaded file" not in \
        s.panels.mechanism.selector.options


def test_an_upload_computes_it_and_its_link_restores_it(explorer, browsers):
    b = browsers(f"voxel={H:g}&z=140")
    s = b.session
    wait_idle(explorer, s, 240)
    mech = preset("6-pss", {"rail_stroke": 120.0})
    assert s.mechanism_controller.apply_upload("linapod.toml", dumps_mechanism(mech).encode())
    wait_mechanism(explorer, s)
    assert s.panels.mechanism.selector.value == "uploaded file"
    assert s.bundle.result.volume == direct_volume(mech)
    wait_for(lambda: "mfile=" in b.search, 5, "the link")
    b2 = browsers(b.search)
    s2 = b2.session
    assert s2.url_messages == [] and s2.state == s.state and s2.state.pose.z == 140.0
    wait_mechanism(explorer, s2)
    assert s2.bundle.result.volume == s.bundle.result.volume


@pytest.mark.parametrize("extra, why", [
    ({"u_cone": {"axis": [0.0, 0.0, 1.0], "angle": 60.0}}, "not available with joint cones"),
    ({"diameter": 4.0}, "not available with leg diameters"),
])
def test_a_mechanism_without_a_bracket_says_why(explorer, browsers, extra, why):
    """An uploaded description with cones or leg diameters (which the bracket's proof does not cover)
    gets its volume and the reason in place of the certified bracket, and no bracket job."""
    data = preset("gough-stewart").to_dict()
    for chain in data["chains"]:
        for leg in chain["legs"]:
            leg.update(extra)
    b = browsers(f"voxel={H:g}&z=140")
    s = b.session
    wait_idle(explorer, s, 240)

    def bracket_jobs():
        return sum(j.client == s.job_client and j.kind == "bracket" for j in explorer.jobs.jobs())

    wait_for(lambda: "(continuous workspace, units³)" in s.panels.numbers.content, 120, "the paper design's bracket")
    before = bracket_jobs()
    assert s.mechanism_controller.apply_upload("coned.json", json.dumps(data).encode())
    wait_mechanism(explorer, s)
    text = s.panels.numbers.content.replace("\\", "")
    wait_for(lambda: f"</span> bracket {why}" in s.panels.numbers.content.replace("\\", ""), 30, "the reason")
    assert s.bundle.result.volume > 0 and "(continuous workspace, units³)" not in text
    assert bracket_jobs() == before  # none started for the mechanism


def test_preset_links_round_trip_and_bad_parameters_are_named():
    link = preset_link("6-pups", {"lift": 40.0})
    st = parse_query("")[0].replace(mechanism=link)
    q = encode_query(st)
    assert "mech=6-pups" in q and "mp_lift=40" in q and "mp_base_radius" not in q  # defaults are not written
    assert parse_query(q) == (st, [])
    f = file_link(dumps_mechanism(preset("gough-stewart")))
    st = st.replace(mechanism=f)
    assert parse_query(encode_query(st)) == (st, [])
    # a bad parameter: the preset builder's message (the CLI's --param message), the default kept
    state, msgs = parse_query("mech=6-pups&mp_lift=2000&mp_l_min=120")
    assert state.mechanism == preset_link("6-pups", {"l_min": 120.0})
    assert msgs == ["mp_lift = 2000.0 is invalid: valid range [0, 1000]; the preset's default is used"]
    state, msgs = parse_query("mech=hexapod")
    assert state.mechanism is None and "mech = 'hexapod' is invalid" in msgs[0]
    state, msgs = parse_query("mech=file&mfile=" + urllib.parse.quote("!!"))
    assert state.mechanism is None and msgs and msgs[0].startswith("mfile")


def test_opening_a_preset_link_restores_mechanism_parameters_and_pose(explorer, browsers):
    b = browsers(f"voxel={H:g}&mech=6-pups&mp_lift=30&z=150&x=5")
    s = b.session
    assert s.url_messages == []
    assert dict(s.state.mechanism.params)["lift"] == 30.0 and s.state.pose.z == 150.0
    assert s.panels.mechanism.selector.value == "6-pups"
    assert s.panels.mechanism.sliders["6-pups"]["lift"].value == 30.0
    wait_mechanism(explorer, s)
    assert s.bundle.result.volume == direct_volume(preset("6-pups", {"lift": 30.0}))
    wait_for(lambda: "mp_lift=30" in b.search, 5, "the address bar")
    assert parse_query(b.search) == (s.state, [])


def test_back_to_paper_is_the_paper_path_unchanged(explorer, browsers):
    b = browsers(f"voxel={H:g}&mech=gough-stewart")
    s = b.session
    wait_mechanism(explorer, s)
    b.set(s.panels.mechanism.selector, "paper")
    wait_for(lambda: s.state.mechanism is None, 30, "paper")
    wait_idle(explorer, s, 240)
    ref = compute_workspace(Design(), WorkspaceSettings(voxel=H))
    assert s.bundle.result.volume == ref.volume
    assert np.array_equal(s.bundle.result.occupancy, ref.occupancy)
    assert s.panels.design["a"].visible and s.mechanism.legs.visible and s.pose_controller.general is None
    assert s.panels.pose["z"].max == 165.0  # the paper design's reach again
    assert not s.tilt.run.disabled and "not for the" not in s.panels.numbers.content
    assert "mech=" not in b.search or wait_for(lambda: "mech=" not in b.search, 5, "the link")


def test_the_drawing_colours_each_leg_by_its_state(explorer, browsers):
    # Gough-Stewart (base radius 100, platform 50): at z = 200 every leg is longer than l_max = 164.5
    b = browsers(f"voxel={H:g}&mech=gough-stewart&z=200")
    s = b.session
    wait_mechanism(explorer, s)
    general = s.pose_controller.general
    mech = preset("gough-stewart")
    tops = np.array([leg.platform for _, _, leg in mech.legs]) + [0.0, 0.0, 200.0]
    bases = np.array([leg.base for _, _, leg in mech.legs])
    assert np.all(np.linalg.norm(tops - bases, axis=1) > 164.5)
    assert np.all(np.asarray(general.legs.batched_colors) == STATE_COLORS["too_long"])
    assert "too long" in s.panels.pose_table.content and not s.ctx.in_workspace
    # down to z = 130: every leg inside (lengths about 139.5, in [114.5, 164.5])
    b.set(s.panels.pose["z"], 130.0)
    wait_for(lambda: s.ctx.in_workspace and np.all(np.asarray(s.pose_controller.general.legs.batched_colors)
                                                   == STATE_COLORS["inside"]), 30, "legs inside, in the workspace")


def test_joint_paths_are_rails_over_the_prismatic_range_and_arcs_over_the_revolute_range():
    mech = preset("6-pups", {"lift": 40.0})
    chain = mech.chains[0]
    segs, _ = joint_paths(chain, [10.0])
    base = np.asarray(chain.legs[0].base)
    assert segs.shape == (1, 2, 3)
    assert np.allclose(segs[0], [base, base + [0.0, 0.0, 40.0]])
    paper = preset("paper")
    ch = paper.chains[0]
    segs, _ = joint_paths(ch, [0.0, 20.0])
    arc = segs[:32]  # first leg, revolute: 33 points about z through the leg's base joint at d = 20
    radius = np.linalg.norm(arc[:, 0, :2], axis=1)
    assert np.allclose(radius, radius[0]) and np.allclose(arc[:, 0, 2], 0.0)
    ang = np.degrees(np.arctan2(arc[[0, -1], [0, 1], 1], arc[[0, -1], [0, 1], 0]))
    d0 = np.degrees(np.arctan2(ch.base_points([0.0, 20.0])[0, 1], ch.base_points([0.0, 20.0])[0, 0]))
    assert np.allclose(ang - d0, [-15.0, 15.0])


def test_leg_state_of_a_cone():
    leg = Leg((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (1.0, 200.0), u_cone=Cone((0.0, 0.0, 1.0), 30.0))
    eye = np.eye(3)
    tilt = np.radians(40.0)
    assert leg_state(leg, np.zeros(3), 100 * np.array([np.sin(tilt), 0.0, np.cos(tilt)]), eye, eye) == "out_of_cone"
    tilt = np.radians(20.0)
    assert leg_state(leg, np.zeros(3), 100 * np.array([np.sin(tilt), 0.0, np.cos(tilt)]), eye, eye) == "inside"
    assert leg_state(leg, np.zeros(3), np.array([0.0, 0.0, 300.0]), eye, eye) == "too_long"


def test_fixed_length_legs_are_drawn_at_their_length_where_the_pose_is_reachable(explorer, browsers):
    # 6-PSS: legs of length 120 on vertical rails [0, 150]; z = 150 is inside its workspace
    b = browsers(f"voxel={H:g}&mech=6-pss&z=150")
    s = b.session
    wait_mechanism(explorer, s)
    assert s.ctx.in_workspace
    general = s.pose_controller.general
    assert np.allclose(np.asarray(general.legs.batched_scales)[:, 2], 120.0, atol=1e-4)
    assert np.all(np.asarray(general.legs.batched_colors) == STATE_COLORS["inside"])
    assert "**reachable**" in s.panels.pose_table.content


def test_stop_goes_back_to_the_mechanism_on_screen_and_stale_jobs_are_dropped(explorer, browsers):
    b = browsers(f"voxel={H:g}&mech=6-pups")
    s = b.session
    wait_mechanism(explorer, s)
    shown = s.state.mechanism
    explorer.shell_cache.clear()  # not a cache hit from another test
    b.set(s.panels.voxel, 1.0)  # a slow general job
    job = wait_for(lambda: s.workspace_controller.job if s.state.voxel == 1.0 and s.workspace_controller.job
                   is not None and s.workspace_controller.job.status == "running" else None, 30, "h=1 job running")
    b.click(s.panels.stop)
    wait_for(lambda: job.is_final, 30, "stopped job")
    assert job.status == "cancelled"
    wait_for(lambda: s.state.voxel == H and s.panels.voxel.value == H, 30, "voxel back to the shown result")
    assert s.state.mechanism == shown and s.bundle.mechanism == shown
    # two selections in a row: the first one's job never shows its shell over the second's
    b.set(s.panels.mechanism.selector, "gough-stewart")
    b.set(s.panels.mechanism.selector, "6-pss")
    wait_for(lambda: s.state.mechanism is not None and s.state.mechanism.preset == "6-pss", 30, "6-pss")
    wait_mechanism(explorer, s)
    assert s.bundle.mechanism.preset == "6-pss" and s.bundle.result.volume == direct_volume(preset("6-pss"))


def test_a_selection_arriving_while_stop_rewrites_the_controls_is_applied(explorer, browsers, monkeypatch):
    """Stop 40's CI: viser runs a session's callbacks on threads, and the selector's callback read the
    selector's value when it ran. A Stop that was still writing the shown mechanism's controls put
    "6-pups" back into the selector between the user's "6-pss" and its callback: the callback applied
    6-pups, and the user's selection was lost. The callbacks here are held until Stop's write is done."""
    import threading

    b = browsers(f"voxel={H:g}&mech=6-pups")
    s = b.session
    wait_mechanism(explorer, s)
    held, release = threading.Semaphore(0), threading.Event()

    def hold() -> None:  # on the callback's thread, before the handler runs
        held.release()
        assert release.wait(30)

    monkeypatch.setattr(s.ctx, "_dismiss_link_messages", hold)
    sel = s.panels.mechanism.selector
    b.set(sel, "gough-stewart")
    b.set(sel, "6-pss")
    assert held.acquire(timeout=30) and held.acquire(timeout=30)  # both callbacks waiting
    assert sel.value == "6-pss"
    s.mechanism_controller.show(s.state.mechanism)  # Stop's write of the mechanism on screen
    assert sel.value == "6-pups"
    release.set()
    wait_for(lambda: s.state.mechanism is not None and s.state.mechanism.preset == "6-pss", 30, "6-pss")
    wait_mechanism(explorer, s)
    assert s.bundle.mechanism.preset == "6-pss" and sel.value == "6-pss"


def test_a_selection_recorded_while_the_first_ones_callback_runs_is_applied(explorer, browsers, monkeypatch):
    """This session's CI (a two-core machine under load) once lost the second of two quick selections
    (gough-stewart, then 6-pss; the state stayed on gough-stewart): the first callback read the
    recorded choice and cleared it in two steps, and the second message's record fell between them.
    The callback now takes the choice and clears it in one locked step; here the first callback is
    held just after its take while the second selection is recorded."""
    import threading

    b = browsers(f"voxel={H:g}&mech=6-pups")
    s = b.session
    wait_mechanism(explorer, s)
    ctl = s.mechanism_controller
    real, first = ctl.chosen.take, []
    taken, go = threading.Event(), threading.Event()

    def take():
        choice = real()
        if not first:
            first.append(choice)
            taken.set()
            assert go.wait(30)
        return choice

    monkeypatch.setattr(ctl.chosen, "take", take)
    sel = s.panels.mechanism.selector
    b.set(sel, "gough-stewart")
    assert taken.wait(30) and first == ["gough-stewart"]
    b.set(sel, "6-pss")
    wait_for(lambda: ctl.chosen.peek() == "6-pss", 30, "the second selection recorded")
    go.set()
    wait_for(lambda: s.state.mechanism is not None and s.state.mechanism.preset == "6-pss", 30, "6-pss")
    wait_mechanism(explorer, s)
    assert s.bundle.mechanism.preset == "6-pss" and sel.value == "6-pss"


def test_a_file_too_large_for_a_link_is_used_but_not_put_in_the_link(explorer, browsers, monkeypatch):
    from paraspace.app.explorer import mechanism_panel

    # a description's compact JSON stays under the 4,096-character query bound (six legs at most):
    # the bound is made small here to see the refusal
    monkeypatch.setattr(mechanism_panel, "MAX_QUERY_CHARS", 400)
    b = browsers(f"voxel={H:g}")
    s = b.session
    wait_idle(explorer, s, 240)
    mech = preset("gough-stewart", {"l_max": 170.0})
    assert s.mechanism_controller.apply_upload("gs.toml", dumps_mechanism(mech).encode())
    assert "too large to share in a link" in s.panels.mechanism.message.content
    wait_mechanism(explorer, s)
    assert s.bundle.result.volume == direct_volume(mech)
    q = s.share_controller.query()  # the link of the state on screen
    assert s.state.mechanism is not None and "mech=" not in q and "mfile" not in q
    assert parse_query(q)[0].mechanism is None


def test_mechanism_link_messages_quote_a_bounded_piece():
    payload = "<script>" + "x" * 5000 + "</script>"
    for query in (f"mech=6-pups&mp_lift={payload}", f"mech={payload}", f"mech=file&mfile={payload}"):
        state, msgs = parse_query(urllib.parse.urlencode(dict(urllib.parse.parse_qsl(query))))
        assert state.mechanism is None or state.mechanism == preset_link("6-pups")
        assert msgs and all(len(m) < 400 and "</script>" not in m for m in msgs), msgs


def test_pins_of_the_paper_design_wait_while_another_mechanism_is_selected(explorer, browsers):
    """A link's Compare pins are paper designs: with the 6-pss mechanism selected their ghosts leave
    the scene and the table says why, while the pin stays in the state and the link; back on the
    paper's mechanism the ghost and the table return."""
    b = browsers(f"voxel={H:g}&angle_step=10&pin=70,14,50,100,114.5,50,30,centered")
    s = b.session
    wait_idle(explorer, s, 240)
    wait_for(lambda: s.compare.pinned is not None and s.compare.handle is not None, 60, "the pin's ghost")
    b.set(s.panels.mechanism.selector, "6-pss")
    wait_for(lambda: s.state.mechanism is not None and s.state.mechanism.preset == "6-pss", 30, "selection")
    wait_mechanism(explorer, s)
    wait_for(lambda: s.compare.handle is None and s.compare.cage is None, 10, "the ghost hidden")
    # the table is written before the ghosts hide; waited for all the same, so that a render of the
    # paper's table that ended late (CI read it once, with the ghost already hidden) fails only if it stays
    wait_for(lambda: "The pinned design is of the paper's mechanism, not the 6-pss mechanism"
             in s.compare.table.content.replace("\\", ""), 10, "the table saying why")
    assert s.compare.pin_button.disabled  # the mechanism's note: its designs cannot be pinned yet
    assert [d.a for d in s.state.pins] == [70.0]
    wait_for(lambda: "pin=70," in urllib.parse.unquote(b.search) and "mech=6-pss" in b.search, 5, "the link")
    b.set(s.panels.mechanism.selector, "paper")
    wait_for(lambda: s.state.mechanism is None, 30, "back to the paper")
    wait_idle(explorer, s, 240)
    wait_for(lambda: s.compare.handle is not None and "| volume" in s.compare.table.content, 30, "the ghost back")
    assert not s.compare.pin_button.disabled
