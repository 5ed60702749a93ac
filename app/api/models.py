"""Request models of the REST API (pydantic), built from the input models of :mod:`paraspace.app.schema`.

The design, pose, joints, workspace and orientation settings are :mod:`paraspace.app.schema`'s models
(the explorer's link parser validates with the same fields); the requests here combine them. Every
numeric field registers its valid-range text in :data:`RANGES`, so a 422 names the field and its
range; each model's ``build()`` makes the core object, turning the core's ParameterError into a 422.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, Field

from paraspace.kinematics.settings import OPTIMIZE, TASK, TOTAL_ORIENTATION, WORKSPACE
from paraspace.kinematics.task import MAX_CSV_BYTES, MAX_POSES

from ..schema import (  # noqa: F401 - the input models, shared with the link parser (app/schema.py)
    _MODEL,
    RANGES,
    AnglesIn,
    BoundsIn,
    DesignIn,
    FieldError,
    JointsIn,
    Num,
    OrientationSettingsIn,
    PoseIn,
    WorkspaceSettingsIn,
    _setting,
    call_core,
)


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
    mechanism: MechanismIn | None = Field(None, description="a preset or a description instead of design")


class MechanismIn(BaseModel):
    """A mechanism instead of the paper's design: a ``preset`` with its ``params``, or a ``description``
    (the TOML file's structure as a JSON object, or the TOML/JSON text; at most 65,536 bytes).
    The paper preset (or a description equal to it) runs the paper's engine with every setting; any
    other mechanism the general engine (kinematics/mechanism_workspace.py)."""

    model_config = _MODEL
    preset: str | None = Field(None, max_length=40, description="a preset: paper, gough-stewart, 6-pups, 6-pss")
    params: dict[str, float | str] = Field(default_factory=dict, max_length=32,
                                           description="the preset's parameters by name (GET /mechanism/presets)")
    description: dict[str, Any] | str | None = Field(
        None, description="a mechanism description: the file's structure as an object, or its TOML/JSON text")
    length_step: float = Field(1.0, ge=0.01, le=100.0, allow_inf_nan=False,
                               description="spacing of a sampled (second) prismatic joint's values; "
                                           "valid range [0.01, 100]")

    def build(self) -> Any:
        """The core :class:`~kinematics.mechanism.Mechanism` (its ParameterError becomes a 422 naming
        ``mechanism.<field>``; an oversized description a 413)."""
        import json

        from paraspace.kinematics.mechanism import MAX_TEXT_BYTES, loads_mechanism, parse_mechanism
        from paraspace.kinematics.presets import preset

        from .errors import ApiError

        if (self.preset is None) == (self.description is None):
            raise FieldError("mechanism", "mechanism: give exactly one of preset (with params) or description")
        if self.description is not None:
            if self.params:
                raise FieldError("mechanism.params", "mechanism.params: only with a preset, not a description")
            text = self.description if isinstance(self.description, str) else json.dumps(self.description)
            size = len(text.encode("utf-8"))
            if size > MAX_TEXT_BYTES:
                raise ApiError(413, f"mechanism.description: {size:,} bytes is too large: a description of at "
                                    f"most {MAX_TEXT_BYTES:,} bytes")
            if isinstance(self.description, str):
                return call_core("mechanism.description", lambda: loads_mechanism(text))
            desc = self.description
            return call_core("mechanism.description", lambda: parse_mechanism(desc))
        name, params = str(self.preset), dict(self.params)
        return call_core("mechanism", lambda: preset(name, params))


IkRequest.model_rebuild()



def refuse_design_with_mechanism(req: BaseModel) -> None:
    """A request gives ``mechanism`` or ``design``, never both (422 naming ``design``)."""
    if "design" in req.model_fields_set:
        raise FieldError("design", "design: not with mechanism (set a preset's parameters in mechanism.params)")


def mechanism_or_design(req: Any) -> tuple[Any, Any]:
    """A request's ``(mechanism, design)``: without ``mechanism``, ``(None, req.design)``; the paper
    preset or a description equal to it, ``(mechanism, its Design)`` (the paper's engine); any other
    description, ``(mechanism, None)`` (the general engine). ``design`` beside ``mechanism`` is refused."""
    if req.mechanism is None:
        return None, req.design.build()
    from paraspace.kinematics.mechanism_workspace import paper_design

    refuse_design_with_mechanism(req)
    mech = req.mechanism.build()
    return mech, paper_design(mech)


class WorkspaceRequest(BaseModel):
    """A constant-orientation position workspace: of the paper's ``design``, or of a ``mechanism``."""

    model_config = _MODEL
    design: DesignIn = Field(default_factory=DesignIn)
    settings: WorkspaceSettingsIn = Field(default_factory=WorkspaceSettingsIn)
    mechanism: MechanismIn | None = Field(None, description="a preset or a description instead of design")


class OrientationRequest(BaseModel):
    """An orientation workspace (tilt indices TI_1, TI_2 of eq. (28)): of the paper's ``design``, or of
    a ``mechanism`` (its lines follow its symmetry axis, kinematics/mechanism_orientation.py)."""

    model_config = _MODEL
    design: DesignIn = Field(default_factory=DesignIn)
    settings: OrientationSettingsIn = Field(default_factory=OrientationSettingsIn)
    mechanism: MechanismIn | None = Field(None, description="a preset or a description instead of design")


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




class SweepAxis(BaseModel):
    """One swept parameter: explicit ``values`` or ``n`` values spread over its slider range."""

    model_config = _MODEL
    param: str = Field(max_length=40, description="design parameter to vary (a, b, d_s, r, l_min, l_s, eta_s; with "
                                                  "a mechanism preset one of its numeric parameters)")
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
    mechanism: MechanismIn | None = Field(
        None, description="a preset (with its fixed params) whose parameters are swept instead of design's; the "
                          "paper preset is the paper's design, any other runs the general engine (position "
                          "workspace measures only)")


class OptimizeRequest(BaseModel):
    """A multi-objective optimisation (``kinematics.optimize``): the Pareto front of ``objectives``
    over the free ``params``; each evaluation is a workspace (plus the orientation indices when an
    objective or constraint needs TI_1/TI_2)."""

    model_config = _MODEL
    design: DesignIn = Field(default_factory=DesignIn, description="base design; non-free fields stay fixed")
    settings: WorkspaceSettingsIn = Field(default_factory=lambda: WorkspaceSettingsIn(voxel=4.0))
    params: list[str] | None = Field(None, min_length=1, max_length=8,
                                     description="free design parameters (default a, d_s, eta_s, l_s); with a "
                                                 "mechanism preset its numeric parameters (default all of them)")
    bounds: dict[str, tuple[float, float]] = Field(
        default_factory=dict, max_length=8,
        description="{param: [lo, hi]} for some free parameters; others: Table I's range (a preset's: each "
                    "parameter's study range, GET /mechanism/presets)")
    objectives: list[str] | None = Field(None, min_length=1, max_length=8,
                                         description="measures; a leading - minimises (kinematics.objectives.MEASURES;"
                                                     " default volume, -footprint; with a general preset volume, "
                                                     "-l_max)")
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
    task: TaskRequest | None = Field(
        None, description="the task of the measures task_fraction, task_margin and the constraint contains_task "
                          "(as POST /task takes it, without design; its joints are settings.joints)")
    total_orientation: tuple[Num, Num, Num] | None = Field(
        None, description="tilt, torsion, angle_step (degrees) of the measure total_orientation_volume "
                          "(null: 15, 15, 5)")
    mechanism: MechanismIn | None = Field(
        None, description="a preset (with its fixed params) whose numeric parameters are optimised instead of "
                          "design; the paper preset is the paper's design, any other runs the general engine and "
                          "has the position workspace's measures and its parameters only")

    def build(self) -> Any:
        """The core ``OptimizeSettings`` (its ParameterError names the field: 422)."""
        from paraspace.kinematics.design import Design
        from paraspace.kinematics.optimize import DEFAULT_PARAMS, OptimizeSettings
        from paraspace.kinematics.presets import PRESETS

        preset, values, length_step = None, {}, 1.0
        if self.mechanism is not None:
            refuse_design_with_mechanism(self)
            if self.mechanism.description is not None or self.mechanism.preset is None:
                raise FieldError("mechanism.preset", "mechanism.preset: the optimiser varies a preset's parameters: "
                                                     f"valid values {', '.join(PRESETS)} (not a description)")
            self.mechanism.build()  # the preset's name and its params validated (422 naming mechanism.<field>)
            preset, values, length_step = self.mechanism.preset, dict(self.mechanism.params), self.mechanism.length_step
        general = preset not in (None, "paper")
        params = self.params if self.params is not None else (
            [q.name for q in PRESETS[str(preset)].params if q.numeric] if general else list(DEFAULT_PARAMS))
        objectives = self.objectives if self.objectives is not None else (
            ["volume", "-l_max"] if general else ["volume", "-footprint"])
        for text in objectives + self.constraints + params:
            if len(text) > 100:
                raise FieldError("objectives", f"{text[:40]!r}... is invalid: at most 100 characters per entry")
        workspace, orientation = study_settings(self.settings, self.orientation)
        spec = None
        if self.task is not None:
            import dataclasses

            from paraspace.kinematics.task import TaskSpec

            if self.task.mechanism is not None:
                raise FieldError("task.mechanism", "task.mechanism: not in an optimisation's task (the designs are "
                                                   "the optimisation's: design, or mechanism)")
            _, task, oset, tsettings = self.task.build()
            spec = TaskSpec(task, oset, dataclasses.replace(tsettings, joints=workspace.joints))
        return OptimizeSettings(
            task=spec, total_orientation=self.total_orientation, preset=preset, preset_values=values,
            length_step=length_step, params=tuple(params),
            bounds={str(k): v for k, v in self.bounds.items()}, objectives=list(objectives),
            constraints=list(self.constraints), design=self.design.build() if preset is None else Design(),
            workspace=workspace,
            orientation=orientation,
            population=self.population, generations=self.generations, seed=self.seed, step=self.step,
            algorithm=self.algorithm)



class RegionIn(BaseModel):
    """A task region: a box (sizes LX, LY, LZ), a cylinder with a vertical axis (R, H) or a sphere (R)."""

    model_config = _MODEL
    shape: Literal["box", "cylinder", "sphere"] = Field(description="box, cylinder (axis z) or sphere")
    center: tuple[Num, Num, Num] = Field(description=f"centre (x, y, z); each in {TASK['center'].range_text()}")
    sizes: list[Num] = Field(min_length=1, max_length=3,
                             description=f"box LX,LY,LZ; cylinder R,H; sphere R; each in {TASK['size'].range_text()}")


class TaskSettingsIn(BaseModel):
    """How a task is sampled (:data:`kinematics.settings.TASK`; ``voxel`` and ``eta_step`` are the
    workspace's entries), and the joint options."""

    model_config = _MODEL
    voxel: float = _setting("settings", WORKSPACE["voxel"])
    angle_step: float = _setting("settings", TASK["angle_step"])
    eta_step: float = _setting("settings", WORKSPACE["eta_step"])
    margin_range: float = _setting("settings", TASK["margin_range"])
    carriage_margin: float = _setting("settings", TASK["carriage_margin"])
    joints: JointsIn = Field(default_factory=JointsIn, description="joint cones and leg interference")


RANGES[("body", "tilt")] = TOTAL_ORIENTATION["tilt"].range_text()
RANGES[("body", "torsion")] = TOTAL_ORIENTATION["torsion"].range_text()
RANGES[("body", "poses")] = f"at most {MAX_POSES:,} poses"
RANGES[("body", "csv")] = f"at most {MAX_CSV_BYTES:,} bytes (at most {MAX_POSES:,} poses)"


class TaskRequest(BaseModel):
    """A task (``kinematics.task``): a ``region`` with an orientation set (``tilt``/``torsion``, or one
    fixed ``orientation``), or a pose list (``poses`` rows x,y,z,psi,theta,phi in degrees with optional
    times ``t``, or the same as ``csv`` text with the header x,y,z,psi,theta,phi[,t])."""

    model_config = _MODEL
    design: DesignIn = Field(default_factory=DesignIn)
    region: RegionIn | None = None
    tilt: float | None = Field(None, ge=TOTAL_ORIENTATION["tilt"].lo, le=TOTAL_ORIENTATION["tilt"].hi,
                               allow_inf_nan=False, description=TOTAL_ORIENTATION["tilt"].label + "; valid range "
                               + TOTAL_ORIENTATION["tilt"].range_text())
    torsion: float | None = Field(None, ge=TOTAL_ORIENTATION["torsion"].lo, le=TOTAL_ORIENTATION["torsion"].hi,
                                  allow_inf_nan=False, description=TOTAL_ORIENTATION["torsion"].label
                                  + "; valid range " + TOTAL_ORIENTATION["torsion"].range_text())
    orientation: AnglesIn | None = Field(None, description="one fixed orientation of the region instead")
    poses: list[tuple[Num, Num, Num, Num, Num, Num]] | None = Field(
        None, min_length=1, max_length=MAX_POSES, description=f"pose list; at most {MAX_POSES:,} poses")
    t: list[Num] | None = Field(None, max_length=MAX_POSES, description="times of the poses (s), increasing")
    csv: str | None = Field(None, max_length=MAX_CSV_BYTES, description="a pose list as CSV text")
    settings: TaskSettingsIn = Field(default_factory=TaskSettingsIn)
    mechanism: MechanismIn | None = Field(
        None, description="POST /task: a preset or a description instead of design (any mechanism other than the "
                          "paper's: kinematics/mechanism_task.py)")

    def build(self) -> tuple[Any, Any, Any, Any]:
        """``(design, task, orientation set, task settings)`` of the core (ParameterError: 422)."""
        from paraspace.kinematics.task import OrientationSet, PoseList, Region, TaskSettings, read_pose_csv

        given = [k for k in ("region", "poses", "csv") if getattr(self, k) is not None]
        if len(given) != 1:
            raise FieldError("region", "give exactly one of region, poses or csv")
        design = self.design.build()
        s = self.settings
        settings = call_core("settings", lambda: TaskSettings(
            voxel=s.voxel, eta_step=s.eta_step, margin_range=s.margin_range, carriage_margin=s.carriage_margin,
            joints=s.joints.build()))
        fixed = (0.0, 0.0, 0.0) if self.orientation is None else (
            self.orientation.psi, self.orientation.theta, self.orientation.phi)
        oset = call_core("body", lambda: OrientationSet(tilt=self.tilt, torsion=self.torsion, fixed=fixed,
                                                        step=s.angle_step))
        task: Any
        if self.region is not None:
            r = self.region
            task = call_core("region", lambda: Region(r.shape, r.center, tuple(r.sizes)))
        elif self.poses is not None:
            task = call_core("body", lambda: PoseList(np.array(self.poses, float),
                                                      None if self.t is None else np.array(self.t, float)))
        else:
            task = call_core("body", lambda: read_pose_csv(self.csv or ""))
        return design, task, oset, settings


OptimizeRequest.model_rebuild()


class LinkRequest(BaseModel):
    """An explorer state as a URL query string (the part after ``?``)."""

    model_config = _MODEL
    query: str = Field(max_length=4096, description="explorer URL query, e.g. a=60&z=120")

