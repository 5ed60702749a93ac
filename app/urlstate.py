"""The explorer's state as a shareable URL query string.

One :class:`ExplorerState` holds everything a link restores: the design (paper Table I), the
platform pose, how the carriages are set (redundancy resolved automatically or by hand), the
workspace sampling (voxel edge ``h``), the height ``z0`` of the orientation-map lines, and the view
(camera preset, cut plane, shell opacity).

URL format (keys are the CLI's names)::

    ?a=60&b=14&d_s=40&r=100&l_min=114.5&l_s=50&eta_s=30&eta_range=centered
     &x=0&y=0&z=130&psi=0&theta=0&phi=0
     [&carriages=manual&d_1=10&d_2=10&d_3=10&eta_1=0&eta_2=0&eta_3=0]
     [&voxel=2&z0=130&angle_range=90&angle_step=0.5&view=iso&cut=1&cut_z=80&cut_keep=below&opacity=0.6]
     [&theta_u=45&theta_s=45&cone_axis=home&leg_diameter=10&clearance=1]
     [&pin=10,14,50,100,114.5,50,30,centered[;80,14,50,100,114.5,50,30,centered...]]
     [&task=box,0,0,130,40,40,30,15,0]
     [&mech=6-pups&mp_lift=40 | &mech=file&mfile=...]   (app/mechanism_link.py)

Encoding policy (:func:`encode_query`): the 8 design keys and the 6 pose keys are **always**
written, so a link states its design and pose explicitly and keeps meaning the same mechanism even
if the paper defaults of a later version change. Every other key is written only when it differs
from its default (short links); the six carriage values are written whenever
``carriages=manual`` or any of them is not 0. Numbers are written in Python's shortest round-trip
form (``60``, ``114.5``), so ``parse_query(encode_query(s)) == (s, [])`` exactly.

Parsing policy (:func:`parse_query`): never raises. Each bad field (not a number, not one of the
choices, outside the field's accepted range (the same as the model's and the explorer's number
boxes; sliders span the narrower Table I ranges), or inconsistent such as ``d_s > r``) produces one
message naming the field, the value and the valid range; that field keeps its default and every
other field still applies. Nothing is silently clamped. Only the explorer's own keys
(:func:`known_keys`) are accepted: any other key, including those viser's web client would act on
(``websocket`` would connect the page to another server, ``playbackPath`` load a foreign recording),
is reported once and dropped, and never written back to the address bar. Values quoted in messages
are cut to :data:`QUOTE_CHARS` characters; messages are data (the explorer shows them escaped, see
:mod:`paraspace.app.textsafe`).
"""

from __future__ import annotations

import dataclasses
import math
import urllib.parse
from collections.abc import Iterator, Mapping
from typing import Any, Literal, cast

from paraspace.kinematics.design import ETA_RANGES, PARAMS, Design, EtaRange, ParameterError
from paraspace.kinematics.joints import CONE_AXES, Joints, check_joint_value
from paraspace.kinematics.orientation import OrientationSettings
from paraspace.kinematics.pose import POSE_LIMITS, Pose
from paraspace.kinematics.settings import ORIENTATION, WORKSPACE, Setting
from paraspace.kinematics.task import SHAPES as TASK_SHAPES
from paraspace.kinematics.task import OrientationSet, Region

from .mechanism_link import MechanismLink, encode_mechanism, param_keys, parse_mechanism_pairs
from .numfmt import format_number
from .schema import LINK_FIELDS, link_number_error

CarriageMode = Literal["auto", "manual"]
CameraPreset = Literal["iso", "top", "bottom", "side"]
CutKeep = Literal["below", "above"]

CARRIAGE_MODES: tuple[str, ...] = ("auto", "manual")
CAMERA_PRESETS: tuple[str, ...] = ("iso", "top", "bottom", "side")
CUT_KEEPS: tuple[str, ...] = ("below", "above")

