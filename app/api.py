"""Versioned REST API of paraspace (FastAPI), served beside the viser explorer.

Everything lives under ``/api/v1`` (OpenAPI docs at ``/docs``, schema at ``/openapi.json``):

==========================================  ===================================================
``GET  /api/v1/health``                     liveness, job counts, limits
``GET  /api/v1/design/defaults``            design fields, defaults, model and slider ranges
``POST /api/v1/ik``                         pose (+ optional carriages ``d``, ``eta``) -> IK
``POST /api/v1/workspace``                  design + settings -> job (``?wait=s`` to block)
``GET  /api/v1/workspace/{id}``             the workspace's measures (when done)
``GET  /api/v1/workspace/{id}/shell.{fmt}`` its boundary surface as stl, ply, obj or glb
``POST /api/v1/orientation``                orientation workspace / tilt indices -> job
``POST /api/v1/sweep``                      1-D or 2-D parameter study -> job
``POST /api/v1/optimize``                   multi-objective optimisation (Pareto front) -> job
``GET  /api/v1/jobs``                       the caller's unfinished jobs
``GET  /api/v1/jobs/{id}``                  status and progress of a job
``DELETE /api/v1/jobs/{id}``                cancel a job
``GET  /api/v1/jobs/{id}/result``           the result of a finished job
``POST /api/v1/links``                      make a short link to an explorer state
``GET  /s?{query}``, ``GET /s/{token}``     307 redirect to the explorer with that state
==========================================  ===================================================

Errors are JSON. Bad input gets **422** with ``{"detail": [{"field": "design.a", "message": "a = -5
is invalid: valid range [1e-06, 1000]"}]}`` (request validation and the core's
:class:`~kinematics.design.ParameterError` alike). Requests over a resource limit get **413**
(too big: voxels, sweep points, orientation samples, body size) or **429** (too many unfinished
jobs; with ``Retry-After``), before anything runs: nothing is queued without bound. A failing job
ends ``failed`` with a one-line error and the server stays healthy.

Finished results are cached by (design, settings) in a small LRU: repeating a request is instant.
"""

from __future__ import annotations

import asyncio
import base64
import collections
import contextlib
import dataclasses
import errno
import json
import logging
import math
import threading
import time
import urllib.parse
import zlib
from typing import Annotated, Any, Callable, Hashable, Literal, Optional, Union

import numpy as np
from fastapi import APIRouter, FastAPI, Path, Query, Request
from fastapi.exceptions import RequestValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException
from fastapi.responses import JSONResponse, RedirectResponse, Response
from starlette.concurrency import run_in_threadpool
from pydantic import BaseModel, ConfigDict, Field, Strict

import paraspace
from paraspace.kinematics.design import ETA_RANGES, PARAMS, Design, ParameterError
from paraspace.kinematics.joints import JOINT_RANGES, Joints
from paraspace.kinematics.pose import POSE_LIMITS, Pose
from paraspace.kinematics.serialize import jsonable

from .bytecache import ByteLRU
from .jobs import Job, JobManager, LimitExceeded
from .limits import MAX_VOXELS, check_workspace_grid, orientation_samples, workspace_voxels

__all__ = ["ApiLimits", "create_api", "API_PREFIX", "encode_link_token", "decode_link_token"]

log = logging.getLogger(__name__)

API_PREFIX = "/api/v1"
API_VERSION = paraspace.__version__  # the package metadata, stated once (pyproject.toml)
CLIENT_PREFIX = "api:"


# ================================================================================================
# limits


@dataclasses.dataclass(frozen=True)
class ApiLimits:
    """Resource limits of the API, checked before any work is queued.

    Attributes:
        max_voxels: voxels of one workspace grid (computed from the bounds and the voxel edge
            before running; for default bounds the design's derived box). Over it: 413.
        max_sweep_points: design points of one sweep (1-D length, or the 2-D product). Over: 413.
        max_sweep_voxels: voxels summed over a sweep's points (each point's analytical reach box,
            an upper bound). Over it: 413.
        max_orientation_samples: position x angle samples of an orientation request (3 lines x
            3 rotations), per design point. Over it: 413.
        max_jobs_per_client: unfinished API jobs per client. Over it: 429.
        max_jobs_total: unfinished API jobs over all clients. Over it: 429.
        max_job_seconds: run time of one job; after it the job is stopped and reported failed.
        max_body_bytes: size of a request body. Over it: 413.
        max_shell_faces: largest ``max_faces`` accepted for shell downloads.
        client_header: take the client identity from this request header (set it only behind a
            proxy you control that overwrites the header); ``None``: the connection's peer address
            (which uvicorn takes from X-Forwarded-For only for ``paraspace serve --trusted-proxy``).
        cache_bytes: finished results kept per kind (workspace, orientation, sweep, optimize), in
            bytes (estimated, voxel grids included).
        shell_cache_bytes: exported shell files kept for repeated downloads, in bytes.
        max_optimize_evaluations: population x generations of one optimisation. Over it: 413.
        max_optimize_voxels: evaluations x the voxels of the largest design in the bounds (the
            analytical reach box at every corner of the parameter box, an upper bound). Over: 413.
    """

    max_voxels: int = MAX_VOXELS
    max_sweep_points: int = 64
    max_sweep_voxels: int = 200_000_000
    max_orientation_samples: int = 20_000_000
    max_jobs_per_client: int = 4
    max_jobs_total: int = 16
    max_job_seconds: float = 300.0
    max_body_bytes: int = 262_144
    max_shell_faces: int = 2_000_000
    client_header: Optional[str] = None
    cache_bytes: int = 256 << 20
    shell_cache_bytes: int = 128 << 20
    # --- optimisation (issue 11) ---
    max_optimize_evaluations: int = 2000
    max_optimize_voxels: int = 4_000_000_000

    def to_dict(self) -> dict[str, Any]:
        """JSON form (reported by ``/health``)."""
        return dataclasses.asdict(self)


# ================================================================================================
# request models: field constraints derived from the core's ranges

#: (section, field) -> valid range text used in 422 messages.
_RANGES: dict[tuple[str, str], str] = {}


def _rng_text(lo: float, hi: float, unit: str = "", lo_open: bool = False) -> str:
    text = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
    return f"{text} {unit}".rstrip()


def _num(section: str, name: str, default: Any, lo: float, hi: float, description: str, unit: str = "",
         *, lo_open: bool = False) -> Any:
    """A float field with bounds; registers the range text for error messages."""
    text = _rng_text(lo, hi, unit, lo_open)
    _RANGES[(section, name)] = text
    bound = {"gt": lo} if lo_open else {"ge": lo}
    return Field(default, le=hi, allow_inf_nan=False, strict=True,
                 description=f"{description}; valid range {text}", **bound)


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
        return _core("design", lambda: Design(**self.model_dump()))


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
        return _core("pose", lambda: Pose(**self.model_dump()))


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


_RANGES[("bounds", "lo")] = _RANGES[("bounds", "hi")] = "[-10000, 10000] on each of x, y, z, lo < hi"
_RANGES[("settings", "bracket_refine")] = "[0, 3]"


