"""The pydantic models of the tool's inputs, one field per setting, derived from the core's tables.

The REST API's request bodies (:mod:`paraspace.app.api.models` builds its requests from these
models) and the explorer's link state (:func:`paraspace.app.urlstate.parse_query` validates every
numeric link key with the field of the same name here: :data:`LINK_FIELDS`) are the same fields:
one bound, one range text, one message. Every numeric field registers its valid-range text in
:data:`RANGES` (``(section, field) -> text``), which the API's 422 messages and the link parser
read. Each model's ``build()`` makes the core object (``Design``, ``Pose``, ``WorkspaceSettings``...),
turning the core's ParameterError into a :class:`FieldError` for that field.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, Strict, TypeAdapter, ValidationError

from paraspace.kinematics.design import PARAMS, Design, ParameterError
from paraspace.kinematics.joints import JOINT_RANGES, Joints
from paraspace.kinematics.pose import POSE_LIMITS, Pose
from paraspace.kinematics.settings import ORIENTATION, WORKSPACE, Setting

#: (section, field) -> valid range text used in 422 messages and link messages.
RANGES: dict[tuple[str, str], str] = {}


class FieldError(Exception):
    """Bad input in one field: answered with 422 ``{"detail": [{"field", "message"}]}``."""

    def __init__(self, field: str, message: str) -> None:
        self.field, self.message = field, message
        super().__init__(message)


def call_core(section: str, build: Callable[[], Any]) -> Any:
    """Run a core constructor, turning its ParameterError into a FieldError under ``section``."""
    try:
        return build()
    except ParameterError as e:
        raise FieldError(f"{section}.{e.field}", str(e)) from None


#: pydantic's ``Field`` called with bounds built at run time (its typed overloads take literals only).
_field: Callable[..., Any] = Field


def _rng_text(lo: float, hi: float, unit: str = "", lo_open: bool = False) -> str:
    text = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
    return f"{text} {unit}".rstrip()


def _num(section: str, name: str, default: Any, lo: float, hi: float, description: str, unit: str = "",
         *, lo_open: bool = False) -> Any:
    """A float field with bounds; registers the range text for error messages."""
    text = _rng_text(lo, hi, unit, lo_open)
    RANGES[(section, name)] = text
    return Field(default, le=hi, allow_inf_nan=False, strict=True, description=f"{description}; valid range {text}",
                 gt=lo if lo_open else None, ge=None if lo_open else lo)


def _setting(section: str, spec: Setting, strict: bool = True) -> Any:
    """The field of one core table entry (:mod:`kinematics.settings`): its default, bounds, label
    and range text (the one message) all come from the entry."""
    text = spec.range_text()
    RANGES[(section, spec.name)] = text
    kwargs: dict[str, Any] = {"gt": spec.lo} if spec.lo_open else {"ge": spec.lo}
    if not spec.integer:
        kwargs["allow_inf_nan"] = False
    return _field(spec.default, le=spec.hi, strict=strict, description=f"{spec.label}; valid range {text}",
                  **kwargs)


_MODEL = ConfigDict(extra="forbid")
#: A number field: a JSON number only (``true`` or ``"3"`` is not a length; an integer is).
Num = Annotated[float, Strict()]


class DesignIn(BaseModel):
    """Design parameters (paper Table I); omitted fields take the paper's Fig. 3 values."""

    model_config = _MODEL
    a: float = _num("design", "a", PARAMS["a"].default, PARAMS["a"].model_min, PARAMS["a"].model_max,
                    PARAMS["a"].description)
    b: float = _num("design", "b", PARAMS["b"].default, PARAMS["b"].model_min, PARAMS["b"].model_max,
                    PARAMS["b"].description)
    d_s: float = _num("design", "d_s", PARAMS["d_s"].default, PARAMS["d_s"].model_min, PARAMS["d_s"].model_max,
                      PARAMS["d_s"].description + " (also d_s <= r)")
    r: float = _num("design", "r", PARAMS["r"].default, PARAMS["r"].model_min, PARAMS["r"].model_max,
                    PARAMS["r"].description)
    l_min: float = _num("design", "l_min", PARAMS["l_min"].default, PARAMS["l_min"].model_min,
                        PARAMS["l_min"].model_max, PARAMS["l_min"].description)
    l_s: float = _num("design", "l_s", PARAMS["l_s"].default, PARAMS["l_s"].model_min, PARAMS["l_s"].model_max,
                      PARAMS["l_s"].description)
    eta_s: float = _num("design", "eta_s", PARAMS["eta_s"].default, PARAMS["eta_s"].model_min,
                        PARAMS["eta_s"].model_max, PARAMS["eta_s"].description, "degrees")
    eta_range: Literal["centered", "from-zero"] = Field(
        "centered", description="where the arc stroke starts: centered on gamma_i or from zero")

    def build(self) -> Design:
        """The core :class:`Design` (cross-field checks such as ``d_s <= r`` happen here)."""
        return call_core("design", lambda: Design(**self.model_dump()))