DESIGN_KEYS: tuple[str, ...] = ("a", "b", "d_s", "r", "l_min", "l_s", "eta_s")
POSE_KEYS: tuple[str, ...] = ("x", "y", "z", "psi", "theta", "phi")
D_KEYS: tuple[str, ...] = ("d_1", "d_2", "d_3")
ETA_KEYS: tuple[str, ...] = ("eta_1", "eta_2", "eta_3")


@dataclasses.dataclass(frozen=True)
class Range:
    """Closed slider range ``[lo, hi]`` with the slider step (the step is a UI hint only)."""

    lo: float
    hi: float
    step: float

    def text(self, unit: str = "") -> str:
        """``"[lo, hi]"`` plus an optional unit."""
        return f"[{self.lo:g}, {self.hi:g}]" + (f" {unit}" if unit else "")


# One rule per field (every entry point: slider, number box, URL, CLI, REST): a field ACCEPTS its
# model range (the *_RANGES below, the same as kinematics' validation); its SLIDER spans the
# paper's Table I range (or a practical range where Table I fixes a value), and the number box
# inside the slider takes any accepted value, so whatever the explorer applies, its link restores.

#: Accepted ranges of the design parameters: the model's (:data:`kinematics.design.PARAMS`);
#: ``d_s <= r`` is checked across fields.
DESIGN_RANGES: dict[str, Range] = {
    name: Range(spec.model_min, spec.model_max, 0.5) for name, spec in PARAMS.items()
}
#: Slider ranges of the design parameters: paper Table I where it gives a range.
DESIGN_SLIDERS: dict[str, Range] = {
    name: Range(spec.slider_min, spec.slider_max, 0.5) for name, spec in PARAMS.items()
}
#: Accepted ranges of the pose (:data:`kinematics.pose.POSE_LIMITS`).
POSE_RANGES: dict[str, Range] = {k: Range(lo, hi, 0.5) for k, (lo, hi) in POSE_LIMITS.items()}
#: Slider ranges of the pose. Positions cover the reach of every design in the Table I ranges
#: (``|P_xy| <= sqrt(r^2 + b^2/4) + l_max <= 500`` is loose; the workspaces found stay well inside
#: these); angles are limited to what a slider can still set precisely.
POSE_SLIDERS: dict[str, Range] = {
    "x": Range(-300.0, 300.0, 0.5),
    "y": Range(-300.0, 300.0, 0.5),
    "z": Range(0.0, 350.0, 0.5),
    "psi": Range(-90.0, 90.0, 0.5),
    "theta": Range(-60.0, 60.0, 0.5),
    "phi": Range(-60.0, 60.0, 0.5),
}
#: The settings whose rule is a core table entry (:mod:`kinematics.settings`): URL key -> entry.
TABLE_SETTINGS: dict[str, tuple[dict[str, Setting], str]] = {
    "voxel": (WORKSPACE, "voxel"), "z0": (ORIENTATION, "z0"),
    "angle_range": (ORIENTATION, "angle_range"), "angle_step": (ORIENTATION, "angle_step")}


class _SettingRanges(Mapping[str, Range]):
    """Ranges of the other numeric settings: the view's own (``cut_z``, ``opacity``), and for the
    keys of :data:`TABLE_SETTINGS` the core table's entry, read when asked (one definition)."""

    def __init__(self, own: dict[str, Range], slider: bool) -> None:
        self._own = own
        self._slider = slider

    def __getitem__(self, key: str) -> Range:
        if key in TABLE_SETTINGS:
            table, name = TABLE_SETTINGS[key]
            spec = table[name]
            if self._slider and spec.slider is not None:
                return Range(*spec.slider)
            return Range(spec.lo, spec.hi, spec.slider[2] if spec.slider else 0.5)
        return self._own[key]

    def __iter__(self) -> Iterator[str]:
        return iter((*TABLE_SETTINGS, *self._own))

    def __len__(self) -> int:
        return len(TABLE_SETTINGS) + len(self._own)