def _joint_field(name: str, default: Any, description: str, optional: bool = False) -> Any:
    lo, hi, lo_open, text = JOINT_RANGES[name]
    _RANGES[("joints", name)] = text + (" or null (no limit)" if optional else "")
    bound = {"gt": lo} if lo_open else {"ge": lo}
    return Field(default, le=hi, allow_inf_nan=False, strict=True,
                 description=f"{description}; valid range {_RANGES[('joints', name)]}", **bound)


class JointsIn(BaseModel):
    """Passive-joint cones and leg interference (``kinematics.joints``); defaults: the paper's model."""

    model_config = _MODEL
    theta_u: Optional[float] = _joint_field("theta_u", None, "half-angle of every U joint's cone, degrees", True)
    theta_s: Optional[float] = _joint_field("theta_s", None, "half-angle of every S joint's cone, degrees", True)
    cone_axis: Literal["normal", "home"] = Field("normal", description="cone axes: base/platform normal or the "
                                                 "legs' home directions")
    leg_diameter: float = _joint_field("leg_diameter", 0.0, "legs are capsules of this diameter (0: no interference)")
    clearance: float = _joint_field("clearance", 0.0, "extra distance required between legs")

    def build(self) -> Any:
        """The core ``Joints``."""
        return _core("joints", lambda: Joints(**self.model_dump()))


class WorkspaceSettingsIn(BaseModel):
    """How the position workspace is sampled (see ``kinematics.workspace.WorkspaceSettings``)."""

    model_config = _MODEL
    voxel: float = _num("settings", "voxel", 2.0, 0.25, 100.0, "voxel edge h")
    orientation: AnglesIn = Field(default_factory=AnglesIn, description="constant platform orientation")
    eta_step: float = _num("settings", "eta_step", 0.5, 0.01, 10.0, "arc-stroke sample spacing", "degrees")
    bounds: Optional[BoundsIn] = Field(None, description="explicit box; null derives it from the design")
    z_floor: float = _num("settings", "z_floor", 0.0, -1e4, 1e4, "lowest platform height of derived bounds")
    symmetry: bool = Field(True, description="use the y -> -y mirror symmetry when it holds exactly")
    diagnostics: bool = Field(False, description="evaluate every chain at every voxel (slower)")
    method: Literal["blocks", "dense"] = Field("blocks", description="engine: coarse-to-fine blocks (default) "
                                               "or every voxel (dense); the same voxels")
    bracket: bool = Field(False, description="also certify volume_inner <= V <= volume_outer (continuous workspace)")
    bracket_refine: int = Field(2, ge=0, le=3, strict=True, description="halvings of the bracket's boundary "
                                "cubes; valid range [0, 3]")
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
        return _core("settings", lambda: WorkspaceSettings(
            voxel=self.voxel, orientation=(o.psi, o.theta, o.phi), eta_step=self.eta_step, bounds=bounds,
            z_floor=self.z_floor, symmetry=self.symmetry, diagnostics=self.diagnostics, method=self.method,
            bracket=self.bracket, bracket_refine=self.bracket_refine, joints=self.joints.build()))


class OrientationSettingsIn(BaseModel):
    """Orientation workspace along the z, y' and x lines (see ``kinematics.orientation``)."""

    model_config = _MODEL
    z0: float = _num("orientation", "z0", 130.0, -1e4, 1e4, "height of the x and y' lines")
    angle_range: float = _num("orientation", "angle_range", 90.0, 0.0, 180.0,
                              "angles scanned in [-angle_range, angle_range]", "degrees", lo_open=True)
    angle_step: float = _num("orientation", "angle_step", 0.5, 0.01, 30.0, "angle sample spacing", "degrees")
    position_step: float = _num("orientation", "position_step", 1.0, 0.01, 100.0, "position sample spacing")
    delta: Literal["extent", "area"] = Field("extent", description="Δ of eq. (28): extent products or area")
    region: Literal["all", "connected"] = Field("all", description="feasible samples counted")
    position_delta: Literal["per_region", "line", "phi"] = Field(
        "per_region", description="position Δ: each region's own, the union of a line's regions, or one per line "
                                  "from the φ region (the literal eq. (28))")
    eta_step: float = _num("orientation", "eta_step", 0.5, 0.01, 10.0, "arc-stroke sample spacing", "degrees")
    z_min: float = _num("orientation", "z_min", 0.0, -1e4, 1e4, "lower end of the z line")
    z_max: Optional[float] = Field(None, ge=-1e4, le=1e4, allow_inf_nan=False,
                                   description="upper end of the z line; null: l_max; valid range [z_min, 10000]")
    s_max: Optional[float] = Field(None, ge=0.0, le=1e4, allow_inf_nan=False,
                                   description="half-length of the x and y' lines; null: derived; valid range [0, 10000]")
    joints: JointsIn = Field(default_factory=JointsIn, description="joint cones and leg interference")

    def build(self) -> Any:
        """The core ``OrientationSettings``."""
        from paraspace.kinematics.orientation import OrientationSettings

        fields = self.model_dump(exclude={"joints"})
        return _core("orientation", lambda: OrientationSettings(**fields, joints=self.joints.build()))


_RANGES[("orientation", "z_max")] = "[z_min, 10000] or null"
_RANGES[("orientation", "s_max")] = "[0, 10000] or null"