def _pose(name: str, default: float, description: str, unit: str = "") -> Any:
    """A pose field: its bounds are :data:`kinematics.pose.POSE_LIMITS`'s."""
    lo, hi = POSE_LIMITS[name]
    return _num("pose", name, default, lo, hi, description, unit)


class PoseIn(BaseModel):
    """Platform pose: position of P and Z-Y-X Euler angles in degrees (paper eq. (2))."""

    model_config = _MODEL
    x: float = _pose("x", 0.0, "x of the platform centre")
    y: float = _pose("y", 0.0, "y of the platform centre")
    z: float = _pose("z", 130.0, "z of the platform centre")
    psi: float = _pose("psi", 0.0, "rotation about z", "degrees")
    theta: float = _pose("theta", 0.0, "rotation about y", "degrees")
    phi: float = _pose("phi", 0.0, "rotation about x", "degrees")

    def build(self) -> Pose:
        """The core :class:`Pose`."""
        return call_core("pose", lambda: Pose(**self.model_dump()))


class AnglesIn(BaseModel):
    """A constant platform orientation (Z-Y-X Euler angles, degrees)."""

    model_config = _MODEL
    psi: float = _num("orientation", "psi", 0.0, -180.0, 180.0, "rotation about z", "degrees")
    theta: float = _num("orientation", "theta", 0.0, -90.0, 90.0, "rotation about y", "degrees")
    phi: float = _num("orientation", "phi", 0.0, -180.0, 180.0, "rotation about x", "degrees")


class BoundsIn(BaseModel):
    """An explicit box ``lo < hi`` on each of x, y, z."""

    model_config = _MODEL
    lo: tuple[Num, Num, Num] = Field(description="lower corner (x, y, z); each in [-10000, 10000]")
    hi: tuple[Num, Num, Num] = Field(description="upper corner (x, y, z); each in [-10000, 10000]")


RANGES[("bounds", "lo")] = RANGES[("bounds", "hi")] = "[-10000, 10000] on each of x, y, z, lo < hi"


def _joint_field(name: str, default: Any, description: str, optional: bool = False) -> Any:
    lo, hi, lo_open, text = JOINT_RANGES[name]
    RANGES[("joints", name)] = text + (" or null (no limit)" if optional else "")
    bound = {"gt": lo} if lo_open else {"ge": lo}
    return _field(default, le=hi, allow_inf_nan=False, strict=True,
                  description=f"{description}; valid range {RANGES[('joints', name)]}", **bound)


class JointsIn(BaseModel):
    """Passive-joint cones and leg interference (``kinematics.joints``); defaults: the paper's model."""

    model_config = _MODEL
    theta_u: float | None = _joint_field("theta_u", None, "half-angle of every U joint's cone, degrees", True)
    theta_s: float | None = _joint_field("theta_s", None, "half-angle of every S joint's cone, degrees", True)
    cone_axis: Literal["normal", "home"] = Field("normal", description="cone axes: base/platform normal or the "
                                                 "legs' home directions")
    leg_diameter: float = _joint_field("leg_diameter", 0.0, "legs are capsules of this diameter (0: no interference)")
    clearance: float = _joint_field("clearance", 0.0, "extra distance required between legs")

    def build(self) -> Any:
        """The core ``Joints``."""
        return call_core("joints", lambda: Joints(**self.model_dump()))


class WorkspaceSettingsIn(BaseModel):
    """How the position workspace is sampled (see ``kinematics.workspace.WorkspaceSettings``)."""

    model_config = _MODEL
    voxel: float = _setting("settings", WORKSPACE["voxel"])
    orientation: AnglesIn = Field(default_factory=AnglesIn, description="constant platform orientation")
    eta_step: float = _setting("settings", WORKSPACE["eta_step"])
    bounds: BoundsIn | None = Field(None, description="explicit box; null derives it from the design")
    z_floor: float = _setting("settings", WORKSPACE["z_floor"])
    symmetry: bool = Field(True, description="use the y -> -y mirror symmetry when it holds exactly")
    diagnostics: bool = Field(False, description="evaluate every chain at every voxel (slower)")
    method: Literal["blocks", "dense"] = Field("blocks", description="engine: coarse-to-fine blocks (default) "
                                               "or every voxel (dense); the same voxels")
    bracket: bool = Field(False, description="also certify volume_inner <= V <= volume_outer (continuous workspace)")
    bracket_refine: int = _setting("settings", WORKSPACE["bracket_refine"])
    joints: JointsIn = Field(default_factory=JointsIn, description="joint cones and leg interference")

    def build(self) -> Any:
        """The core ``WorkspaceSettings``."""
        from paraspace.kinematics.workspace import WorkspaceSettings

        o = self.orientation
        bounds = None
        if self.bounds is not None:
            for corner in ("lo", "hi"):
                for axis, v in zip("xyz", getattr(self.bounds, corner)):
                    if not (math.isfinite(v) and -1e4 <= v <= 1e4):
                        raise FieldError(f"settings.bounds.{corner}",
                                         f"bounds.{corner}.{axis} = {v!r} is invalid: valid range [-10000, 10000]")
            lo, hi = self.bounds.lo, self.bounds.hi
            bounds = ((lo[0], lo[1], lo[2]), (hi[0], hi[1], hi[2]))
        return call_core("settings", lambda: WorkspaceSettings(
            voxel=self.voxel, orientation=(o.psi, o.theta, o.phi), eta_step=self.eta_step, bounds=bounds,
            z_floor=self.z_floor, symmetry=self.symmetry, diagnostics=self.diagnostics, method=self.method,
            bracket=self.bracket, bracket_refine=self.bracket_refine, joints=self.joints.build()))