#: Accepted ranges of the other numeric settings (voxel: ``WorkspaceSettings``; z0: the
#: orientation settings; a grid over the voxel limit is refused when computed, with its message).
SETTING_RANGES: Mapping[str, Range] = _SettingRanges(
    {"cut_z": Range(-1e4, 1e4, 1.0), "opacity": Range(0.0, 1.0, 0.05)}, slider=False)
#: Slider ranges of the other numeric settings.
SETTING_SLIDERS: Mapping[str, Range] = _SettingRanges(
    {"cut_z": Range(0.0, 350.0, 1.0), "opacity": Range(0.1, 1.0, 0.05)}, slider=True)
#: Keys of the joint options (:mod:`kinematics.joints`), written only when set.
JOINT_KEYS: tuple[str, ...] = ("theta_u", "theta_s", "cone_axis", "leg_diameter", "clearance")


@dataclasses.dataclass(frozen=True)
class TaskLink:
    """The Task tab's region task as a link carries it: ``task=SHAPE,CX,CY,CZ,SIZES...,TILT,TORSION``
    (``box``: LX,LY,LZ; ``cylinder``: R,H; ``sphere``: R; tilt and torsion in degrees, 0 for the
    fixed home orientation). A pose list is not carried (it is pasted or uploaded)."""

    region: Region
    tilt: float = 0.0
    torsion: float = 0.0

    def orientations(self, step: float | None = None) -> OrientationSet:
        """The orientation set: every tilt up to ``tilt`` and torsion within ``torsion``, or the home
        orientation when both are 0."""
        if self.tilt == 0.0 and self.torsion == 0.0:
            return OrientationSet() if step is None else OrientationSet(step=step)
        if step is None:
            return OrientationSet(tilt=self.tilt, torsion=self.torsion)
        return OrientationSet(tilt=self.tilt, torsion=self.torsion, step=step)


def encode_task(task: TaskLink) -> str:
    """The ``task`` value of :class:`TaskLink`."""
    r = task.region
    return ",".join([r.shape, *(format_number(v) for v in (*r.center, *r.sizes, task.tilt, task.torsion))])


def parse_task(raw: str) -> tuple[TaskLink | None, str | None]:
    """:func:`encode_task` read back, or ``(None, message)`` naming what is wrong."""
    parts = [p.strip() for p in raw.split(",")]
    shape = parts[0] if parts else ""
    sizes = TASK_SHAPES.get(shape)
    if sizes is None:
        return None, f"task = {_quote(raw)} is invalid; expected box, cylinder or sphere first"
    names = ("CX", "CY", "CZ", *sizes, "TILT", "TORSION")
    if len(parts) != 1 + len(names):
        return None, f"task = {_quote(raw)} is invalid; expected {shape},{','.join(names)}"
    try:
        vals = [float(v) for v in parts[1:]]
    except ValueError:
        return None, f"task = {_quote(raw)} is invalid; expected numbers after the shape ({','.join(names)})"
    try:
        region = Region(shape, tuple(vals[:3]), tuple(vals[3:-2]))  # type: ignore[arg-type]
        tilt, torsion = vals[-2:]
        link = TaskLink(region, tilt, torsion)
        link.orientations()  # checks the tilt and torsion ranges
    except ParameterError as exc:
        return None, f"task: {exc}"
    return link, None


#: Most designs pinned at once (Compare tab, and the link's ``pin`` key).
MAX_PINS = 4


def encode_pin(design: Design) -> str:
    """The ``pin`` value: the seven design numbers in :data:`DESIGN_KEYS` order and the arc range,
    comma-separated (``50,14,50,100,114.5,50,30,centered``)."""
    return ",".join([format_number(getattr(design, k)) for k in DESIGN_KEYS] + [design.eta_range])


