"""The explorer's "Task" tab: does the design on screen hold my region, or follow my path?

A designer gives a **region** (box, vertical cylinder or sphere: centre and sizes) with the
orientations required at every point (every tilt up to T at all azimuths and torsion within +-Q,
or the home orientation), or a **pose list** (CSV ``x,y,z,psi,theta,phi[,t]``, pasted or uploaded).
"Check the task" answers in a background job with :mod:`paraspace.kinematics.task`
(:func:`~paraspace.kinematics.task.region_task`, :func:`~paraspace.kinematics.task.pose_list_task`),
on the design, joints and voxel edge on screen:

* the answer: the reachable fraction, contained or not, the certified verdict (never wrong), the
  margin (how far the region could grow, or must shrink), the worst pose and the limit that binds
  there; for a path also the carriage travel, the jumps and each actuator's range against its stroke;
* in the 3-D view: the region as a translucent solid (green when contained, orange otherwise),
  its sample points coloured reachable (green) / not (red), the worst pose marked; a path as a
  polyline with its poses coloured the same way;
* for a path: an interactive plot of the 12 actuator values along it with their stroke limits,
  and a slider that moves the mechanism along the path.

A region task travels in the link (``task=box,0,0,130,40,40,30,15,0``,
:class:`~paraspace.app.urlstate.TaskLink`); a pose list does not (it is pasted or uploaded, at most
:data:`~paraspace.kinematics.task.MAX_POSES` poses / :data:`~paraspace.kinematics.task.MAX_CSV_BYTES`).
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import trimesh
import viser

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.settings import TOTAL_ORIENTATION

from ..jobs import Job, JobManager, LimitExceeded
from ..numfmt import significant
from ..textsafe import md_text
from ..urlstate import TaskLink
from .lazy_plot import LazyPlot
from .scene import glb_with_material, remove_node
from .session import SessionJobs
from .typed_values import hold_typed_values

if TYPE_CHECKING:  # pragma: no cover - types only
    from paraspace.kinematics.joints import Joints
    from paraspace.kinematics.task import TaskResult

#: The task kinds offered, as the dropdown shows them.
KINDS: tuple[str, ...] = ("box", "cylinder", "sphere", "pose list (CSV)")
#: Default sizes per shape (the CLI's order), shown when the shape is chosen.
DEFAULT_SIZES: dict[str, str] = {"box": "40,40,30", "cylinder": "25,30", "sphere": "20"}
SIZE_HINTS: dict[str, str] = {"box": "edges LX,LY,LZ", "cylinder": "radius R, height H (axis vertical)",
                              "sphere": "radius R"}
OK_COLOUR = (40, 170, 80)
BAD_COLOUR = (220, 40, 40)
REGION_OK = (40, 170, 80, 255)
REGION_BAD = (230, 140, 20, 255)
#: Most sample poses (lattice points x orientations) one check may test in the explorer (a few
#: seconds on two cores; the command line and the REST API have their own bounds).
MAX_SAMPLES = 2_000_000
EXAMPLE_CSV = "x,y,z,psi,theta,phi,t\n-30,0,130,0,0,0,0\n0,0,140,0,5,0,1\n30,0,130,0,0,0,2\n"


def region_mesh(region: Any) -> trimesh.Trimesh:
    """The region as a closed mesh at its place (box, vertical cylinder or sphere)."""
    c = np.asarray(region.center, float)
    if region.shape == "box":
        m = trimesh.creation.box(extents=region.sizes)
    elif region.shape == "cylinder":
        m = trimesh.creation.cylinder(radius=region.sizes[0], height=region.sizes[1], sections=48)
    else:
        m = trimesh.creation.icosphere(subdivisions=3, radius=region.sizes[0])
    m.apply_translation(c)
    return m


def answer_markdown(res: TaskResult) -> str:
    """The task's answer in words (the Task tab's text)."""
    d = res.to_dict()
    lines = []
    if res.kind == "region":
        lines.append(f"**Reachable:** {100 * res.fraction:.1f} % of the region "
                     f"({d['reachable_points']:,} of {d['sample_points']:,} sample points, "
                     f"{d['orientation_samples']} orientation{'s' if d['orientation_samples'] != 1 else ''} each)")
        grow = "could grow by" if res.margin > 0 else "must shrink by"
        sat = " (at least: none unreachable within the search range)" if d.get("margin_saturated") else ""
        lines.append(f"**Margin:** the region {grow} {significant(abs(res.margin), 3)} units and stay inside{sat}")
    else:
        lines.append(f"**Reachable:** {100 * res.fraction:.1f} % of the {d['count']:,} poses")
        lines.append(f"**Margin:** smallest leg slack {significant(res.margin, 3)} units (pose "
                     f"{res.worst.get('index', 0) + 1})")
    verdict = {"contained": "contained (proven)", "not contained": "not contained (proven)",
               "undecided": "undecided (neither proven at this sampling; a smaller voxel or angle step may decide)"}
    lines.append(f"**Contained:** {'yes' if res.contained else 'no'} · **certified:** "
                 f"{verdict.get(res.certified, res.certified)}")
    if res.binding:
        lines.append(f"**Binding limit:** {md_text(str(res.binding.get('message', res.binding)), 300)}")
    if res.kind == "poses":
        car = d["carriage"]
        lines.append(f"**Carriage travel:** d {significant(car['travel_d'], 3)} units, eta "
                     f"{significant(car['travel_eta'], 3)} deg"
                     + (f"; top speeds {significant(car['max_speed_d'], 3)} units/s, "
                        f"{significant(car['max_speed_eta'], 3)} deg/s" if "max_speed_d" in car else ""))
        jumps = res.discontinuities or []
        lines.append("**Jumps:** none (one continuous carriage motion)" if not jumps else
                     f"**Jumps:** {len(jumps)}: the carriages must jump at pose "
                     + ", ".join(str(j.get("index", "?") + 1 if isinstance(j.get("index"), int) else "?")
                                 for j in jumps[:10]) + ("..." if len(jumps) > 10 else ""))
        used = [f"{a['name']} {100 * a['used_fraction']:.0f} %" for a in d["actuators"]]
        lines.append("**Stroke used:** " + ", ".join(used))
    lines.append(f"*{res.seconds:.2f} s*")
    return "  \n".join(lines)


def actuator_figure(res: TaskResult) -> Any:
    """The 12 actuator values along a pose list (legs, radial and arc carriages in three rows) with
    their stroke limits as dashed lines; unreachable poses marked."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    d = res.to_dict()
    rows = res.poses or []
    k = np.arange(1, len(rows) + 1)
    q = np.array([r["q"] for r in rows]) if rows else np.zeros((0, 12))
    names = d["actuator_names"]
    strokes = [a["stroke"] for a in d["actuators"]]
    fig = make_subplots(rows=3, cols=1, shared_xaxes=True, vertical_spacing=0.11,
                        subplot_titles=("leg lengths l (units)", "radial carriages d (units)",
                                        "arc carriages eta (deg)"))
    colours = ["#0072B2", "#56B4E9", "#D55E00", "#E69F00", "#009E73", "#66CC99"]
    for row, idx in ((1, range(6)), (2, range(6, 9)), (3, range(9, 12))):
        for n, a in enumerate(idx):
            fig.add_trace(go.Scatter(x=k, y=q[:, a], mode="lines+markers", name=names[a], marker=dict(size=4),
                                     line=dict(color=colours[(2 * n) % 6 if row > 1 else n], width=1.5)),
                          row=row, col=1)
        lo, hi = strokes[idx[0]]
        for v in (lo, hi):
            fig.add_hline(y=v, line=dict(color="#CC0000", dash="dash", width=1), row=row, col=1)
    bad = [r["index"] + 1 for r in rows if not r["reachable"]]
    for b in bad[:200]:
        fig.add_vline(x=b, line=dict(color="rgba(204,0,0,0.25)", width=4))
    fig.update_xaxes(title_text="pose", row=3, col=1, nticks=8)
    fig.update_yaxes(nticks=6)
    fig.update_layout(title=dict(text="Actuators along the path (dashed: stroke limits)", font=dict(size=13)),
                      height=520, margin=dict(l=50, r=10, t=70, b=40), font=dict(size=11),
                      legend=dict(orientation="h", y=-0.15, font=dict(size=10)), plot_bgcolor="white")
    return fig