class OrientationSettingsIn(BaseModel):
    """Orientation workspace along the z, y' and x lines (see ``kinematics.orientation``)."""

    model_config = _MODEL
    z0: float = _setting("orientation", ORIENTATION["z0"])
    angle_range: float = _setting("orientation", ORIENTATION["angle_range"])
    angle_step: float = _setting("orientation", ORIENTATION["angle_step"])
    position_step: float = _setting("orientation", ORIENTATION["position_step"])
    delta: Literal["extent", "area"] = Field("extent", description="Δ of eq. (28): extent products or area")
    region: Literal["all", "connected"] = Field("all", description="feasible samples counted")
    position_delta: Literal["per_region", "line", "phi"] = Field(
        "per_region", description="position Δ: each region's own, the union of a line's regions, or one per line "
                                  "from the φ region (the literal eq. (28))")
    eta_step: float = _setting("orientation", ORIENTATION["eta_step"])
    z_min: float = _setting("orientation", ORIENTATION["z_min"])
    z_max: float | None = Field(None, ge=-1e4, le=1e4, allow_inf_nan=False,
                                   description="upper end of the z line; null: a rigorous cover (l_max for the paper's "
                                               "design, the chains' reach for a mechanism); valid range [z_min, 10000]")
    s_max: float | None = Field(None, ge=0.0, le=1e4, allow_inf_nan=False,
                                   description="half-length of the x and y' lines; null: derived; "
                                               "valid range [0, 10000]")
    joints: JointsIn = Field(default_factory=JointsIn, description="joint cones and leg interference")

    def build(self) -> Any:
        """The core ``OrientationSettings``."""
        from paraspace.kinematics.orientation import OrientationSettings

        fields = self.model_dump(exclude={"joints"})
        return call_core("orientation", lambda: OrientationSettings(**fields, joints=self.joints.build()))


RANGES[("orientation", "z_max")] = "[z_min, 10000] or null"
RANGES[("orientation", "s_max")] = "[0, 10000] or null"




#: The explorer's numeric link keys and the input field each is validated with:
#: ``key -> (model, section)`` (the link ``?a=60`` and the body ``{"design": {"a": 60}}`` meet the
#: same :class:`DesignIn` field ``a``).
LINK_FIELDS: dict[str, tuple[type[BaseModel], str]] = {
    **{k: (DesignIn, "design") for k in PARAMS},
    **{k: (PoseIn, "pose") for k in POSE_LIMITS},
    "voxel": (WorkspaceSettingsIn, "settings"),
    **{k: (OrientationSettingsIn, "orientation") for k in ("z0", "angle_range", "angle_step")},
    **{k: (JointsIn, "joints") for k in JOINT_RANGES},
}
_ADAPTERS: dict[str, TypeAdapter] = {}


def link_range_text(key: str) -> str:
    """The valid-range text of the link key ``key`` (the same as its REST field's)."""
    model, section = LINK_FIELDS[key]
    return RANGES[(section, key)]


def link_number_error(key: str, value: float) -> str | None:
    """``None`` if ``value`` is valid for the link key ``key`` by its input field (the REST model's
    field of the same name: bounds, finiteness), else that field's valid-range text."""
    adapter = _ADAPTERS.get(key)
    if adapter is None:
        model, _section = LINK_FIELDS[key]
        info = model.model_fields[key]
        field_type: Any = Annotated[info.annotation, info]  # the model field, bounds included
        adapter = _ADAPTERS[key] = TypeAdapter(field_type)
    try:
        adapter.validate_python(value)
    except ValidationError:
        return link_range_text(key)
    return None