def parse_pin(raw: str) -> tuple[Design | None, str | None]:
    """:func:`encode_pin` read back, or ``(None, message)`` naming what is wrong (the same ranges as
    the design fields)."""
    parts = [p.strip() for p in raw.split(",")]
    if len(parts) != len(DESIGN_KEYS) + 1:
        return None, (f"pin = {_quote(raw)} is invalid; expected {len(DESIGN_KEYS)} numbers "
                      f"({', '.join(DESIGN_KEYS)}) and centered or from-zero")
    fields: dict[str, Any] = {}
    for key, text in zip(DESIGN_KEYS, parts):
        v, msg = _parse_number(key, text, DESIGN_RANGES[key], UNITS.get(key, ""))
        if msg:
            return None, f"pin: {msg}"
        fields[key] = v
    try:
        return Design(**fields, eta_range=cast(EtaRange, parts[-1])), None
    except ParameterError as exc:
        return None, f"pin: {exc}"


def check_field(key: str, value: float) -> str | None:
    """The one message for a numeric field outside its accepted range (``None`` when valid)."""
    if key in LINK_FIELDS and key not in TABLE_SETTINGS:  # the input field of the same name (app/schema.py)
        valid = link_number_error(key, value)
        return None if valid is None else f"{key} = {value:g} is out of range; valid range {valid}"
    if key in TABLE_SETTINGS:  # the core table's entry: its range (open or closed) and its text
        spec = TABLE_SETTINGS[key][0][TABLE_SETTINGS[key][1]]
        ok = math.isfinite(value) and spec.contains(value)
        return None if ok else f"{key} = {value:g} is out of range; valid range {spec.range_text()}"
    rng = DESIGN_RANGES.get(key) or POSE_RANGES.get(key) or SETTING_RANGES[key]
    if not (math.isfinite(value) and rng.lo <= value <= rng.hi):
        return f"{key} = {value:g} is out of range; valid range {rng.text(UNITS.get(key, ''))}"
    return None
UNITS: dict[str, str] = {"eta_s": "deg", "psi": "deg", "theta": "deg", "phi": "deg"}

#: Longest quote of a user's value (or key) in a message.
QUOTE_CHARS = 40
#: Most unknown keys named in the one message that reports them.
MAX_NAMED_UNKNOWN = 8


def _cut(raw: str) -> str:
    """``raw`` cut to :data:`QUOTE_CHARS` characters (an ellipsis marks the cut)."""
    return raw if len(raw) <= QUOTE_CHARS else raw[: QUOTE_CHARS - 1] + "…"


def _quote(raw: str) -> str:
    """``repr`` of ``raw`` cut to :data:`QUOTE_CHARS` characters (data, never markup)."""
    return repr(_cut(raw))