@dataclasses.dataclass
class TaskHooks:
    """What the tab needs from its session."""

    get_input: Callable[[], tuple[Design, Joints, float]]  # design, joints, voxel edge on screen
    get_task: Callable[[], TaskLink | None]
    set_task: Callable[[TaskLink | None], None]  # the state and the link
    move_to: Callable[[Pose], None]  # the platform to a pose (the path slider)
    notify: Callable[[str, str], None]
    #: the answer in one line for the Numbers panel (``None``: no task on screen)
    show_in_numbers: Callable[[str | None], None] = lambda _line: None


class TaskPanel:
    """The Task tab of one browser (module docstring)."""

    NODE = "/task"

    def __init__(self, gui: viser.GuiApi, scene: viser.SceneApi, jobs: JobManager | SessionJobs, client: str,
                 hooks: TaskHooks) -> None:
        self.gui = gui
        self.scene = scene
        self.jobs = jobs
        self.client = client
        self.hooks = hooks
        self.lock = threading.Lock()
        self.job: Job | None = None
        self.result: TaskResult | None = None
        self.csv_text = ""
        self.pose_list: Any = None  # the pose list of the answer on screen (the path slider's poses)
        self.nodes: list[Any] = []
        gui.add_markdown("Does this design hold a region with the orientations your job needs, or follow a "
                         "path of poses? The answer is computed on the design, joints and voxel edge on screen.")
        self.kind: Any = gui.add_dropdown("task", KINDS, initial_value="box")
        self.center: Any = gui.add_text("centre x,y,z", "0,0,130", hint="the region's centre, length units")
        self.sizes: Any = gui.add_text("sizes", DEFAULT_SIZES["box"], hint=SIZE_HINTS["box"])
        tilt, torsion = TOTAL_ORIENTATION["tilt"], TOTAL_ORIENTATION["torsion"]
        assert tilt.slider is not None and torsion.slider is not None
        self.tilt: Any = hold_typed_values(gui.add_slider(
            "tilt ≤ (deg)", min=tilt.slider[0], max=tilt.slider[1], step=tilt.slider[2], initial_value=0.0,
            hint=f"{tilt.label} at every point; 0 with torsion 0: the home orientation only"))
        self.torsion: Any = hold_typed_values(gui.add_slider(
            "torsion ± (deg)", min=torsion.slider[0], max=torsion.slider[1], step=torsion.slider[2],
            initial_value=0.0, hint=torsion.label))
        self.csv: Any = gui.add_text("poses (CSV)", EXAMPLE_CSV, multiline=True, visible=False,
                                hint="header x,y,z,psi,theta,phi[,t]; angles in degrees, t in seconds")
        self.upload: Any = gui.add_upload_button("Upload CSV", icon=viser.Icon.UPLOAD, mime_type="text/csv")
        self.upload.visible = False
        self.run: Any = gui.add_button("Check the task", icon=viser.Icon.PLAYER_PLAY)
        self.stop: Any = gui.add_button("Stop", color="red", icon=viser.Icon.PLAYER_STOP, visible=False)
        self.progress: Any = gui.add_progress_bar(0.0, visible=False)
        self.answer: Any = gui.add_markdown("")
        with gui.add_folder("Along the path", expand_by_default=True, visible=False) as self.path_folder:
            self.path_slider: Any = gui.add_slider("pose", min=1, max=2, step=1, initial_value=1,
                                              hint="moves the mechanism to this pose of the path")
            self.plot = LazyPlot(gui, self.path_folder, "", visible=True)
        self.clear_button: Any = gui.add_button("Clear the task", icon=viser.Icon.TRASH, disabled=True)
        self.kind.on_update(lambda _e: self._on_kind())
        self.upload.on_upload(lambda e: self._on_upload(e))
        self.run.on_click(lambda _e: self.start())
        self.stop.on_click(lambda _e: self.cancel())
        self.clear_button.on_click(lambda _e: self.clear())
        self.path_slider.on_update(lambda _e: self._on_path_slider())
        link = hooks.get_task()
        if link is not None:
            self.show_link(link)

    # ----- inputs -------------------------------------------------------------------------------
    def _on_kind(self) -> None:
        kind = str(self.kind.value)
        poses = kind not in DEFAULT_SIZES
        self.center.visible = self.sizes.visible = not poses
        self.csv.visible = self.upload.visible = poses
        if not poses:
            self.sizes.value = DEFAULT_SIZES[kind]
            self.sizes.hint = SIZE_HINTS[kind]

    def _on_upload(self, event: Any) -> None:
        from paraspace.kinematics.task import MAX_CSV_BYTES

        f = event.target.value
        if len(f.content) > MAX_CSV_BYTES:
            self.hooks.notify("CSV not read", f"{f.name}: {len(f.content):,} bytes; at most {MAX_CSV_BYTES:,}")
            return
        try:
            text = f.content.decode("utf-8-sig")
        except UnicodeDecodeError:
            self.hooks.notify("CSV not read", f"{f.name}: not UTF-8 text")
            return
        self.csv_text = text
        self.csv.value = text if len(text) <= 20_000 else text[:20_000] + "\n... (shown cut; the whole file is used)"

    def show_link(self, link: TaskLink) -> None:
        """Fill the fields from a link's task (and check it once the workspace is there)."""
        r = link.region
        self.kind.value = r.shape
        self._on_kind()
        self.center.value = ",".join(f"{v:g}" for v in r.center)
        self.sizes.value = ",".join(f"{v:g}" for v in r.sizes)
        self.tilt.value = link.tilt
        self.torsion.value = link.torsion

    def read_task(self) -> Any:
        """The task of the fields: a :class:`~paraspace.app.urlstate.TaskLink` for a region, a
        :class:`~paraspace.kinematics.task.PoseList` for a pose list; raises ``ParameterError``
        naming the field."""
        from paraspace.kinematics.task import Region, read_pose_csv

        kind = str(self.kind.value)
        if kind not in DEFAULT_SIZES:
            text = self.csv_text if self.csv_text and str(self.csv.value).endswith("whole file is used)") \
                else str(self.csv.value)
            return read_pose_csv(text)

        def numbers(field: str, raw: str) -> list[float]:
            try:
                return [float(v) for v in raw.replace(" ", "").split(",") if v != ""]
            except ValueError:
                raise ParameterError(field, raw, "numbers separated by commas") from None

        center = numbers("centre", str(self.center.value))
        if len(center) != 3:
            raise ParameterError("centre", str(self.center.value), "three numbers x,y,z")
        region = Region(kind, tuple(center), tuple(numbers("sizes", str(self.sizes.value))))  # type: ignore[arg-type]
        link = TaskLink(region, float(self.tilt.value), float(self.torsion.value))
        link.orientations()
        return link

    # ----- the job ------------------------------------------------------------------------------
    def start(self) -> None:
        """Check the task in the background (a newer check supersedes an older one)."""
        from paraspace.kinematics.task import TaskSettings, pose_list_task, region_samples, region_task

        try:
            task = self.read_task()
        except ParameterError as exc:
            self.answer.content = f"**Task not checked:** {md_text(str(exc))}"
            return
        design, joints, voxel = self.hooks.get_input()
        settings = TaskSettings(voxel=voxel, joints=joints)
        if isinstance(task, TaskLink):
            oset = task.orientations()
            work = region_samples(task.region, oset, settings)
            if work > MAX_SAMPLES:
                self.answer.content = (f"**Task not checked:** {work:,} sample poses at h = {voxel:g}; at most "
                                       f"{MAX_SAMPLES:,} (a larger voxel h, a smaller region or fewer orientations)")
                return
            self.hooks.set_task(task)

            def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
                return region_task(design, task.region, oset, settings, progress=progress, cancel=cancel)
        else:
            self.hooks.set_task(None)  # a pose list does not travel in the link

            def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
                return pose_list_task(design, task, settings, progress=progress, cancel=cancel)

        def on_progress(job: Job) -> None:
            self.progress.value = 100.0 * float(job.progress)
            self.answer.content = f"checking the task, {100 * job.progress:.0f} %"

        def done(job: Job) -> None:
            self.run.disabled = False
            self.stop.visible = False
            self.progress.visible = False
            if job.status == "done":
                self.show(job.result, task)
            elif job.status == "failed":
                self.answer.content = f"**Task failed:** {md_text(str(job.error))}"
            else:
                self.answer.content = "*stopped: change the task or press Check the task again*"

        self.cancel()
        try:
            job = self.jobs.submit(fn, kind="task", client=self.client, supersede=True, on_done=done,
                                   on_progress=on_progress)
        except (LimitExceeded, RuntimeError) as exc:
            self.answer.content = f"**Task not checked:** {md_text(str(exc))}"
            return
        with self.lock:
            self.job = job
        self.run.disabled = True
        self.stop.visible = True
        self.progress.value = 0.0
        self.progress.visible = True
        self.answer.content = "checking the task..."

    def cancel(self) -> None:
        """Stop the running check, if any."""
        with self.lock:
            job = self.job
        if job is not None and not job.is_final:
            self.jobs.cancel(job.id)

    # ----- display ------------------------------------------------------------------------------
    def _remove_nodes(self) -> None:
        for h in self.nodes:
            remove_node(h)
        self.nodes = []

    def clear(self) -> None:
        """Forget the task: its drawing, its answer and its place in the link."""
        self.cancel()
        self._remove_nodes()
        self.result = None
        self.answer.content = ""
        self.path_folder.visible = False
        self.clear_button.disabled = True
        self.hooks.set_task(None)
        self.hooks.show_in_numbers(None)

    def show(self, res: TaskResult, task: Any) -> None:
        """Draw the answer of a finished check (``result`` is set last: when it is there, so is the rest)."""
        self.result = None
        self._remove_nodes()
        self.answer.content = answer_markdown(res)
        self.clear_button.disabled = False
        sc = self.scene
        if res.kind == "region" and isinstance(task, TaskLink):
            mesh = region_mesh(task.region)
            colour = REGION_OK if res.contained else REGION_BAD
            visual: Any = mesh.visual
            visual.vertex_colors = np.tile(np.array(colour, np.uint8), (len(mesh.vertices), 1))
            glb = cast(bytes, mesh.export(file_type="glb", include_normals=True))
            self.nodes.append(sc.add_glb(f"{self.NODE}/region", glb_with_material(glb, 0.22), cast_shadow=False,
                                         receive_shadow=False))
            if res.cells is not None and res.cells_ok is not None and len(res.cells):
                ok = np.asarray(res.cells_ok, bool)
                cols = np.where(ok[:, None], np.array(OK_COLOUR), np.array(BAD_COLOUR)).astype(np.uint8)
                size = 0.35 * float(np.min(task.region.extent / np.maximum(1, np.ceil(task.region.extent / 4.0))))
                self.nodes.append(sc.add_point_cloud(f"{self.NODE}/cells", np.asarray(res.cells, np.float32), cols,
                                                     point_size=max(0.8, size), point_shape="circle"))
            self.path_folder.visible = False
        elif res.kind == "poses":
            self.pose_list = task
            pts = np.asarray(task.poses, float)[:, :3].astype(np.float32)
            ok = np.array([r["reachable"] for r in res.poses or []], bool)
            cols = np.where(ok[:, None], np.array(OK_COLOUR), np.array(BAD_COLOUR)).astype(np.uint8)
            if len(pts) > 1:
                seg = np.stack([pts[:-1], pts[1:]], axis=1)
                self.nodes.append(sc.add_line_segments(f"{self.NODE}/path", seg, (60, 60, 60), thickness=2.0,
                                                       thickness_units="screen"))
            self.nodes.append(sc.add_point_cloud(f"{self.NODE}/poses", pts, cols, point_size=2.5,
                                                 point_shape="circle"))
            self.path_slider.max = max(2, len(pts))
            self.path_slider.value = 1
            self.plot.figure = actuator_figure(res)
            self.plot.aspect = 1.35
            self.path_folder.visible = True
        worst = res.worst or {}
        at = worst.get("position") or (worst.get("pose") or [None])[:3]
        if at and at[0] is not None:
            text = f"worst: margin {significant(res.margin, 3)}"
            if res.binding and res.binding.get("limit"):
                text += f" ({res.binding.get('limit')})"
            where = np.asarray(at[:3], float)
            self.nodes.append(sc.add_label(f"{self.NODE}/worst", text, position=where, font_size_mode="screen",
                                           font_screen_scale=0.75))
            self.nodes.append(sc.add_icosphere(f"{self.NODE}/worst_marker", radius=2.5, color=(20, 20, 20),
                                               position=where))
        self.result = res
        what = "of the region" if res.kind == "region" else f"of the {len(res.poses or [])} poses"
        self.hooks.show_in_numbers(f"{100 * res.fraction:.1f} % {what} reachable, margin {significant(res.margin, 3)}, "
                                   f"certified: {res.certified}")

    def _on_path_slider(self) -> None:
        res = self.result
        if res is None or res.kind != "poses" or not res.poses:
            return
        k = int(self.path_slider.value) - 1
        task = self.pose_list
        if task is None:
            return
        k = max(0, min(k, len(task) - 1))
        x, y, z, psi, theta, phi = (float(v) for v in task.poses[k])
        self.hooks.move_to(Pose(x=x, y=y, z=z, psi=psi, theta=theta, phi=phi))
