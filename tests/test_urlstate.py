"""Shareable-URL state: encode -> parse is the identity; bad fields are reported, the rest applies."""

from __future__ import annotations

import urllib.parse

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from paraspace.app.urlstate import (
    CAMERA_PRESETS,
    CUT_KEEPS,
    DEFAULT_STATE,
    DESIGN_RANGES,
    POSE_RANGES,
    SETTING_RANGES,
    ExplorerState,
    check_field,
    encode_query,
    known_keys,
    parse_query,
)
from paraspace.kinematics.design import ETA_RANGES, PARAMS, Design
from paraspace.kinematics.pose import Pose


def _num(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(min_value=lo, max_value=hi, allow_nan=False, allow_infinity=False)


@st.composite
def states(draw: st.DrawFn) -> ExplorerState:
    fields = {k: draw(_num(r.lo, r.hi)) for k, r in DESIGN_RANGES.items()}
    fields["d_s"] = min(fields["d_s"], fields["r"])  # the model requires d_s <= r
    design = Design(**fields, eta_range=draw(st.sampled_from(ETA_RANGES)))
    pose = Pose(**{k: draw(_num(r.lo, r.hi)) for k, r in POSE_RANGES.items()})
    lo, hi = design.eta_limits
    return ExplorerState(
        design=design, pose=pose,
        carriages=draw(st.sampled_from(("auto", "manual"))),
        d=tuple(draw(_num(0.0, design.d_s)) for _ in range(3)),  # type: ignore[arg-type]
        eta=tuple(draw(_num(lo, hi)) for _ in range(3)),  # type: ignore[arg-type]
        voxel=draw(_num(SETTING_RANGES["voxel"].lo, SETTING_RANGES["voxel"].hi)),
        z0=draw(_num(SETTING_RANGES["z0"].lo, SETTING_RANGES["z0"].hi)),
        view=draw(st.sampled_from(CAMERA_PRESETS)),
        cut=draw(st.booleans()),
        cut_z=draw(_num(SETTING_RANGES["cut_z"].lo, SETTING_RANGES["cut_z"].hi)),
        cut_keep=draw(st.sampled_from(CUT_KEEPS)),
        opacity=draw(_num(SETTING_RANGES["opacity"].lo, SETTING_RANGES["opacity"].hi)),
    )


@settings(max_examples=300, deadline=None)
@given(states())
def test_round_trip_is_identity(state: ExplorerState) -> None:
    parsed, messages = parse_query(encode_query(state))
    assert messages == []
    assert parsed == state


def test_round_trip_of_defaults_and_leading_question_mark() -> None:
    q = encode_query(DEFAULT_STATE)
    assert parse_query(q) == (DEFAULT_STATE, [])
    assert parse_query("?" + q) == (DEFAULT_STATE, [])
    assert parse_query("") == (DEFAULT_STATE, [])


def test_encoding_is_readable_and_names_cli_keys() -> None:
    state = DEFAULT_STATE.replace(design=Design(a=60, d_s=40, eta_s=30), pose=Pose(z=130.5))
    q = dict(urllib.parse.parse_qsl(encode_query(state)))
    # design and pose always written, with the CLI's names and short numbers
    assert q["a"] == "60" and q["d_s"] == "40" and q["eta_s"] == "30" and q["l_min"] == "114.5"
    assert q["z"] == "130.5" and q["eta_range"] == "centered"
    # view settings at their defaults are left out
    assert "view" not in q and "opacity" not in q and "carriages" not in q


def test_bad_values_are_reported_by_field_and_the_rest_applies() -> None:
    state, messages = parse_query("a=60&b=abc&l_s=5000&eta_s=nan&eta_range=sideways&z=140&view=front&voxel=0.1")
    assert state.design.a == 60.0 and state.pose.z == 140.0  # good fields applied
    # bad fields keep their defaults: nothing clamped
    assert state.design.b == PARAMS["b"].default
    assert state.design.l_s == PARAMS["l_s"].default
    assert state.design.eta_s == PARAMS["eta_s"].default
    assert state.design.eta_range == "centered" and state.view == "iso" and state.voxel == 2.0
    assert len(messages) == 6
    text = "\n".join(messages)
    for field, valid in (("b", "[0, 1000]"), ("l_s", "[0, 1000]"), ("eta_s", "[0, 180] deg"),
                         ("eta_range", "centered, from-zero"), ("view", "iso, top, bottom, side"),
                         ("voxel", "[0.25, 100]")):
        assert any(m.startswith(field + " = ") and valid in m for m in messages), (field, text)


def test_out_of_range_is_rejected_not_clamped() -> None:
    state, messages = parse_query("a=1000.5&x=-10001&theta=91")
    assert state.design.a == 50.0 and state.pose.x == 0.0 and state.pose.theta == 0.0
    assert [m.split(" ")[0] for m in messages] == ["a", "x", "theta"]
    assert all("out of range" in m for m in messages)


def test_one_rule_per_field_the_link_accepts_what_the_model_accepts() -> None:
    """Issue 8 defect 1: a value outside the slider (Table I) range that the number box accepts
    (a = 8) is restored exactly by its link, and the range a link reports for a field is the one
    the core reports (CLI, REST, explorer)."""
    from paraspace.kinematics.design import Design, ParameterError
    from paraspace.kinematics.pose import Pose
    from paraspace.kinematics.workspace import WorkspaceSettings

    typed = DEFAULT_STATE.replace(design=Design(a=8.0, l_min=250.0), pose=Pose(x=400.0, psi=120.0), voxel=0.5)
    state, messages = parse_query(encode_query(typed))
    assert messages == [] and state == typed
    for key, bad, build in (("a", 2000.0, lambda v: Design(a=v)), ("eta_s", 190.0, lambda v: Design(eta_s=v)),
                            ("z", 2e4, lambda v: Pose(z=v)), ("theta", 95.0, lambda v: Pose(theta=v)),
                            ("voxel", 0.1, lambda v: WorkspaceSettings(voxel=v))):
        _, msgs = parse_query(f"{key}={bad:g}")
        with pytest.raises(ParameterError) as err:
            build(bad)
        assert len(msgs) == 1 and err.value.valid.split(" ")[0] in msgs[0], (key, msgs, err.value.valid)
        assert check_field(key, bad) is not None and check_field(key, bad).split(";")[1] == msgs[0].split(";")[1]


def test_joint_keys_round_trip_and_bad_ones_name_the_range() -> None:
    from paraspace.kinematics.joints import Joints

    s = DEFAULT_STATE.replace(joints=Joints(theta_u=45.0, theta_s=37.5, cone_axis="home", leg_diameter=10.0,
                                            clearance=1.0))
    q = encode_query(s)
    assert "theta_u=45" in q and "cone_axis=home" in q
    assert parse_query(q) == (s, [])
    assert "theta_u" not in encode_query(DEFAULT_STATE)
    state, messages = parse_query("theta_u=0&cone_axis=up&leg_diameter=-3")
    assert state.joints == Joints()
    assert [m.split(" ")[0] for m in messages] == ["theta_u", "cone_axis", "leg_diameter"]
    assert "(0, 90] degrees" in messages[0] and "[0, 100]" in messages[2]


def test_inconsistent_design_names_the_field() -> None:
    state, messages = parse_query("r=60&d_s=80&a=70")
    assert state.design.r == 60.0 and state.design.a == 70.0
    assert state.design.d_s == 50.0  # default kept (<= r)
    assert len(messages) == 1 and messages[0].startswith("d_s = 80") and "r=60" in messages[0]


def test_manual_carriages_are_checked_against_the_parsed_design() -> None:
    state, messages = parse_query("d_s=30&eta_s=20&carriages=manual&d_1=25&d_2=31&eta_1=-10&eta_3=11")
    assert state.carriages == "manual"
    assert state.d == (25.0, 0.0, 0.0) and state.eta == (-10.0, 0.0, 0.0)
    assert [m.split(" ")[0] for m in messages] == ["d_2", "eta_3"]
    assert "d_s=30" in messages[0] and "[-10, 10]" in messages[1]


def test_unknown_duplicate_and_viser_keys_are_reported_and_never_kept() -> None:
    state, messages = parse_query("a=20&a=30&color=red&websocket=ws://127.0.0.1:9/&darkMode=1&playbackPath=/x")
    assert state.design.a == 30.0
    assert len(messages) == 2
    assert any("a is given more than once" in m for m in messages)
    unknown = next(m for m in messages if m.startswith("unknown parameters"))
    for key in ("'color'", "'websocket'", "'darkMode'", "'playbackPath'"):
        assert key in unknown
    q = encode_query(state)
    keys = {k for k, _ in urllib.parse.parse_qsl(q)}
    assert keys <= set(known_keys()) and "websocket" not in keys
    assert parse_query(q) == (state, [])


def test_messages_quote_at_most_a_bounded_piece_of_the_value() -> None:
    payload = "<script>" + "x" * 5000 + "</script>"
    _, messages = parse_query(urllib.parse.urlencode({"view": payload, "a": payload, payload: "1"}))
    assert len(messages) == 3
    assert all(len(m) < 400 for m in messages), [len(m) for m in messages]
    assert all("</script>" not in m for m in messages)


@pytest.mark.parametrize("query", ["%zz=1", "&&&", "a", "a=", "=5", "a=1e999", "cut=maybe", "x=0x10"])
def test_garbage_never_raises(query: str) -> None:
    state, messages = parse_query(query)
    assert isinstance(state, ExplorerState)
    assert isinstance(messages, list)


def test_pinned_design_round_trips_and_bad_pins_are_named() -> None:
    s = DEFAULT_STATE.replace(pins=(Design(a=10.0, eta_range="from-zero"),))
    q = encode_query(s)
    assert "pin=10%2C14%2C50%2C100%2C114.5%2C50%2C30%2Cfrom-zero" in q or "pin=10,14,50,100,114.5,50,30,from-zero" in q
    assert parse_query(q) == (s, [])
    for bad, text in (("1,2,3", "expected 7 numbers"), ("10,14,50,100,114.5,50,300,centered", "eta_s"),
                      ("10,14,150,100,114.5,50,30,centered", "d_s"), ("10,14,50,100,114.5,50,30,sideways", "eta_range")):
        state, messages = parse_query("pin=" + bad)
        assert state.pins == () and len(messages) == 1 and text in messages[0], (bad, messages)


def test_several_pins_round_trip_in_order_and_the_bound_is_named() -> None:
    from paraspace.app.urlstate import MAX_PINS

    pins = tuple(Design(a=a) for a in (10.0, 30.0, 80.0))
    s = DEFAULT_STATE.replace(pins=pins)
    q = encode_query(s)
    assert q.count("pin=") == 1 and q.count(";") == 2  # one key, designs separated by ';'
    assert parse_query(q) == (s, [])
    # a bad design among good ones is named; the good ones are kept, in order
    good = "10,14,50,100,114.5,50,30,centered"
    state, messages = parse_query(f"pin={good};1,2,3;80,14,50,100,114.5,50,30,centered")
    assert [d.a for d in state.pins] == [10.0, 80.0] and len(messages) == 1 and "expected 7 numbers" in messages[0]
    # more than MAX_PINS: the bound is named, the first MAX_PINS kept (nothing silently dropped)
    many = ";".join(f"{10 + k},14,50,100,114.5,50,30,centered" for k in range(MAX_PINS + 2))
    state, messages = parse_query("pin=" + many)
    assert len(state.pins) == MAX_PINS and any(f"at most {MAX_PINS} designs" in m for m in messages)