@dataclasses.dataclass(frozen=True)
class ExplorerState:
    """Everything a shareable link restores.

    Attributes:
        design: the mechanism's geometry (Table I).
        pose: platform pose ``(x, y, z, psi, theta, phi)``, degrees.
        carriages: ``"auto"`` (redundancy resolved) or ``"manual"`` (``d``/``eta`` below apply).
        d: hand-set radial carriage values ``d_1..d_3`` in ``[0, d_s]`` (used when manual).
        eta: hand-set arc carriage values ``eta_1..eta_3`` in degrees, in the design's arc range.
        voxel: voxel edge ``h`` of the full workspace computation.
        z0: height of the x and y' lines of the orientation maps.
        angle_range: the orientation maps scan angles in ``[-angle_range, angle_range]`` degrees.
        angle_step: angle sample spacing of the orientation maps, degrees.
        view: camera preset.
        cut: whether the shell is cut by a horizontal plane.
        cut_z: height of the cut plane.
        cut_keep: which side of the cut plane stays visible.
        opacity: shell opacity.
        joints: joint cones and leg interference (:mod:`kinematics.joints`).
        pins: the pinned designs shown beside the current one (Compare tab), at most
            :data:`MAX_PINS`; the link writes them in one ``pin`` key, separated by ``;``.
        task: the Task tab's region and orientation set (:class:`TaskLink`), or ``None``.
        mechanism: a preset other than the paper's, or an uploaded description
            (:class:`~app.mechanism_link.MechanismLink`); ``None``: the paper's ``design``.
    """

    design: Design = dataclasses.field(default_factory=Design)
    pose: Pose = dataclasses.field(default_factory=Pose)
    carriages: CarriageMode = "auto"
    d: tuple[float, float, float] = (0.0, 0.0, 0.0)
    eta: tuple[float, float, float] = (0.0, 0.0, 0.0)
    voxel: float = 2.0
    z0: float = 130.0
    angle_range: float = ORIENTATION["angle_range"].default
    angle_step: float = ORIENTATION["angle_step"].default
    view: CameraPreset = "iso"
    cut: bool = False
    cut_z: float = 80.0
    cut_keep: CutKeep = "below"
    opacity: float = 0.6
    joints: Joints = dataclasses.field(default_factory=Joints)
    pins: tuple[Design, ...] = ()
    task: TaskLink | None = None
    mechanism: MechanismLink | None = None

    def replace(self, **changes: Any) -> ExplorerState:
        """A copy with some fields changed (no validation beyond the dataclasses')."""
        return dataclasses.replace(self, **changes)

    def orientation_settings(self) -> OrientationSettings:
        """The settings of this state's orientation maps (z0, scan range and step, joints)."""
        return OrientationSettings(z0=self.z0, angle_range=self.angle_range, angle_step=self.angle_step,
                                   joints=self.joints)


DEFAULT_STATE = ExplorerState()


def _parse_fields(keys, values: dict[str, str], ranges: Mapping[str, Range], messages: list[str]) -> dict[str, float]:
    """:func:`_parse_number` for every ``key`` present in ``values``; bad ones add a message."""
    out: dict[str, float] = {}
    for key in keys:
        if key in values:
            spec = TABLE_SETTINGS[key][0][TABLE_SETTINGS[key][1]] if key in TABLE_SETTINGS else None
            text = spec.range_text() if spec is not None else None  # the table's one message text
            v, msg = _parse_number(key, values[key], ranges[key], UNITS.get(key, ""), range_text=text)
            if spec is not None and v is not None and not msg and not spec.contains(v):
                msg = f"{key} = {_cut(values[key])} is out of range; valid range {text}"  # e.g. open at lo
            if msg:
                messages.append(msg)
            else:
                out[key] = v  # type: ignore[assignment]
    return out


def _parse_number(key: str, raw: str, rng: Range, unit: str = "",
                  range_text: str | None = None) -> tuple[float | None, str | None]:
    """Parse one number and check it lies in ``rng``; returns (value, None) or (None, message)."""
    valid = range_text or rng.text(unit)
    try:
        v = float(raw)
    except ValueError:
        return None, f"{key} = {_quote(raw)} is not a number; valid range {valid}"
    if not math.isfinite(v):
        return None, f"{key} = {_quote(raw)} is not a finite number; valid range {valid}"
    if range_text is None and key in LINK_FIELDS and key not in TABLE_SETTINGS:  # its input field (app/schema.py)
        field_text = link_number_error(key, v)
        if field_text is not None:
            return None, f"{key} = {_cut(raw)} is out of range; valid range {field_text}"
        return (0.0 if v == 0.0 else v), None
    if not (rng.lo <= v <= rng.hi):
        return None, f"{key} = {_cut(raw)} is out of range; valid range {valid}"
    return (0.0 if v == 0.0 else v), None


def _parse_choice(key: str, raw: str, options: tuple[str, ...]) -> tuple[str | None, str | None]:
    if raw in options:
        return raw, None
    return None, f"{key} = {_quote(raw)} is invalid; valid values: {', '.join(options)}"


