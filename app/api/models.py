"""Request models of the REST API (pydantic): each field's bounds come from the core's ranges.

Every numeric field registers its valid-range text in :data:`errors.RANGES`, so a 422 names the field
and its range; each model's ``build()`` makes the core object (``Design``, ``Pose``,
``WorkspaceSettings``...), turning the core's ParameterError into a 422 for that field.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, Strict

from paraspace.kinematics.design import PARAMS, Design
from paraspace.kinematics.joints import JOINT_RANGES, Joints
from paraspace.kinematics.pose import POSE_LIMITS, Pose
from paraspace.kinematics.settings import OPTIMIZE, ORIENTATION, WORKSPACE, Setting

from .errors import RANGES, FieldError, call_core


def _rng_text(lo: float, hi: float, unit: str = "", lo_open: bool = False) -> str:
    text = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
    return f"{text} {unit}".rstrip()


def _num(section: str, name: str, default: Any, lo: float, hi: float, description: str, unit: str = "",
         *, lo_open: bool = False) -> Any:
    """A float field with bounds; registers the range text for error messages."""
    text = _rng_text(lo, hi, unit, lo_open)
    RANGES[(section, name)] = text
    bound = {"gt": lo} if lo_open else {"ge": lo}
    return Field(default, le=hi, allow_inf_nan=False, strict=True,
                 description=f"{description}; valid range {text}", **bound)


def _setting(section: str, spec: Setting, strict: bool = True) -> Any:
    """The field of one core table entry (:mod:`kinematics.settings`): its default, bounds, label
    and range text (the one message) all come from the entry."""
    text = spec.range_text()
    RANGES[(section, spec.name)] = text
    bound = {"gt": spec.lo} if spec.lo_open else {"ge": spec.lo}
    extra: dict[str, Any] = {} if spec.integer else {"allow_inf_nan": False}
    return Field(spec.default, le=spec.hi, strict=strict, description=f"{spec.label}; valid range {text}",
                 **bound, **extra)


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


class PoseIn(BaseModel):
    """Platform pose: position of P and Z-Y-X Euler angles in degrees (paper eq. (2))."""

    model_config = _MODEL
    x: float = _num("pose", "x", 0.0, *POSE_LIMITS["x"], "x of the platform centre")
    y: float = _num("pose", "y", 0.0, *POSE_LIMITS["y"], "y of the platform centre")
    z: float = _num("pose", "z", 130.0, *POSE_LIMITS["z"], "z of the platform centre")
    psi: float = _num("pose", "psi", 0.0, *POSE_LIMITS["psi"], "rotation about z", "degrees")
    theta: float = _num("pose", "theta", 0.0, *POSE_LIMITS["theta"], "rotation about y", "degrees")
    phi: float = _num("pose", "phi", 0.0, *POSE_LIMITS["phi"], "rotation about x", "degrees")

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
    return Field(default, le=hi, allow_inf_nan=False, strict=True,
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
            bounds = (tuple(self.bounds.lo), tuple(self.bounds.hi))
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
                                   description="upper end of the z line; null: l_max; valid range [z_min, 10000]")
    s_max: float | None = Field(None, ge=0.0, le=1e4, allow_inf_nan=False,
                                   description="half-length of the x and y' lines; null: derived; valid range [0, 10000]")
    joints: JointsIn = Field(default_factory=JointsIn, description="joint cones and leg interference")

    def build(self) -> Any:
        """The core ``OrientationSettings``."""
        from paraspace.kinematics.orientation import OrientationSettings

        fields = self.model_dump(exclude={"joints"})
        return call_core("orientation", lambda: OrientationSettings(**fields, joints=self.joints.build()))


RANGES[("orientation", "z_max")] = "[z_min, 10000] or null"
RANGES[("orientation", "s_max")] = "[0, 10000] or null"


class IkRequest(BaseModel):
    """Inverse kinematics of one pose; give both ``d`` and ``eta`` to set the carriages by hand,
    neither to resolve the redundancy automatically."""

    model_config = _MODEL
    design: DesignIn = Field(default_factory=DesignIn)
    pose: PoseIn = Field(default_factory=PoseIn)
    d: list[Num] | None = Field(None, min_length=3, max_length=3,
                                     description="carriage strokes d_1..d_3, each in [0, d_s]")
    eta: list[Num] | None = Field(None, min_length=3, max_length=3,
                                       description="arc positions eta_1..eta_3 in degrees, within the arc stroke")
    joints: JointsIn = Field(default_factory=JointsIn, description="joint cones and leg interference")


class WorkspaceRequest(BaseModel):
    """A constant-orientation position workspace."""

    model_config = _MODEL
    design: DesignIn = Field(default_factory=DesignIn)
    settings: WorkspaceSettingsIn = Field(default_factory=WorkspaceSettingsIn)


class OrientationRequest(BaseModel):
    """An orientation workspace (tilt indices TI_1, TI_2 of eq. (28))."""

    model_config = _MODEL
    design: DesignIn = Field(default_factory=DesignIn)
    settings: OrientationSettingsIn = Field(default_factory=OrientationSettingsIn)


def study_settings(settings: WorkspaceSettingsIn, orientation: OrientationSettingsIn | None) -> tuple[Any, Any]:
    """The core ``(WorkspaceSettings, OrientationSettings | None)`` of a study (sweep, optimiser):
    one mechanism, so the joints given in ``settings`` or in ``orientation`` apply to both; given in
    both, they must agree (422 naming ``orientation.joints``)."""
    if orientation is None:
        return settings.build(), None
    given_s, given_o = "joints" in settings.model_fields_set, "joints" in orientation.model_fields_set
    if given_s and given_o and settings.joints != orientation.joints:
        raise FieldError("orientation.joints", "orientation.joints differs from settings.joints: valid values the "
                                               "same joints (or give them once, in settings.joints)")
    joints = orientation.joints if given_o else settings.joints
    return (settings.model_copy(update={"joints": joints}).build(),
            orientation.model_copy(update={"joints": joints}).build())


ParamName = Literal["a", "b", "d_s", "r", "l_min", "l_s", "eta_s"]


class SweepAxis(BaseModel):
    """One swept parameter: explicit ``values`` or ``n`` values spread over its slider range."""

    model_config = _MODEL
    param: ParamName = Field(description="design parameter to vary")
    values: list[Num] | None = Field(None, min_length=1, max_length=10_000,
                                          description="values (each within the parameter's model range)")
    n: int | None = Field(None, ge=1, le=10_000, description="number of values over the slider range")


RANGES[("x", "n")] = RANGES[("y", "n")] = "[1, 10000]"


class SweepRequest(BaseModel):
    """A parameter study: ``x`` alone (1-D) or ``x`` and ``y`` (2-D); each point is a workspace
    (plus the orientation indices when ``orientation`` is given)."""

    model_config = _MODEL
    design: DesignIn = Field(default_factory=DesignIn)
    settings: WorkspaceSettingsIn = Field(default_factory=lambda: WorkspaceSettingsIn(voxel=4.0))
    x: SweepAxis
    y: SweepAxis | None = None
    orientation: OrientationSettingsIn | None = Field(
        None, description="orientation sampling for TI_1/TI_2; its joints are settings.joints when not given here")


class OptimizeRequest(BaseModel):
    """A multi-objective optimisation (``kinematics.optimize``): the Pareto front of ``objectives``
    over the free ``params``; each evaluation is a workspace (plus the orientation indices when an
    objective or constraint needs TI_1/TI_2)."""

    model_config = _MODEL
    design: DesignIn = Field(default_factory=DesignIn, description="base design; non-free fields stay fixed")
    settings: WorkspaceSettingsIn = Field(default_factory=lambda: WorkspaceSettingsIn(voxel=4.0))
    params: list[ParamName] = Field(default_factory=lambda: ["a", "d_s", "eta_s", "l_s"], min_length=1,
                                    max_length=7, description="free design parameters")
    bounds: dict[ParamName, tuple[float, float]] = Field(
        default_factory=dict, description="{param: [lo, hi]} for some free parameters; others: Table I's range")
    objectives: list[str] = Field(default_factory=lambda: ["volume", "-footprint"], min_length=1, max_length=8,
                                  description="measures; a leading - minimises (kinematics.optimize.MEASURES)")
    constraints: list[str] = Field(default_factory=list, max_length=8,
                                   description="flags (boundary_complete) or MEASURE>=V / MEASURE<=V")
    population: int = _setting("body", OPTIMIZE["population"], strict=False)
    generations: int = _setting("body", OPTIMIZE["generations"], strict=False)
    seed: int = _setting("body", OPTIMIZE["seed"], strict=False)
    step: float = _setting("body", OPTIMIZE["step"], strict=False)
    algorithm: Literal["auto", "nsga2", "nsga3", "agemoea"] = Field("auto")
    orientation: OrientationSettingsIn | None = Field(
        None, description="orientation sampling for TI_1/TI_2 (null: the defaults, used only when needed); "
                          "its joints are settings.joints when not given here")

    def build(self) -> Any:
        """The core ``OptimizeSettings`` (its ParameterError names the field: 422)."""
        from paraspace.kinematics.optimize import OptimizeSettings

        for text in self.objectives + self.constraints:
            if len(text) > 100:
                raise FieldError("objectives", f"{text[:40]!r}... is invalid: at most 100 characters per entry")
        workspace, orientation = study_settings(self.settings, self.orientation)
        return OptimizeSettings(
            params=tuple(self.params), bounds=dict(self.bounds), objectives=list(self.objectives),
            constraints=list(self.constraints), design=self.design.build(), workspace=workspace,
            orientation=orientation,
            population=self.population, generations=self.generations, seed=self.seed, step=self.step,
            algorithm=self.algorithm)




class LinkRequest(BaseModel):
    """An explorer state as a URL query string (the part after ``?``)."""

    model_config = _MODEL
    query: str = Field(max_length=4096, description="explorer URL query, e.g. a=60&z=120")