class IkRequest(BaseModel):
    """Inverse kinematics of one pose; give both ``d`` and ``eta`` to set the carriages by hand,
    neither to resolve the redundancy automatically."""

    model_config = _MODEL
    design: DesignIn = Field(default_factory=DesignIn)
    pose: PoseIn = Field(default_factory=PoseIn)
    d: Optional[list[Num]] = Field(None, min_length=3, max_length=3,
                                     description="carriage strokes d_1..d_3, each in [0, d_s]")
    eta: Optional[list[Num]] = Field(None, min_length=3, max_length=3,
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


ParamName = Literal["a", "b", "d_s", "r", "l_min", "l_s", "eta_s"]


class SweepAxis(BaseModel):
    """One swept parameter: explicit ``values`` or ``n`` values spread over its slider range."""

    model_config = _MODEL
    param: ParamName = Field(description="design parameter to vary")
    values: Optional[list[Num]] = Field(None, min_length=1, max_length=10_000,
                                          description="values (each within the parameter's model range)")
    n: Optional[int] = Field(None, ge=1, le=10_000, description="number of values over the slider range")


_RANGES[("x", "n")] = _RANGES[("y", "n")] = "[1, 10000]"


class SweepRequest(BaseModel):
    """A parameter study: ``x`` alone (1-D) or ``x`` and ``y`` (2-D); each point is a workspace
    (plus the orientation indices when ``orientation`` is given)."""

    model_config = _MODEL
    design: DesignIn = Field(default_factory=DesignIn)
    settings: WorkspaceSettingsIn = Field(default_factory=lambda: WorkspaceSettingsIn(voxel=4.0))
    x: SweepAxis
    y: Optional[SweepAxis] = None
    orientation: Optional[OrientationSettingsIn] = None


# ----- optimisation (issue 11): request model, limits check, compute --------------------------


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
    population: int = Field(16, ge=4, le=1000, description="designs per generation; valid range [4, 1000]")
    generations: int = Field(12, ge=1, le=1000, description="generations; valid range [1, 1000]")
    seed: int = Field(1, ge=0, le=2**32 - 1, description="random seed; valid range [0, 4294967295]")
    step: float = Field(0.01, ge=1e-6, le=10.0, allow_inf_nan=False,
                        description="parameter resolution; valid range [1e-06, 10]")
    algorithm: Literal["auto", "nsga2", "nsga3", "agemoea"] = Field("auto")
    orientation: Optional[OrientationSettingsIn] = Field(
        None, description="orientation sampling for TI_1/TI_2 (null: the defaults, used only when needed)")

    def build(self) -> Any:
        """The core ``OptimizeSettings`` (its ParameterError names the field: 422)."""
        from paraspace.kinematics.optimize import OptimizeSettings

        for text in self.objectives + self.constraints:
            if len(text) > 100:
                raise FieldError("objectives", f"{text[:40]!r}... is invalid: at most 100 characters per entry")
        return OptimizeSettings(
            params=tuple(self.params), bounds=dict(self.bounds), objectives=list(self.objectives),
            constraints=list(self.constraints), design=self.design.build(), workspace=self.settings.build(),
            orientation=None if self.orientation is None else self.orientation.build(),
            population=self.population, generations=self.generations, seed=self.seed, step=self.step,
            algorithm=self.algorithm)


_RANGES[("body", "population")] = "[4, 1000]"
_RANGES[("body", "generations")] = "[1, 1000]"


def optimize_limits_check(settings: Any, limits: "ApiLimits") -> None:
    """413 when the run is over ``max_optimize_evaluations`` or ``max_optimize_voxels`` (see
    :class:`ApiLimits`), or when one orientation evaluation is over ``max_orientation_samples``."""
    import itertools

    n_eval = settings.population * settings.generations
    if n_eval > limits.max_optimize_evaluations:
        raise ApiError(413, f"optimisation of {n_eval} evaluations (population x generations) exceeds the limit "
                            f"max_optimize_evaluations = {limits.max_optimize_evaluations}")
    per_design = 0
    n_ori = 0
    ori = settings.orientation_used
    for corner in itertools.product(*[settings.bounds_of(p) for p in settings.params]):
        try:
            d = settings.design.replace(**dict(zip(settings.params, corner)))
        except ParameterError:
            continue  # an invalid corner (d_s > r) is never evaluated
        per_design = max(per_design, workspace_voxels(d, settings.workspace, analytic=True))
        if ori is not None:
            n_ori = max(n_ori, orientation_samples(d, ori))
    total = per_design * n_eval
    if total > limits.max_optimize_voxels:
        raise ApiError(413, f"optimisation of up to {total} voxels in all ({n_eval} evaluations x {per_design} "
                            f"voxels of the largest design) exceeds the limit max_optimize_voxels = "
                            f"{limits.max_optimize_voxels}: use a larger voxel (now {settings.workspace.voxel:g}), "
                            f"a smaller population or fewer generations")
    if n_ori > limits.max_orientation_samples:
        raise ApiError(413, f"orientation part of {n_ori} samples per design exceeds the limit "
                            f"max_orientation_samples = {limits.max_orientation_samples}")


def optimize_compute(settings: Any, progress: Any, cancel: Any, cache: Any = None) -> "ApiResult":
    """Run the optimisation in this process (the job's thread); the payload is
    ``OptimizeResult.to_dict()`` (``front``, ``hypervolume`` per generation, ``settings``...)."""
    from paraspace.kinematics.optimize import optimize

    res = optimize(settings, cache=cache, progress=progress, cancel=cancel)
    return ApiResult(raw=None, payload=jsonable(res.to_dict()))


class LinkRequest(BaseModel):
    """An explorer state as a URL query string (the part after ``?``)."""

    model_config = _MODEL
    query: str = Field(max_length=4096, description="explorer URL query, e.g. a=60&z=120")


# ================================================================================================
# errors


class FieldError(Exception):
    """Bad input in one field: answered with 422 ``{"detail": [{"field", "message"}]}``."""

    def __init__(self, field: str, message: str) -> None:
        self.field, self.message = field, message
        super().__init__(message)


class ApiError(Exception):
    """An HTTP error with a plain-text ``detail`` (413, 404, 409, 429, ...)."""

    def __init__(self, status: int, detail: str, headers: Optional[dict[str, str]] = None) -> None:
        self.status, self.detail, self.headers = status, detail, headers
        super().__init__(detail)


def _core(section: str, build: Callable[[], Any]) -> Any:
    """Run a core constructor, turning its ParameterError into a FieldError under ``section``."""
    try:
        return build()
    except ParameterError as e:
        raise FieldError(f"{section}.{e.field}", str(e)) from None


def _short_repr(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _validation_items(errors: list[dict[str, Any]]) -> list[dict[str, str]]:
    """Pydantic errors -> ``[{"field", "message"}]`` naming the field and its valid range."""
    items: list[dict[str, str]] = []
    for err in errors:
        loc = list(err.get("loc", ()))
        where = loc[0] if loc and loc[0] in ("body", "query", "path", "header") else None
        parts = loc[1:] if where else loc
        field = ""
        for p in parts:
            if isinstance(p, int):
                field += f"[{p}]"
            else:
                field += ("." if field else "") + str(p)
        field = field or (where or "request")
        names = [p for p in parts if isinstance(p, str)]
        name = names[-1] if names else field
        section = names[-2] if len(names) >= 2 else (where or "")
        rng = _RANGES.get((section, name))
        if rng is None:
            matches = {v for (s, n), v in _RANGES.items() if n == name}
            rng = matches.pop() if len(matches) == 1 else None
        etype = err.get("type", "")
        ctx = err.get("ctx") or {}
        value = err.get("input")
        if etype == "missing":
            msg = f"{field} is required" + (f" (valid range {rng})" if rng else "")
        elif etype == "extra_forbidden":
            msg = f"{field} is not an accepted field"
        elif etype in ("literal_error", "enum"):
            msg = f"{field} = {_short_repr(value)} is invalid: valid values {ctx.get('expected', '')}"
        elif etype == "json_invalid":
            msg = f"the request body is not valid JSON: {ctx.get('error', err.get('msg', ''))}"
            field = "body"
        elif rng is not None:
            msg = f"{name} = {_short_repr(value)} is invalid: valid range {rng}"
            if etype not in ("greater_than_equal", "less_than_equal", "greater_than", "less_than",
                             "finite_number"):
                msg += f" ({err.get('msg', '')})"
        else:
            msg = f"{field} = {_short_repr(value)} is invalid: {err.get('msg', '')}"
        items.append({"field": field, "message": msg})
    return items


class FieldProblem(BaseModel):
    """One bad field: its dotted name and a sentence with the value and the valid range."""

    field: str
    message: str


class ErrorOut(BaseModel):
    """Every error answer: ``detail`` is a sentence, or (422) one entry per bad field."""

    detail: Union[str, list[FieldProblem]]


#: What any endpoint may answer besides its success codes (declared in the OpenAPI document).
ERROR_RESPONSES: dict[Union[int, str], dict[str, Any]] = {
    code: {"model": ErrorOut, "description": text} for code, text in (
        (404, "unknown job, or short links disabled"),
        (408, "request body not received in time"),
        (409, "the job has no result (yet)"),
        (410, "the result was dropped from memory; submit again"),
        (413, "over a size limit (grid, sweep, body)"),
        (422, "bad input: the field and its valid range"),
        (429, "too many unfinished jobs; retry later"),
        (507, "the server's disk is full"),
    )}


def _error_json(status: int, detail: Any, headers: Optional[dict[str, str]] = None) -> JSONResponse:
    return JSONResponse(status_code=status, content={"detail": detail}, headers=headers)


# ================================================================================================
# helpers


@dataclasses.dataclass
class ApiResult:
    """What an API job returns: the raw core object (for shells) and the JSON payload."""

    raw: Any
    payload: dict[str, Any]


def encode_link_token(query: str) -> str:
    """Explorer query -> URL-safe token for ``/s/{token}`` (stateless: survives restarts)."""
    raw = query.lstrip("?").encode()
    packed = zlib.compress(raw, 9)
    body, tag = (packed, "z") if len(packed) < len(raw) else (raw, "q")
    return tag + base64.urlsafe_b64encode(body).decode().rstrip("=")


_TOKEN_BODY = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_")


def decode_link_token(token: str) -> str:
    """Inverse of :func:`encode_link_token`; raises ValueError on a malformed token (a character
    outside the URL-safe base64 alphabet, a length no encoder produces, a broken or trailing zlib
    stream, or text that is not UTF-8)."""
    if not token or token[0] not in "zq" or len(token) > 8192:
        raise ValueError("not a link token")
    body = token[1:]
    if not set(body) <= _TOKEN_BODY or len(body) % 4 == 1:
        raise ValueError("not a link token")
    data = base64.urlsafe_b64decode(body + "=" * (-len(body) % 4))
    if token[0] == "z":
        d = zlib.decompressobj()
        try:
            data = d.decompress(data, 16384)
        except zlib.error as exc:
            raise ValueError("not a link token") from exc
        if d.unconsumed_tail:
            raise ValueError("link token too long")
        if not d.eof or d.unused_data:
            raise ValueError("not a link token")
    return data.decode("utf-8")


# ================================================================================================
# the application


class _BodyLimit:
    """ASGI middleware: refuse request bodies over ``max_bytes`` with 413 (before parsing), and
    bodies not complete within ``seconds`` (dripped slowly) with 408."""

    def __init__(self, app: Any, max_bytes: int, seconds: float = 10.0) -> None:
        self.app, self.max_bytes, self.seconds = app, max_bytes, seconds

    async def __call__(self, scope: dict, receive: Callable, send: Callable) -> None:
        if scope["type"] != "http" or scope.get("method") in ("GET", "HEAD", "OPTIONS", "DELETE"):
            await self.app(scope, receive, send)
            return
        too_big = False
        for k, v in scope.get("headers", []):
            if k == b"content-length":
                try:
                    too_big = int(v) > self.max_bytes
                except ValueError:
                    too_big = False
        chunks: list[bytes] = []
        size = 0
        more = not too_big
        deadline = time.monotonic() + self.seconds
        while more:
            try:
                msg = await asyncio.wait_for(receive(), timeout=max(0.01, deadline - time.monotonic()))
            except asyncio.TimeoutError:
                resp = _error_json(408, f"request body not received within {self.seconds:g} s")
                await resp(scope, receive, send)
                return
            if msg["type"] == "http.disconnect":
                return
            body = msg.get("body", b"")
            size += len(body)
            if size > self.max_bytes:
                too_big = True
                break
            chunks.append(body)
            more = msg.get("more_body", False)
        if too_big:
            resp = _error_json(413, f"request body too large: limit max_body_bytes = {self.max_bytes} bytes")
            await resp(scope, receive, send)
            return
        body = b"".join(chunks)
        sent = False

        async def replay() -> dict:
            nonlocal sent
            if not sent:
                sent = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()

        await self.app(scope, replay, send)


def create_api(jobs: JobManager, *, explorer_url: Optional[str] = None,
               limits: ApiLimits = ApiLimits(), api_url: Optional[str] = None) -> FastAPI:
    """Build the FastAPI application.

    Args:
        jobs: the shared job manager (the explorer uses the same one).
        explorer_url: base URL of the viser explorer, used by the short links; ``None`` disables
            them (404 with a message).
        limits: resource limits (see :class:`ApiLimits`).
        api_url: this API's base URL as clients reach it, for the absolute short links
            (``None``: ``short_url`` is the path alone). Links never use the request's Host header.
    """
    app = FastAPI(
        title="paraspace API",
        version=API_VERSION,
        description=("Workspace, orientation capability, parameter studies and inverse kinematics of the "
                     "3-(arc-P, P, 2-(UPS)) redundant parallel mechanism. Long computations are jobs: "
                     "POST returns a job id, poll `GET /api/v1/jobs/{id}`, fetch `.../result`. "
                     "Bad input: 422 naming the field and its valid range; over a limit: 413/429."),
        docs_url="/docs",
        openapi_url="/openapi.json",
        redoc_url=None,
    )
    app.state.jobs = jobs
    app.state.limits = limits
    app.state.explorer_url = explorer_url
    # The workspace cache owns the voxel grids: an evicted result drops its grid (its measures stay),
    # so memory is bounded by cache_bytes however many jobs the history remembers (the job history
    # keeps only the JSON payload of results it cannot afford: JobManager(history_bytes=...)).
    caches = {"workspace": ByteLRU(limits.cache_bytes, on_evict=_drop_raw),
              "orientation": ByteLRU(limits.cache_bytes), "sweep": ByteLRU(limits.cache_bytes)}
    shells = ByteLRU(limits.shell_cache_bytes)
    shell_builds = threading.BoundedSemaphore(2)  # marching cubes at most twice at a time
    submit_lock = threading.Lock()
    app.state.caches = caches
    sweep_cache = None
    try:
        from paraspace.kinematics.sweep import ResultCache

        sweep_cache = ResultCache()
    except Exception:  # noqa: BLE001 - optional: the sweep module may be absent or differ
        sweep_cache = None

    # ----- error handlers -----------------------------------------------------------------
    @app.exception_handler(RequestValidationError)
    async def _on_validation(request: Request, exc: RequestValidationError) -> JSONResponse:
        return _error_json(422, _validation_items(list(exc.errors())))

    @app.exception_handler(StarletteHTTPException)
    async def _on_http(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        # FastAPI answers a body it cannot parse (invalid UTF-8, nesting too deep for the JSON
        # parser, truncated JSON) with a bare 400: name the field instead.
        if exc.status_code == 400 and "parsing the body" in str(exc.detail):
            return _error_json(422, [{"field": "body", "message": "body = <unreadable> is invalid: expected a "
                                      "UTF-8 JSON object (at most a few levels deep) as documented for this endpoint"}])
        return _error_json(exc.status_code, exc.detail, dict(exc.headers or {}))

    @app.exception_handler(OSError)
    async def _on_os(request: Request, exc: OSError) -> JSONResponse:
        if getattr(exc, "errno", None) in (errno.ENOSPC, errno.EDQUOT):
            log.error("disk full on %s %s: %s", request.method, request.url.path, exc)
            return _error_json(507, "the server's disk is full, so this request cannot be stored; "
                                    "requests that need no disk (health, ik, cached results) still work")
        log.exception("unhandled OS error on %s %s", request.method, request.url.path)
        return _error_json(500, f"internal error: {type(exc).__name__}: {' '.join(str(exc).split())[:300]}")

    @app.exception_handler(FieldError)
    async def _on_field(request: Request, exc: FieldError) -> JSONResponse:
        return _error_json(422, [{"field": exc.field, "message": exc.message}])

    @app.exception_handler(ParameterError)
    async def _on_param(request: Request, exc: ParameterError) -> JSONResponse:
        return _error_json(422, [{"field": exc.field, "message": str(exc)}])

    @app.exception_handler(ApiError)
    async def _on_api(request: Request, exc: ApiError) -> JSONResponse:
        return _error_json(exc.status, exc.detail, exc.headers)

    @app.exception_handler(Exception)
    async def _on_crash(request: Request, exc: Exception) -> JSONResponse:  # pragma: no cover - bugs only
        log.exception("unhandled error on %s %s", request.method, request.url.path)
        return _error_json(500, f"internal error: {type(exc).__name__}: {' '.join(str(exc).split())[:300]}")

    app.add_middleware(_BodyLimit, max_bytes=limits.max_body_bytes)

    # ----- helpers bound to this app ------------------------------------------------------
    def client_of(request: Request) -> str:
        ident = None
        if limits.client_header:
            ident = request.headers.get(limits.client_header)
        if not ident:
            ident = request.client.host if request.client else "unknown"
        return CLIENT_PREFIX + ident.strip()[:100]

    def submit(request: Request, kind: str, key: Hashable, compute: Callable[[Any, Any], ApiResult]) -> Job:
        """Submit through the limits; a cached result becomes an instantly finished job."""
        client = client_of(request)
        cache = caches[kind]
        cached = cache.get(key)
        fn: Callable[[Any, Any], Any] = (lambda p, c: cached) if cached is not None else compute
        ckey = ("cached", key) if cached is not None else key
        def on_done(job: Job) -> None:
            if job.status == "done" and cached is None and isinstance(job.result, ApiResult):
                cache.put(key, job.result)

        with submit_lock:  # check and submit atomically: the limits hold under concurrent requests
            return _submit_locked(client, kind, ckey, fn, on_done, hit=cached is not None)

    precheck_slots = threading.BoundedSemaphore(2)  # grid estimates (a coarse scout each) at once

    @contextlib.contextmanager
    def prechecks() -> Any:
        if not precheck_slots.acquire(timeout=10.0):
            raise ApiError(429, "server busy estimating other requests; retry later", {"Retry-After": "2"})
        try:
            yield
        finally:
            precheck_slots.release()

    def live_api_jobs() -> list[Job]:
        return [j for j in jobs.active() if j.client.startswith(CLIENT_PREFIX) and not j.cancel_token.is_set()]

    def quota_check(request: Request, client: Optional[str] = None, live: Optional[list[Job]] = None) -> None:
        """429 at once when the caller or the server is at its job limit (nothing computed yet)."""
        client = client or client_of(request)
        live = live_api_jobs() if live is None else live
        if sum(1 for j in live if j.client == client) >= limits.max_jobs_per_client:
            raise ApiError(429, f"too many unfinished jobs for this client: limit max_jobs_per_client = "
                                f"{limits.max_jobs_per_client}; wait for one to finish or cancel it "
                                f"(DELETE {API_PREFIX}/jobs/{{id}})", {"Retry-After": "1"})
        if len(live) >= limits.max_jobs_total:
            raise ApiError(429, f"server busy: limit max_jobs_total = {limits.max_jobs_total} unfinished "
                                f"jobs reached; retry later", {"Retry-After": "2"})

    def grid_check(design: Design, settings: Any, *, analytic: bool = False, point: Optional[int] = None) -> None:
        """413 with the grid rule's message (app/limits.py) when the grid is over max_voxels."""
        try:
            check_workspace_grid(design, settings, limits.max_voxels, analytic=analytic)
        except ParameterError as exc:
            where = "" if point is None else f"sweep point {point}: "
            raise ApiError(413, f"{where}{exc} (limit max_voxels = {limits.max_voxels})") from None

    def _submit_locked(client: str, kind: str, ckey: Hashable, fn: Callable[[Any, Any], Any],
                       on_done: Callable[[Job], None], *, hit: bool) -> Job:
        live = live_api_jobs()
        same = [j for j in live if j.client == client and j.kind == kind and j.key == ckey]
        # a cache hit computes nothing: only the job manager's own limits apply to it
        if not same and not hit:
            quota_check(None, client, live)  # type: ignore[arg-type]
        try:
            return jobs.submit(fn, kind=kind, client=client, key=ckey, on_done=on_done,
                               max_seconds=limits.max_job_seconds, summarize=_payload_only)
        except LimitExceeded as e:
            raise ApiError(429, str(e), {"Retry-After": "2"}) from None
        except RuntimeError as e:
            raise ApiError(409, f"not accepting jobs: {e}") from None

    def job_links(job: Job) -> dict[str, str]:
        base = f"{API_PREFIX}/jobs/{job.id}"
        links = {"status": base, "result": f"{base}/result", "cancel": base}
        if job.kind == "workspace":
            links["measures"] = f"{API_PREFIX}/workspace/{job.id}"
            for fmt in ("stl", "ply", "obj", "glb"):
                links[f"shell_{fmt}"] = f"{API_PREFIX}/workspace/{job.id}/shell.{fmt}"
        return links

    async def job_response(job: Job, wait: float, cached: bool) -> JSONResponse:
        # Waiting happens on the event loop (no thread is held), so many waiting callers cannot
        # exhaust the thread pool that runs the synchronous endpoints.
        if wait > 0:
            deadline = time.monotonic() + wait
            step = 0.002
            while not job.is_final and time.monotonic() < deadline:
                await asyncio.sleep(min(step, max(0.0, deadline - time.monotonic())))
                step = min(step * 1.5, 0.05)
        body: dict[str, Any] = {"job_id": job.id, "status": job.status, "cached": cached,
                                "job": job.to_dict(), "links": job_links(job)}
        if job.status == "done" and isinstance(job.result, ApiResult):
            body["result"] = job.result.payload
            return JSONResponse(status_code=200, content=jsonable(body))
        return JSONResponse(status_code=202, content=jsonable(body),
                            headers={"Location": f"{API_PREFIX}/jobs/{job.id}"})

    def api_job(job_id: str, request: Request, kind: Optional[str] = None) -> Job:
        try:
            job = jobs.get(job_id)
        except KeyError:
            job = None
        if job is None or not job.client.startswith(CLIENT_PREFIX) or (kind is not None and job.kind != kind):
            what = f"{kind} job" if kind else "job"
            raise ApiError(404, f"no {what} with id {job_id!r} (unknown, or expired from the history)")
        return job

    def finished_result(job: Job) -> ApiResult:
        if job.status == "done" and isinstance(job.result, ApiResult):
            if job.result.raw is None and job.kind in caches:  # the history kept only the payload
                key = job.key[1] if isinstance(job.key, tuple) and job.key[:1] == ("cached",) else job.key
                full = caches[job.kind].get(key)
                if isinstance(full, ApiResult):
                    return full
            return job.result
        if job.status == "done" and job.result_dropped:
            raise ApiError(410, f"job {job.id} finished, but its result was dropped from memory (the "
                                f"history's byte budget); submit the same request again to recompute it")
        if job.status in ("queued", "running"):
            raise ApiError(409, f"job {job.id} is {job.status} ({100 * job.progress:.0f}%): "
                                f"the result is available when its status is done",
                           {"Retry-After": "1"})
        why = job.error or job.message
        raise ApiError(409, f"job {job.id} ended {job.status}: {why}; it has no result")

    wait_q = Query(0.0, ge=0.0, le=60.0, allow_inf_nan=False,
                   description="seconds to wait for the job before answering; valid range [0, 60]")
    _RANGES[("query", "wait")] = "[0, 60] seconds"
    _RANGES[("query", "max_faces")] = "[100, 2000000]"

    router = APIRouter(prefix=API_PREFIX, responses=ERROR_RESPONSES)

    # ----- small synchronous endpoints ------------------------------------------------------
    @router.get("/health", summary="Liveness, job counts and limits")
    async def health() -> dict[str, Any]:
        """Always cheap; 200 while the server can answer."""
        return {"status": "ok", "api_version": "v1", "version": API_VERSION, "time": time.time(),
                "explorer_url": explorer_url, "jobs": jobs.stats(), "limits": limits.to_dict()}

    @router.get("/design/defaults", summary="Design fields, defaults and ranges")
    async def design_defaults() -> dict[str, Any]:
        """Every design parameter with its default (the paper's Fig. 3 design), the range the
        model accepts and the slider range of paper Table I."""
        fields = {name: {"default": s.default, "description": s.description, "unit": s.unit or None,
                         "model_min": s.model_min, "model_max": s.model_max,
                         "slider_min": s.slider_min, "slider_max": s.slider_max}
                  for name, s in PARAMS.items()}
        return {"fields": fields, "defaults": Design().to_dict(),
                "eta_range": {"default": "centered", "options": list(ETA_RANGES)},
                "constraints": ["d_s <= r"]}

    @router.post("/ik", summary="Inverse kinematics of one pose")
    async def ik(req: IkRequest) -> dict[str, Any]:  # ~1 ms of numpy: on the event loop, never queued
        # behind the thread pool that heavy requests may fill
        """Redundancy resolved automatically (no ``d``/``eta``) or with hand-set carriages."""
        from paraspace.kinematics.redundancy import inverse_kinematics, resolve_redundancy

        design, pose = req.design.build(), req.pose.build()
        if (req.d is None) != (req.eta is None):
            missing = "eta" if req.eta is None else "d"
            raise FieldError(missing, f"{missing} is required when {'d' if missing == 'eta' else 'eta'} is "
                                      f"given: set both carriages d_1..d_3 and eta_1..eta_3, or neither")
        joints = req.joints.build()
        if req.d is None:
            run = lambda: resolve_redundancy(design, pose, joints)  # noqa: E731
        else:
            run = lambda: _core("carriage", lambda: inverse_kinematics(design, pose, req.d, req.eta, joints))  # noqa: E731
        # with joint options the engine's compiled witness search runs: off the event loop
        res = run() if joints.is_default else await run_in_threadpool(run)
        return jsonable({"design": design.to_dict(), "pose": pose.to_dict(), **res.to_dict()})

    # ----- workspace ------------------------------------------------------------------------
    @router.post("/workspace", status_code=202, summary="Start a position-workspace job",
                 responses={200: {"description": "finished within `wait`: the result is included"},
                            202: {"description": "job accepted"}})
    async def workspace(req: WorkspaceRequest, request: Request, wait: float = wait_q) -> JSONResponse:
        """Constant-orientation position workspace; the result has the workspace measures."""
        job, cached = await run_in_threadpool(_start_workspace, req, request)
        return await job_response(job, wait, cached)

    def _start_workspace(req: WorkspaceRequest, request: Request) -> tuple[Job, bool]:
        from paraspace.kinematics.workspace import compute_workspace

        design, settings = req.design.build(), req.settings.build()
        key = (design.key(), settings.key())
        cached = caches["workspace"].get(key) is not None
        if not cached:
            quota_check(request)  # refuse at once, before any pre-computation
            with prechecks():
                grid_check(design, settings)

        def compute(progress: Any, cancel: Any) -> ApiResult:
            res = compute_workspace(design, settings, progress, cancel)
            return ApiResult(raw=res, payload=_workspace_payload(res))

        return submit(request, "workspace", key, compute), cached

    @router.get("/workspace/{job_id}", summary="Measures of a finished workspace job")
    def workspace_result(job_id: str, request: Request) -> dict[str, Any]:
        """409 while the job runs or when it failed or was cancelled."""
        job = api_job(job_id, request, "workspace")
        return jsonable({"job": job.to_dict(), **finished_result(job).payload})

    @router.get("/workspace/{job_id}/shell.{fmt}", summary="Boundary surface of a finished workspace",
                response_class=Response,
                responses={200: {"content": {"model/stl": {}, "application/octet-stream": {}}}})
    def workspace_shell(job_id: str, request: Request,
                        fmt: Literal["stl", "ply", "obj", "glb"] = Path(description="mesh format"),
                        max_faces: Optional[int] = Query(None, ge=100, le=2_000_000,
                                                         description="decimate to at most this many faces; "
                                                                     "valid range [100, 2000000]")) -> Response:
        """The workspace shell (marching cubes of the occupancy) as a mesh file download."""
        if max_faces is not None and max_faces > limits.max_shell_faces:
            raise FieldError("max_faces", f"max_faces = {max_faces} is invalid: valid range "
                                          f"[100, {limits.max_shell_faces}]")
        job = api_job(job_id, request, "workspace")
        res = finished_result(job)
        skey = (job_id, fmt, max_faces)
        data = shells.get(skey)
        if data is None:
            from paraspace.kinematics.shell import export_shell
            from paraspace.kinematics.shell import workspace_shell as make_shell

            raw = res.raw
            if raw is None:
                raise ApiError(409, f"the voxel grid of job {job_id} was evicted from the result cache "
                                    f"(limit cache_bytes = {limits.cache_bytes}); submit the workspace "
                                    f"request again to export its shell")
            if not raw.occupancy.any():
                raise ApiError(409, "the workspace is empty: there is no shell to export")
            with shell_builds:
                mesh = make_shell(raw, max_faces=max_faces)
                data = export_shell(mesh, fmt)
            shells.put(skey, data)
        media = {"stl": "model/stl", "ply": "application/octet-stream", "obj": "model/obj",
                 "glb": "model/gltf-binary"}[fmt]
        return Response(content=data, media_type=media,
                         headers={"Content-Disposition": f'attachment; filename="workspace-{job_id}.{fmt}"'})

    # ----- orientation ----------------------------------------------------------------------
    @router.post("/orientation", status_code=202, summary="Start an orientation-workspace job",
                 responses={200: {"description": "finished within `wait`"}, 202: {"description": "job accepted"}})
    async def orientation(req: OrientationRequest, request: Request, wait: float = wait_q) -> JSONResponse:
        """Orientation capability along the z, y' and x lines; the result has TI_1, TI_2, the Δ's
        and the nine regions."""
        job, cached = await run_in_threadpool(_start_orientation, req, request)
        return await job_response(job, wait, cached)

    def _start_orientation(req: OrientationRequest, request: Request) -> tuple[Job, bool]:
        from paraspace.kinematics.orientation import orientation_workspace

        design, settings = req.design.build(), req.settings.build()
        key = (design.key(), settings.key())
        cached = caches["orientation"].get(key) is not None
        if not cached:
            quota_check(request)
            n = _core("orientation", lambda: orientation_samples(design, settings))
            if n > limits.max_orientation_samples:
                raise ApiError(413, f"orientation request of {n} samples exceeds the limit "
                                    f"max_orientation_samples = {limits.max_orientation_samples}: use larger "
                                    f"angle_step / position_step")

        def compute(progress: Any, cancel: Any) -> ApiResult:
            res = orientation_workspace(design, settings, progress, cancel)
            return ApiResult(raw=None, payload=jsonable(res.to_dict(include_grids=False)))

        return submit(request, "orientation", key, compute), cached

    # ----- sweeps ---------------------------------------------------------------------------
    @router.post("/sweep", status_code=202, summary="Start a 1-D or 2-D parameter study job",
                 responses={200: {"description": "finished within `wait`"}, 202: {"description": "job accepted"}})
    async def sweep(req: SweepRequest, request: Request, wait: float = wait_q) -> JSONResponse:
        """Each point is ``kinematics.sweep.evaluate_design`` of the design with the swept
        parameter(s) replaced; 2-D when ``y`` is given."""
        job, cached = await run_in_threadpool(_start_sweep, req, request)
        return await job_response(job, wait, cached)

    def _start_sweep(req: SweepRequest, request: Request) -> tuple[Job, bool]:
        from paraspace.kinematics import sweep as sw

        design, settings = req.design.build(), req.settings.build()
        ori = req.orientation.build() if req.orientation is not None else None
        axes = [("x", req.x)] + ([("y", req.y)] if req.y is not None else [])
        if len(axes) == 2 and req.x.param == req.y.param:  # type: ignore[union-attr]
            raise FieldError("y.param", f"y.param = {req.y.param!r} is invalid: "  # type: ignore[union-attr]
                                        f"valid values any design parameter other than x.param")
        vals: list[list[float]] = []
        for name, ax in axes:
            if (ax.values is None) == (ax.n is None):
                raise FieldError(name, f"{name}: give exactly one of values (a list) or n (a count); "
                                       f"n valid range [1, 10000]")
            spec = PARAMS[ax.param]
            if ax.values is None:
                vs = [float(v) for v in sw.study_values(ax.param, ax.n)]
            else:
                vs = [float(v) for v in ax.values]
            for i, v in enumerate(vs):
                if not (spec.model_min <= v <= spec.model_max):
                    raise FieldError(f"{name}.values[{i}]", f"{ax.param} = {v!r} is invalid: valid range "
                                                            f"[{spec.model_min:g}, {spec.model_max:g}]")
            vals.append(vs)
        n_points = int(np.prod([len(v) for v in vals]))
        if n_points > limits.max_sweep_points:
            raise ApiError(413, f"sweep of {n_points} points exceeds the limit max_sweep_points = "
                                f"{limits.max_sweep_points}")
        key = (design.key(), settings.key(), None if ori is None else ori.key(),
               tuple((ax.param, tuple(v)) for (_, ax), v in zip(axes, vals)))
        cached = caches["sweep"].get(key) is not None
        if not cached:
            quota_check(request)
            total = 0
            n_ori = 0
            points = _grid_points(design, [ax.param for _, ax in axes], vals, [n for n, _ in axes])
            with prechecks():
                for i, d in enumerate(points):
                    grid_check(d, settings, point=i)  # each point obeys the workspace limit
            for d in points:
                total += workspace_voxels(d, settings, analytic=True)
                if ori is not None:
                    n_ori = max(n_ori, _core("orientation", lambda d=d: orientation_samples(d, ori)))
            if total > limits.max_sweep_voxels:
                raise ApiError(413, f"sweep of {total} voxels in all (analytical reach boxes) exceeds the limit "
                                    f"max_sweep_voxels = {limits.max_sweep_voxels}: use a larger voxel "
                                    f"(now {settings.voxel:g}) or fewer points")
            if n_ori > limits.max_orientation_samples:
                raise ApiError(413, f"orientation part of {n_ori} samples per point exceeds the limit "
                                    f"max_orientation_samples = {limits.max_orientation_samples}")

        def compute(progress: Any, cancel: Any) -> ApiResult:
            if len(axes) == 1:
                rows = sw.sweep_1d(design, req.x.param, vals[0], settings, orientation=ori,
                                   progress=progress, cancel=cancel, cache=sweep_cache)
                payload = {"mode": "1d", "param": req.x.param, "values": vals[0], "points": rows}
            else:
                out = sw.sweep_2d(design, req.x.param, vals[0], req.y.param, vals[1],  # type: ignore[union-attr]
                                  settings, orientation=ori, progress=progress, cancel=cancel, cache=sweep_cache)
                payload = {"mode": "2d", "param_x": req.x.param, "values_x": vals[0],
                           "param_y": req.y.param, "values_y": vals[1], **dict(out)}  # type: ignore[union-attr]
            return ApiResult(raw=None, payload=jsonable(payload))

        return submit(request, "sweep", key, compute), cached

    # ----- optimisation (issue 11) ------------------------------------------------------------
    caches["optimize"] = ByteLRU(limits.cache_bytes)

    @router.post("/optimize", status_code=202, summary="Start a multi-objective optimisation job",
                 responses={200: {"description": "finished within `wait`"}, 202: {"description": "job accepted"}})
    async def optimize_job(req: OptimizeRequest, request: Request, wait: float = wait_q) -> JSONResponse:
        """Pareto front of the objectives over the free parameters (``kinematics.optimize``);
        evaluations share the sweeps' result cache. The result: ``front`` (``{"design",
        "measures"}`` each), ``hypervolume`` per generation, ``settings``, ``failed``..."""
        job, cached = await run_in_threadpool(_start_optimize, req, request)
        return await job_response(job, wait, cached)

    def _start_optimize(req: OptimizeRequest, request: Request) -> tuple[Job, bool]:
        settings = req.build()
        key = settings.key()
        cached = caches["optimize"].get(key) is not None
        if not cached:
            quota_check(request)
            optimize_limits_check(settings, limits)
        return submit(request, "optimize", key,
                      lambda progress, cancel: optimize_compute(settings, progress, cancel, sweep_cache)), cached

    # ----- generic jobs ---------------------------------------------------------------------
    @router.get("/jobs", summary="The caller's unfinished jobs")
    async def my_jobs(request: Request) -> dict[str, Any]:
        """Queued and running jobs of this client (oldest first)."""
        return {"jobs": [j.to_dict() for j in jobs.active(client_of(request))]}

    @router.get("/jobs/{job_id}", summary="Status and progress of a job")
    async def job_status(job_id: str, request: Request) -> dict[str, Any]:
        """``status`` is queued, running, done, failed or cancelled; ``progress`` in [0, 1]."""
        job = api_job(job_id, request)
        return jsonable({**job.to_dict(), "links": job_links(job)})

    @router.delete("/jobs/{job_id}", summary="Cancel a job")
    def job_cancel(job_id: str, request: Request) -> dict[str, Any]:
        """Only the client that submitted a job may cancel it; cancelling a finished job is a no-op
        (``cancelled: false``)."""
        job = api_job(job_id, request)
        if job.client != client_of(request):
            raise ApiError(403, f"job {job_id} belongs to another client; only its submitter may cancel it")
        ok = jobs.cancel(job_id)
        return jsonable({"cancelled": ok, **job.to_dict()})

    @router.get("/jobs/{job_id}/result", summary="Result of a finished job")
    def job_result(job_id: str, request: Request) -> dict[str, Any]:
        """The JSON result (409 while running, or when the job failed or was cancelled)."""
        job = api_job(job_id, request)
        return jsonable({"job": job.to_dict(), "result": finished_result(job).payload})

    # ----- short links ----------------------------------------------------------------------
    def explorer_base(request: Request) -> Optional[str]:
        """The explorer URL from the configuration (``serve --public-url``); never from the request's
        Host header, which a client controls."""
        return explorer_url.rstrip("/") if explorer_url else None

    def explorer_redirect(query: str, request: Request) -> RedirectResponse:
        base = explorer_base(request)
        if not base:
            raise ApiError(404, "no explorer is attached to this API server, so short links are disabled")
        query = query.lstrip("?")
        try:
            from paraspace.app.urlstate import parse_query
        except ImportError:  # pragma: no cover - urlstate is part of the app
            parse_query = None
        if parse_query is not None:
            _state, errors = parse_query(query)
            if errors:
                raise ApiError(422, [{"field": _error_field(m), "message": m} for m in errors])  # type: ignore[arg-type]
        target = base + "/" + (f"?{query}" if query else "")
        return RedirectResponse(target, status_code=307)

    @router.post("/links", summary="Make a short link to an explorer state")
    def make_link(req: LinkRequest, request: Request) -> dict[str, Any]:
        """Validates the query like the explorer does; returns ``/s/{token}`` (stateless)."""
        query = req.query.lstrip("?")
        try:
            from paraspace.app.urlstate import parse_query
        except ImportError:  # pragma: no cover
            parse_query = None
        if parse_query is not None:
            _state, errors = parse_query(query)
            if errors:
                raise ApiError(422, [{"field": _error_field(m), "message": m} for m in errors])  # type: ignore[arg-type]
        token = encode_link_token(query)
        # the API's own address from the configuration (serve), never from the request's Host header
        base = (api_url or "").rstrip("/")  # type: ignore[union-attr]
        return {"token": token, "path": f"/s/{token}", "short_url": f"{base}/s/{token}",
                "explorer_url": (explorer_base(request) + "/?" + query) if explorer_url else None}

    app.include_router(router)

    @app.get("/s", summary="Short link: redirect to the explorer with this query", status_code=307,
             response_class=RedirectResponse, responses={307: {"description": "redirect"}, **ERROR_RESPONSES})
    def short_query(request: Request) -> RedirectResponse:
        """``/s?a=60&z=120`` -> ``{explorer}/?a=60&z=120`` after validating the state."""
        return explorer_redirect(request.url.query, request)

    @app.get("/s/{token}", summary="Short link by token", status_code=307, response_class=RedirectResponse,
             responses={307: {"description": "redirect"}, **ERROR_RESPONSES})
    def short_token(request: Request, token: str = Path(max_length=8192)) -> RedirectResponse:
        """Token from ``POST /api/v1/links``."""
        try:
            query = decode_link_token(token)
        except (ValueError, UnicodeDecodeError, zlib.error):
            raise ApiError(404, f"not a valid short-link token: {token[:40]!r}") from None
        return explorer_redirect(query, request)

    @app.get("/", include_in_schema=False)
    def root(request: Request) -> Response:
        """A browser gets the landing page (static/index.html); a script gets the JSON index."""
        if "text/html" in request.headers.get("accept", ""):
            page = landing_page().replace("{{explorer_url}}", explorer_url or "/s").replace("{{api_prefix}}", API_PREFIX)
            return Response(page, media_type="text/html")
        return JSONResponse({"name": "paraspace API", "docs": "/docs", "openapi": "/openapi.json", "api": API_PREFIX,
                             "health": f"{API_PREFIX}/health", "explorer_url": explorer_url})

    return app


def landing_page() -> str:
    """``static/index.html``: from the source tree when running from a checkout, else from the
    installed package data ``paraspace.static``."""
    import importlib.resources
    import pathlib

    source = pathlib.Path(__file__).resolve().parent.parent / "static" / "index.html"
    if source.is_file():
        return source.read_text("utf-8")
    return importlib.resources.files("paraspace.static").joinpath("index.html").read_text("utf-8")


def _payload_only(result: Any) -> Any:
    """What the job history keeps of an API result it cannot afford: the JSON payload."""
    return ApiResult(raw=None, payload=result.payload) if isinstance(result, ApiResult) else None


def _drop_raw(result: Any) -> None:
    if isinstance(result, ApiResult):
        result.raw = None


def _error_field(message: str) -> str:
    """The field a urlstate message names (its first word before ' = ' or ':')."""
    head = message.split(" = ", 1)[0].split(":", 1)[0].strip()
    return head if head and " " not in head else "query"


def _grid_points(design: Design, params: list[str], vals: list[list[float]], names: list[str]) -> list[Design]:
    """Designs of a sweep's grid (validated: a bad combination names the axis and index)."""
    out: list[Design] = []
    if len(params) == 1:
        for i, v in enumerate(vals[0]):
            out.append(_core(f"{names[0]}.values[{i}]", lambda v=v: design.replace(**{params[0]: v})))
        return out
    for i, vx in enumerate(vals[0]):
        for j, vy in enumerate(vals[1]):
            out.append(_core(f"{names[0]}.values[{i}]/{names[1]}.values[{j}]",
                             lambda vx=vx, vy=vy: design.replace(**{params[0]: vx, params[1]: vy})))
    return out


def _workspace_payload(res: Any) -> dict[str, Any]:
    """JSON summary of a WorkspaceResult with its measures."""
    g = res.grid
    payload: dict[str, Any] = {
        "design": res.design.to_dict(),
        "settings": jsonable(dataclasses.asdict(res.settings)),
        "voxels": res.voxels,
        "volume": res.volume,
        "compute_seconds": res.compute_seconds,
        "n_eta": res.n_eta,
        "volume_inner": res.volume_inner,
        "volume_outer": res.volume_outer,
        "grid": {"origin": list(g.origin), "h": g.h, "shape": list(g.shape), "lo": list(g.lo), "hi": list(g.hi),
                 "size": g.size},
    }
    try:
        from paraspace.kinematics.measures import measure_workspace
    except ImportError as e:  # pragma: no cover - measures is part of the core
        payload["measures"] = None
        payload["measures_error"] = f"measures unavailable: {e}"
    else:
        payload["measures"] = measure_workspace(res).to_dict()
    return jsonable(payload)


def _json_dumps(x: Any) -> str:  # pragma: no cover - debugging aid
    return json.dumps(jsonable(x))