_BOOL_TRUE = ("1", "true", "on", "yes")
_BOOL_FALSE = ("0", "false", "off", "no")


#: Keys of the explorer's Optimize panel (its run settings; app/optimize_panel.URL_KEYS maps them).
OPT_KEYS: tuple[str, ...] = ("opt_params", "opt_objectives", "opt_constraints", "opt_pop", "opt_gen",
                             "opt_voxel", "opt_seed")


def link_keys() -> tuple[str, ...]:
    """Every key an explorer link may carry: :func:`known_keys` plus the Optimize panel's."""
    return known_keys() + OPT_KEYS


def panel_pairs(query: str) -> dict[str, str]:
    """The Optimize panel's entries of a link (the last of a repeated key; values cut to 200
    characters; the panel validates them and reports bad ones)."""
    try:
        pairs = urllib.parse.parse_qsl((query or "").lstrip("?"), keep_blank_values=True)
    except ValueError:
        return {}
    return {k: v[:200] for k, v in pairs if k in OPT_KEYS}


def known_keys() -> tuple[str, ...]:
    """All query keys the explorer understands, in URL order."""
    return (DESIGN_KEYS + ("eta_range",) + POSE_KEYS + ("carriages",) + D_KEYS + ETA_KEYS
            + ("voxel", "z0", "angle_range", "angle_step", "view", "cut", "cut_z", "cut_keep", "opacity")
            + JOINT_KEYS + ("pin", "task", "mech", "mfile") + param_keys())


def parse_query(query: str) -> tuple[ExplorerState, list[str]]:
    """Parse a URL query (with or without the leading ``?``) into a state and messages.

    Never raises. Every invalid field yields one message naming it and its valid range and keeps
    its default; all other fields apply. See the module docstring.

    Returns:
        ``(state, messages)``; ``messages`` is empty when every field was valid.
    """
    messages: list[str] = []
    try:
        pairs = urllib.parse.parse_qsl((query or "").lstrip("?"), keep_blank_values=True)
    except Exception as exc:  # noqa: BLE001 - parse_qsl is lenient; this is only a safety net
        return DEFAULT_STATE, [f"the link's query could not be read ({exc}); using the defaults"]
    values: dict[str, str] = {}
    known = set(known_keys())
    unknown: list[str] = []
    for key, raw in pairs:
        if key in OPT_KEYS:  # the Optimize panel's (panel_pairs)
            continue
        if key not in known:
            if key not in unknown:
                unknown.append(key)
            continue
        if key in values:
            messages.append(f"{key} is given more than once; the last value ({_quote(raw)}) is used")
        values[key] = raw.strip()
    if unknown:
        named = ", ".join(_quote(k) for k in unknown[:MAX_NAMED_UNKNOWN])
        more = f" and {len(unknown) - MAX_NAMED_UNKNOWN} more" if len(unknown) > MAX_NAMED_UNKNOWN else ""
        messages.append(f"unknown parameter{'s' if len(unknown) > 1 else ''} {named}{more} ignored; "
                        f"known parameters: {', '.join(k for k in known_keys() if k not in param_keys())}, "
                        "mp_NAME (a preset's parameter)")

    # ----- design: per-field ranges, then the model's cross-checks (d_s <= r) ------------------
    design_fields: dict[str, Any] = _parse_fields(DESIGN_KEYS, values, DESIGN_RANGES, messages)
    if "eta_range" in values:
        v, msg = _parse_choice("eta_range", values["eta_range"], ETA_RANGES)
        if msg:
            messages.append(msg)
        else:
            design_fields["eta_range"] = v
    design = Design()
    for _ in range(len(design_fields) + 1):
        try:
            design = Design(**design_fields)
            break
        except ParameterError as exc:
            field = exc.field if exc.field in design_fields else next(iter(design_fields), None)
            shown = format_number(exc.value) if isinstance(exc.value, float) else repr(exc.value)
            messages.append(f"{exc.field} = {shown} is invalid with the other design values; "
                            f"valid range {exc.valid}")
            if field is None:  # pragma: no cover - defaults are always valid
                break
            design_fields.pop(field, None)

    # ----- pose ----------------------------------------------------------------------------------
    pose_fields = _parse_fields(POSE_KEYS, values, POSE_RANGES, messages)
    pose = Pose(**pose_fields)

    # ----- carriages -----------------------------------------------------------------------------
    carriages = DEFAULT_STATE.carriages
    if "carriages" in values:
        v, msg = _parse_choice("carriages", values["carriages"], CARRIAGE_MODES)
        if msg:
            messages.append(msg)
        else:
            carriages = v  # type: ignore[assignment]
    d = list(DEFAULT_STATE.d)
    eta = list(DEFAULT_STATE.eta)
    d_rng = Range(0.0, design.d_s, 0.5)
    e_lo, e_hi = design.eta_limits
    e_rng = Range(e_lo, e_hi, 0.5)
    for i, key in enumerate(D_KEYS):
        if key in values:
            num, msg = _parse_number(key, values[key], d_rng, range_text=f"[0, d_s={design.d_s:g}]")
            if msg or num is None:
                messages.append(msg or key)
            else:
                d[i] = num
    for i, key in enumerate(ETA_KEYS):
        if key in values:
            num, msg = _parse_number(key, values[key], e_rng, range_text=(
                f"[{e_lo:g}, {e_hi:g}] deg (eta_s={design.eta_s:g}, {design.eta_range})"))
            if msg or num is None:
                messages.append(msg or key)
            else:
                eta[i] = num
    # Defaults of d/eta (0) are always inside the strokes.

    # ----- settings and view ------------------------------------------------------------------------
    numbers = _parse_fields(("voxel", "z0", "angle_range", "angle_step", "cut_z", "opacity"), values,
                            SETTING_RANGES, messages)
    view = DEFAULT_STATE.view
    if "view" in values:
        v, msg = _parse_choice("view", values["view"], CAMERA_PRESETS)
        if msg:
            messages.append(msg)
        else:
            view = v  # type: ignore[assignment]
    cut = DEFAULT_STATE.cut
    if "cut" in values:
        raw = values["cut"].lower()
        if raw in _BOOL_TRUE:
            cut = True
        elif raw in _BOOL_FALSE:
            cut = False
        else:
            messages.append(f"cut = {_quote(values['cut'])} is invalid; valid values: 1 (on) or 0 (off)")
    cut_keep = DEFAULT_STATE.cut_keep
    if "cut_keep" in values:
        v, msg = _parse_choice("cut_keep", values["cut_keep"], CUT_KEEPS)
        if msg:
            messages.append(msg)
        else:
            cut_keep = v  # type: ignore[assignment]

    joint_fields: dict[str, Any] = {}
    for key in JOINT_KEYS:
        if key not in values:
            continue
        if key == "cone_axis":
            v, msg = _parse_choice(key, values[key], CONE_AXES)
            if msg:
                messages.append(msg)
            else:
                joint_fields[key] = v
            continue
        try:
            joint_fields[key] = check_joint_value(key, values[key])
        except ParameterError as exc:
            messages.append(f"{key} = {_quote(values[key])} is invalid; valid range {exc.valid}")
    try:
        joints = Joints(**joint_fields)
    except ParameterError as exc:  # e.g. a clearance without a leg diameter
        messages.append(f"{exc.field} = {_quote(str(exc.value))} is invalid; {exc.valid}")
        joint_fields.pop(exc.field, None)
        joints = Joints(**joint_fields)

    pins: list[Design] = []
    if "pin" in values:
        parts = values["pin"].split(";")
        if len(parts) > MAX_PINS:
            messages.append(f"pin = {_quote(values['pin'])} is invalid; at most {MAX_PINS} designs separated by ';' "
                            f"({len(parts)} given; the first {MAX_PINS} are kept)")
        for part in parts[:MAX_PINS]:
            pin, msg = parse_pin(part)
            if msg:
                messages.append(msg)
            elif pin is not None and pin not in pins:
                pins.append(pin)

    task = None
    if "task" in values:
        task, msg = parse_task(values["task"])
        if msg:
            messages.append(msg)

    mechanism, mech_messages = parse_mechanism_pairs(values)
    messages += mech_messages

    state = ExplorerState(
        design=design, pose=pose, carriages=carriages, joints=joints, pins=tuple(pins), task=task,
        mechanism=mechanism,
        d=(float(d[0]), float(d[1]), float(d[2])), eta=(float(eta[0]), float(eta[1]), float(eta[2])),
        voxel=numbers.get("voxel", DEFAULT_STATE.voxel), z0=numbers.get("z0", DEFAULT_STATE.z0),
        angle_range=numbers.get("angle_range", DEFAULT_STATE.angle_range),
        angle_step=numbers.get("angle_step", DEFAULT_STATE.angle_step),
        view=view, cut=cut, cut_z=numbers.get("cut_z", DEFAULT_STATE.cut_z), cut_keep=cut_keep,
        opacity=numbers.get("opacity", DEFAULT_STATE.opacity),
    )
    return state, messages


def encode_pairs(state: ExplorerState) -> list[tuple[str, str]]:
    """The ``(key, value)`` pairs of :func:`encode_query`, in URL order."""
    pairs: list[tuple[str, str]] = []
    for key in DESIGN_KEYS:
        pairs.append((key, format_number(getattr(state.design, key))))
    pairs.append(("eta_range", state.design.eta_range))
    for key in POSE_KEYS:
        pairs.append((key, format_number(getattr(state.pose, key))))
    if state.carriages != DEFAULT_STATE.carriages:
        pairs.append(("carriages", state.carriages))
    if (state.carriages != DEFAULT_STATE.carriages or state.d != DEFAULT_STATE.d
            or state.eta != DEFAULT_STATE.eta):
        pairs += [(k, format_number(v)) for k, v in zip(D_KEYS, state.d)]
        pairs += [(k, format_number(v)) for k, v in zip(ETA_KEYS, state.eta)]
    for key in ("voxel", "z0", "angle_range", "angle_step"):
        if getattr(state, key) != getattr(DEFAULT_STATE, key):
            pairs.append((key, format_number(getattr(state, key))))
    if state.view != DEFAULT_STATE.view:
        pairs.append(("view", state.view))
    if state.cut != DEFAULT_STATE.cut:
        pairs.append(("cut", "1" if state.cut else "0"))
    if state.cut_z != DEFAULT_STATE.cut_z:
        pairs.append(("cut_z", format_number(state.cut_z)))
    if state.cut_keep != DEFAULT_STATE.cut_keep:
        pairs.append(("cut_keep", state.cut_keep))
    if state.opacity != DEFAULT_STATE.opacity:
        pairs.append(("opacity", format_number(state.opacity)))
    if state.pins:
        pairs.append(("pin", ";".join(encode_pin(d) for d in state.pins)))
    if state.task is not None:
        pairs.append(("task", encode_task(state.task)))
    j = state.joints
    for key in JOINT_KEYS:
        v = getattr(j, key)
        if v != getattr(DEFAULT_STATE.joints, key):
            pairs.append((key, v if isinstance(v, str) else format_number(v)))
    return pairs + encode_mechanism(state.mechanism)


def encode_query(state: ExplorerState) -> str:
    """The query string (without ``?``) that :func:`parse_query` turns back into ``state``.

    Design and pose keys are always written; the others only when they differ from their defaults
    (the carriage values whenever ``carriages=manual`` or one is not 0). See the module docstring.
    """
    return urllib.parse.urlencode(encode_pairs(state), safe=",;")
