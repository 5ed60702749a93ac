"""paraspace explorer: the interactive workspace explorer in the browser (viser).

Every browser (viser client) gets its own :class:`ClientSession`: its own control panel on
``client.gui`` and its own 3-D scene on ``client.scene``, built from the link it was opened with
(:mod:`app.urlstate`). One user's slider never moves another's.

What happens when something changes (all callbacks run on viser's thread pool, concurrently):

* **pose** (x, y, z): inverse kinematics only (redundancy resolved, or hand-set carriages) --
  about 2 ms -- and the mechanism is moved inside ``client.atomic()``; no workspace job.
* **orientation** (psi, theta, phi), **design**, **voxel**: the mechanism is redrawn at once and a
  ``"workspace"`` job is submitted to the shared :class:`~app.jobs.JobManager` with
  ``supersede=True`` (the previous unfinished one is cancelled: the last slider value wins). The
  job computes a coarse preview (h = 6) and shows its shell, then the full workspace (h from the
  voxel slider) and its shell, then the measures. A per-session generation counter makes sure a
  stale job can never overwrite a newer result, whatever the thread timing. When it finishes, the
  orientation maps (TI_1, TI_2) are recomputed as an ``"orientation"`` job.
* **view** (camera, cut plane, opacity): only the scene changes.
* after any change the address bar is rewritten (debounced, ``history.replaceState``) so it always
  holds a link to the current state; the Share tab shows the same link.

Finished results are kept in a small LRU shared by all sessions (results are immutable), so
returning to a design -- or a second browser opening the same link -- shows it at once.
"""

from __future__ import annotations

import collections
import contextlib
import csv
import dataclasses
import errno
import io
import json
import logging
import math
import threading
import time
import urllib.parse
from typing import Any, Callable, Hashable, Iterator, Optional

import numpy as np
import viser

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.progress import Cancelled
from paraspace.kinematics.redundancy import Resolution, inverse_kinematics, resolve_redundancy
from paraspace.kinematics.workspace import WorkspaceResult, WorkspaceSettings, compute_workspace, reachable, warm_up

from . import figures, jsbridge, pagehook
from .bytecache import ByteLRU
from .jobs import Job, JobManager, LimitExceeded
from .limits import MAX_VOXELS, check_workspace_grid
from .numfmt import fixed, significant
from .optimize_panel import DEFAULTS as _OPT_DEFAULTS
from .optimize_panel import URL_KEYS as _OPT_URL_KEYS
from .optimize_panel import OptimizePanel, ResultStore
from .textsafe import md_text, plain_text
from .panels import Panels, build_panels, slider_span
from .compare_panel import CompareHooks, ComparePanel
from .paper_panel import PaperPanel
from .dexterity_colour import COLOUR_MODES, DEXTERITY_VOXEL, LIMIT_COLOURS, binding_labels, field_colours
from .dexterous_panel import DexterousPanel
from .tilt_panel import TiltPanel
from .scene import LEG_STATE_TEXT, MechanismScene, ShellScene
from .urlstate import (
    D_KEYS, DESIGN_KEYS, DESIGN_SLIDERS, ETA_KEYS, POSE_KEYS, POSE_RANGES, POSE_SLIDERS, ExplorerState, encode_query,
    panel_pairs, parse_query,
)

log = logging.getLogger(__name__)

#: Voxel edge of the coarse preview shell.
PREVIEW_VOXEL = 6.0
#: Seconds of quiet after which a value typed outside a slider's range is applied (see on_design_input).
TYPING_PAUSE = 0.8
#: Face budgets of the shells sent to the browser (decimated; keeps the transfer small).
PREVIEW_FACES = 20_000
FULL_FACES = 60_000
#: Smallest interval between two progress updates of one bar, seconds.
PROGRESS_INTERVAL = 0.25
#: Debounce of the address-bar update, seconds.
URL_DEBOUNCE = 0.25


# --------------------------------------------------------------------------------------------
# shared caches


@dataclasses.dataclass
class ShellBundle:
    """A computed workspace and what is derived from it (immutable once built)."""

    result: WorkspaceResult
    mesh: Any  # trimesh.Trimesh (decimated shell, colored by z)
    measures: Any = None  # kinematics.measures.WorkspaceMeasures
    shell_seconds: float = 0.0
    bracket: Any = None  # kinematics.bracket.VolumeBracket (certified volume_inner <= V <= volume_outer)


#: The Optimize panel's settings as the link writes them, at their defaults (left out of links).
_OPT_DEFAULT_QUERY = {k: (f"{_OPT_DEFAULTS[v]:g}" if isinstance(_OPT_DEFAULTS[v], float) else str(_OPT_DEFAULTS[v]))
                      for k, v in _OPT_URL_KEYS.items()}


def make_shell(result: WorkspaceResult, max_faces: int) -> Any:
    """Marching-cubes shell of ``result`` colored by z, re-meshed to at most ``max_faces`` faces
    (block re-mesh: fast and volume-preserving) and smoothed for display (no voxel terracing;
    :func:`kinematics.shell.smooth_for_display`)."""
    from paraspace.kinematics.shell import smooth_for_display, workspace_shell

    return smooth_for_display(workspace_shell(result, max_faces=max_faces, color_by_z=True, reduction="remesh"))


def _fmt(v: Optional[float], digits: int = 4) -> str:
    if v is None:
        return "-"
    try:
        if not np.isfinite(v):
            return "-"
    except TypeError:
        return str(v)
    return significant(float(v), digits)


# --------------------------------------------------------------------------------------------
# one browser


#: Directions (from the target to the camera) of the camera presets.
PRESET_DIRECTIONS: dict[str, tuple[float, float, float]] = {
    "iso": (0.55, -0.7, 0.45), "top": (0.0, -0.002, 1.0), "bottom": (0.0, -0.002, -1.0), "side": (0.0, -1.0, 0.0),
}
#: Share of the window's width that the control panel covers (on the right).
PANEL_SHARE = 0.3


def camera_framing(lo: np.ndarray, hi: np.ndarray, preset: str, fov: float, aspect: float
                   ) -> tuple[np.ndarray, np.ndarray]:
    """``(position, look_at)`` of a camera that shows the box ``[lo, hi]`` whole from the preset's
    direction, in the part of the window the control panel leaves free.

    The box's bounding sphere (radius ``rho``) fits the narrower of the vertical field ``fov`` and
    the free horizontal field (``(1 - PANEL_SHARE)`` of ``aspect`` times it); the look-at point is
    moved along the camera's right vector by half the panel's share of the visible width, so the
    box is centred in the free part."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    centre = 0.5 * (lo + hi)
    rho = max(0.5 * float(np.linalg.norm(hi - lo)), 1.0)
    d = np.asarray(PRESET_DIRECTIONS.get(preset, PRESET_DIRECTIONS["iso"]), float)
    d /= np.linalg.norm(d)
    half_v = 0.5 * fov
    half_h = math.atan(math.tan(half_v) * aspect * (1.0 - PANEL_SHARE))
    dist = 1.08 * rho / math.sin(min(half_v, half_h))
    up = np.array([0.0, 0.0, 1.0])
    right = np.cross(-d, up)
    if np.linalg.norm(right) < 1e-6:  # looking straight down or up
        right = np.array([1.0, 0.0, 0.0])
    right /= np.linalg.norm(right)
    visible_w = 2.0 * dist * math.tan(half_v) * aspect
    look_at = centre + right * (0.5 * PANEL_SHARE * visible_w)
    return look_at + dist * d, look_at


class SessionJobs:
    """The job manager as one browser's session sees it: the same jobs, but progress and completion
    callbacks are dropped once the browser has left (no GUI writes to a closed connection)."""

    def __init__(self, jobs: JobManager, is_closed: Callable[[], bool]) -> None:
        self._jobs = jobs
        self._closed = is_closed

    def submit(self, fn: Any, *, on_done: Optional[Callable[[Job], None]] = None,
               on_progress: Optional[Callable[[Job], None]] = None, **kw: Any) -> Job:
        def alive(cb: Optional[Callable[[Job], None]]) -> Optional[Callable[[Job], None]]:
            if cb is None:
                return None
            return lambda job: None if self._closed() else cb(job)
        return self._jobs.submit(fn, on_done=alive(on_done), on_progress=alive(on_progress), **kw)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._jobs, name)


def _joints_text(j: Any) -> str:
    """One line for the joint options in force, e.g. "theta_U 45°, theta_S 40° (home axes), legs 10 + 1"."""
    parts = []
    if j.theta_u is not None:
        parts.append(f"theta_U {j.theta_u:g}°")
    if j.theta_s is not None:
        parts.append(f"theta_S {j.theta_s:g}°")
    if parts:
        parts[-1] += f" ({j.cone_axis} axes)"
    if j.leg_diameter > 0:
        parts.append(f"legs Ø {j.leg_diameter:g}" + (f" + clearance {j.clearance:g}" if j.clearance else ""))
    return ", ".join(parts)


class ClientSession:
    """State, GUI and scene of one browser (see the module docstring).

    Args:
        explorer: the owning :class:`Explorer` (shared job manager and caches).
        client: the viser client.
        state: initial state (from the link).
        base_url: the page's URL without query (for the Share tab's link).
        messages: problems found in the link (shown on screen).
    """

    def __init__(self, explorer: "Explorer", client: viser.ClientHandle, state: ExplorerState,
                 base_url: str, messages: list[str], optimize_query: Optional[dict[str, str]] = None) -> None:
        self.explorer = explorer
        self.client = client
        self.optimize_query = dict(optimize_query or {})  # the link's opt_* entries (Optimize panel)
        self.optimize: Optional[OptimizePanel] = None
        self.job_client = f"viser-{client.client_id}"
        self.lock = threading.RLock()
        self._design_timer: Optional[threading.Timer] = None  # pending typed design value
        self._framed = False  # the camera has framed a shell once
        self.jobs = SessionJobs(explorer.jobs, lambda: self.closed)
        self.view_lock = threading.Lock()
        self.input_lock = threading.RLock()  # serialises design input (see on_design_input)
        self.mech_lock = threading.Lock()
        self.state = state
        self.base_url = base_url
        self.url_messages = list(messages)
        self.closed = False
        self._tls = threading.local()
        self._ws_gen = 0
        self._ws_job: Optional[Job] = None
        self._ws_shown: Optional[tuple] = None  # key of the full result on screen
        self._ws_info: dict[str, Any] = {}
        self.bundle: Optional[ShellBundle] = None  # full result on screen
        self.preview: Optional[ShellBundle] = None
        self.resolution: Optional[Resolution] = None
        self.in_workspace: Optional[bool] = None
        self._or_gen = 0
        self._or_job: Optional[Job] = None
        self._or_key: Optional[tuple] = None  # (design key, z0) of the maps being computed/shown
        self.orientation: Any = None
        self._orientation_spec: Optional[figures.FigureSpec] = None
        self._exports: dict[tuple[str, str], tuple[Any, bytes]] = {}  # (plot, format) -> file of the plot on screen
        self._sweep_job: Optional[Job] = None
        self._sweep: Optional[dict] = None
        self._surface_job: Optional[Job] = None
        self._surface: Optional[dict] = None
        self._url_timer: Optional[threading.Timer] = None
        self.last_query: Optional[str] = None
        self.events: list[tuple[float, str]] = []  # (time, what) for tests/benchmarks
        self._last_update: dict[str, float] = {}
        self.payloads: dict[str, int] = {}  # GLB bytes of the last preview/full shell sent
        self.design_error: Optional[str] = None
        self.ready = threading.Event()  # set when the GUI is built and wired
        self.panels: Panels
        self.mechanism: MechanismScene
        self.shell: ShellScene

    # ----- helpers ------------------------------------------------------------------------------
    @contextlib.contextmanager
    def programmatic(self) -> Iterator[None]:
        """GUI values assigned inside this block do not count as user input (same thread only)."""
        self._tls.depth = getattr(self._tls, "depth", 0) + 1
        try:
            yield
        finally:
            self._tls.depth -= 1

    def _is_programmatic(self) -> bool:
        return getattr(self._tls, "depth", 0) > 0

    def _callback(self, fn: Callable[[], None]) -> Callable[[Any], None]:
        """Wrap a handler: ignore programmatic changes and closed sessions; log failures."""
        def handler(_event: Any = None) -> None:
            if self.closed or self._is_programmatic():
                return
            try:
                self._dismiss_link_messages()
                fn()
            except Exception:  # noqa: BLE001 - never kill viser's callback thread
                log.exception("explorer callback failed")
        return handler

    def _dismiss_link_messages(self) -> None:
        """The link's problems were read: the user's first change closes the note about them."""
        if self.url_messages and self.panels.url_messages.visible:
            self.panels.url_messages.visible = False

    def _event(self, what: str) -> None:
        self.events.append((time.perf_counter(), what))
        if len(self.events) > 500:
            del self.events[:250]

    def _notify(self, title: str, body: str, color: str = "red") -> None:
        try:
            self.client.add_notification(title, plain_text(body, 600), auto_close_seconds=8.0,
                                         color=color)  # type: ignore[arg-type]
        except Exception:  # noqa: BLE001
            log.debug("notification failed", exc_info=True)

    # ----- build --------------------------------------------------------------------------------
    def build(self) -> None:
        """Create this client's GUI and scene and start the first computations."""
        s = self.state
        self.panels = build_panels(self.client.gui, s)
        self._build_optimize_tab()
        with self.panels.pose_tab:
            self.tilt = TiltPanel(self.client.gui, self.jobs, client=self.job_client,
                                  get_input=lambda: (self.state.design, self.state.pose.position, self.state.joints),
                                  notify=self._notify)
            self.dexterous = DexterousPanel(self.client.gui, self.client.scene, self.jobs,
                                            client=self.job_client,
                                            get_input=lambda: (self.state.design, self.state.joints),
                                            notify=self._notify)
        with self.panels.tabs.add_tab("Compare", viser.Icon.GIT_COMPARE):
            self.compare = ComparePanel(self.client.gui, self.client.scene, self.jobs, self.job_client,
                                        CompareHooks(get_state=lambda: self.state, set_pin=self._set_pin,
                                                     bundle_for=self._cached_bundle,
                                                     compute_bundle=self._compute_bundle,
                                                     current_bundle=lambda: self.bundle,
                                                     load_design=self.load_design, notify=self._notify))
        with self.panels.tabs.add_tab("Paper", viser.Icon.BOOK):
            self.paper = PaperPanel(self.client.gui, self.jobs, client=self.job_client,
                                    cache=self.explorer.paper_results, notify=self._notify)
        res = self._resolve(s)
        self.resolution = res
        with self.client.atomic():
            self.mechanism = MechanismScene(self.client.scene, s.design, s.pose, res.d, res.eta, res.leg_status)
            self.shell = ShellScene(self.client.scene)
            self.gizmo = self.client.scene.add_transform_controls(
                "/gizmo", scale=max(25.0, 0.9 * s.design.a), position=s.pose.position,
                wxyz=self.mechanism.platform.wxyz, depth_test=False, opacity=0.8,
                translation_limits=tuple((POSE_SLIDERS[k].lo, POSE_SLIDERS[k].hi) for k in ("x", "y", "z")))
        self._wire()
        self._show_url_messages()
        self.update_mechanism()  # pose marker, gizmo, tables
        self.set_camera(s.view)
        self._sync_url_now()
        self.submit_workspace()
        if s.pin is not None:
            self.compare.restore(s.pin)
        self.ready.set()

    # ----- Compare tab hooks ------------------------------------------------------------------------
    def _set_pin(self, design: Optional[Design]) -> None:
        with self.lock:
            self.state = self.state.replace(pin=design)
        self.schedule_url()

    def _cached_bundle(self, state: ExplorerState) -> Optional[ShellBundle]:
        hit = self.explorer.shell_cache.get(self._ws_key(state, state.voxel))
        return hit if hit is not None and hit.measures is not None else None

    def _compute_bundle(self, state: ExplorerState, progress: Callable[[float, str], None],
                        cancel: threading.Event) -> ShellBundle:
        res = compute_workspace(state.design, self._ws_settings(state, state.voxel), progress=progress, cancel=cancel)
        bundle = ShellBundle(res, make_shell(res, FULL_FACES))
        bundle.measures = _measure(res)
        self.explorer.shell_cache.put(self._ws_key(state, state.voxel), bundle)
        return bundle

    def _build_optimize_tab(self) -> None:
        """The Optimize tab (app/optimize_panel.py): a bounded multi-objective run of this session's
        design, its front, "Load this design"; its settings travel in the link (opt_* keys)."""
        with self.panels.tabs.add_tab("Optimize", viser.Icon.CHART_DOTS):
            self.optimize = OptimizePanel(
                self.client.gui, self.jobs, client=self.job_client,
                get_design=lambda: self.state.design, load_design=self.load_design,
                cache=self.explorer.study_cache, results=self.explorer.optimize_results,
                on_settings_change=lambda _q: self.schedule_url())
        if self.optimize_query:
            self.url_messages += self.optimize.apply_query(self.optimize_query)

    def _show_design(self, design: Design) -> None:
        """Put ``design`` into the design sliders (each widened to hold its value); the caller
        suppresses the callbacks."""
        for key in DESIGN_KEYS:
            h, v = self.panels.design[key], float(getattr(design, key))
            h.min, h.max = slider_span(DESIGN_SLIDERS[key].lo, DESIGN_SLIDERS[key].hi, v)
            h.value = v
        self.panels.eta_range.value = design.eta_range

    def load_design(self, design: Design) -> None:
        """Put ``design`` into the design sliders and apply it (as if typed)."""
        with self.input_lock:
            with self.programmatic():
                self._show_design(design)
            self.design_error = None
            self.panels.design_message.visible = False
            self.apply_design(design)

    def _wire(self) -> None:
        p = self.panels
        for key in DESIGN_KEYS:
            p.design[key].on_update(self._callback(self.on_design_input))
        p.eta_range.on_update(self._callback(self.on_design_input))
        p.reset.on_click(self._callback(self.reset_design))
        for h in p.joints.handles():
            h.on_update(self._callback(self.on_joints_input))
        p.voxel.on_update(self._callback(self.on_voxel))
        for key in ("x", "y", "z"):
            p.pose[key].on_update(self._callback(lambda: self.on_pose_input(orientation_changed=False)))
        for key in ("psi", "theta", "phi"):
            p.pose[key].on_update(self._callback(lambda: self.on_pose_input(orientation_changed=True)))
        p.gizmo.on_update(self._callback(self.on_gizmo_toggle))
        self.gizmo.on_update(self._callback_gizmo)
        p.carriages.on_update(self._callback(self.on_carriage_mode))
        for h in p.d + p.eta:
            h.on_update(self._callback(self.on_manual_carriage))
        p.view_buttons.on_click(self._callback(lambda: self.on_view(str(self.panels.view_buttons.value))))
        p.fit_view.on_click(self._callback(self.fit_view))
        p.shell_colour.on_update(self._callback(self.recolour_shell))
        for h in (p.cut, p.cut_z, p.cut_keep, p.opacity):
            h.on_update(self._callback(self.on_view_settings))
        p.stop.on_click(self._callback(self.stop_workspace))
        p.z0.on_update(self._callback(self.on_z0))
        p.orientation_png.on_click(self._callback(lambda: self.download_plot("orientation", "png")))
        p.orientation_svg.on_click(self._callback(lambda: self.download_plot("orientation", "svg")))
        p.sweep_measure.on_update(self._callback(self.on_sweep_measure))
        p.sweep_run.on_click(self._callback(self.run_sweep))
        p.sweep_stop.on_click(self._callback(lambda: self._cancel_job(self._sweep_job)))
        p.sweep_csv.on_click(self._callback(self.download_sweep_csv))
        p.sweep_png.on_click(self._callback(lambda: self.download_plot("sweep", "png")))
        p.sweep_svg.on_click(self._callback(lambda: self.download_plot("sweep", "svg")))
        p.surface_run.on_click(self._callback(self.run_surface))
        p.surface_stop.on_click(self._callback(lambda: self._cancel_job(self._surface_job)))
        p.surface_csv.on_click(self._callback(self.download_surface_csv))
        p.surface_png.on_click(self._callback(lambda: self.download_plot("surface", "png")))
        p.surface_svg.on_click(self._callback(lambda: self.download_plot("surface", "svg")))
        p.copy_link.on_click(self._callback(self.copy_link))
        p.download_stl.on_click(self._callback(lambda: self.download_shell("stl")))
        p.download_ply.on_click(self._callback(lambda: self.download_shell("ply")))
        p.download_glb.on_click(self._callback(lambda: self.download_shell("glb")))
        p.download_json.on_click(self._callback(self.download_measures))

    def _show_url_messages(self) -> None:
        msgs = self.url_messages
        if not msgs:
            self.panels.url_messages.visible = False
            return
        body = "\n".join(f"- {md_text(m)}" for m in msgs)
        self.panels.url_messages.content = (
            "**The link had problems; these fields keep their defaults, everything else applies** "
            "(this note closes at your first change):\n\n" + body)
        self.panels.url_messages.visible = True
        self._notify("Link problems", "; ".join(msgs), color="orange")

    # ----- kinematics ---------------------------------------------------------------------------
    @staticmethod
    def _resolve(state: ExplorerState) -> Resolution:
        if state.carriages == "manual":
            return inverse_kinematics(state.design, state.pose, state.d, state.eta, state.joints)
        return resolve_redundancy(state.design, state.pose, state.joints)

    @staticmethod
    def _ws_settings(s: ExplorerState, voxel: float) -> WorkspaceSettings:
        """The engine settings of ``s`` at voxel edge ``voxel`` (its orientation and joint options)."""
        return WorkspaceSettings(voxel=voxel, orientation=(s.pose.psi, s.pose.theta, s.pose.phi), joints=s.joints)

    def update_mechanism(self) -> Resolution:
        """IK at the current state and move the mechanism (the latest state always wins)."""
        with self.mech_lock:
            with self.lock:
                s = self.state
            res = self._resolve(s)
            inside = bool(reachable(s.design, s.pose.position[None, :], (s.pose.psi, s.pose.theta, s.pose.phi),
                                    joints=s.joints)[0])
            with self.client.atomic():
                if s.design != self.mechanism.design:
                    self.mechanism.set_design(s.design, s.pose, res.d, res.eta, res.leg_status)
                else:
                    self.mechanism.update_pose(s.pose, res.d, res.eta, res.leg_status)
                self.mechanism.set_reachable(inside)
                self.gizmo.position = s.pose.position
                self.gizmo.wxyz = self.mechanism.platform.wxyz
            with self.lock:
                self.resolution = res
                self.in_workspace = inside
            self._update_pose_views(res)
            self._event("mechanism")
            return res

    def _update_pose_views(self, res: Resolution) -> None:
        if self.closed:
            return
        s = self.state
        rows = ["| chain | d | η (°) | leg 1 | leg 2 | margin |", "|---|---|---|---|---|---|"]
        for c in res.chains:
            legs = [f"{fixed(c.lengths[j])} {_state_badge(c.leg_status[j])}" for j in range(2)]
            rows.append(f"| {c.chain + 1} | {fixed(c.d)} | {fixed(c.eta)} | {legs[0]} | {legs[1]} | {fixed(c.margin)} |")
        verdict = ("**reachable**" if res.feasible else f"**{res.message}**")
        cond = "-" if res.condition_number is None or not np.isfinite(res.condition_number) else \
            f"{res.condition_number:.3g}"
        text = (f"{verdict}  \ncarriages: {res.mode}; legs in [{s.design.l_min:g}, {s.design.l_max:g}]; "
                f"cond(J) = {cond}\n\n" + "\n".join(rows))
        self.panels.pose_table.content = text
        self._render_numbers()

    def _render_numbers(self) -> None:
        if self.closed:  # the browser left: its GUI handles lead nowhere
            return
        with self.lock:
            info = dict(self._ws_info)
            res = self.resolution
            inside = self.in_workspace
            ori = self.orientation
            s = self.state
        lines: list[str] = []
        if not s.joints.is_default:
            lines.append(f"**Joints** {md_text(_joints_text(s.joints))}  ")
        if info:
            m = info.get("measures")
            kind = "preview" if info.get("preview") else "full"
            lines.append(f"**Volume** {_fmt(info['volume'], 4)} units³  ({kind}, h = {info['h']:g})")
            br = info.get("bracket")
            if br is not None and info["volume"] > 0:
                lines.append(f"certified: {_fmt(br.volume_inner, 4)} ≤ V ≤ {_fmt(br.volume_outer, 4)} "
                             "(continuous workspace, units³)  ")
            if info["volume"] == 0:
                lines.append("**Empty workspace:** no platform position is reachable at this orientation "
                             "(psi, theta, phi) with this design.")
            elif m is not None:
                lines.append(f"**Voids** {m.voids} ({100 * m.void_ratio:.2f} % of volume)  ")
                lines.append(f"**Hollowness** {m.hollowness:.3f}  ")
                if m.boundary_complete:
                    lines.append("**Boundary** complete: one closed surface standing on the base  ")
                else:
                    lines.append(f"**Boundary** incomplete: {md_text(m.completeness_reason)}  ")
                closed = "closed" if m.boundary_closed_stable else "open (cut or in pieces)"
                frag = (f" + {m.fragments} fragment{'s' if m.fragments != 1 else ''} "
                        f"({100 * m.fragment_volume_fraction:.2f} % of volume)" if m.fragments else "")
                lines.append(f"**Topology** surface {closed}, {m.pieces} piece{'s' if m.pieces != 1 else ''}"
                             f"{frag}, genus {m.stable_genus} (features > {2 * m.feature_radius:.3g}; "
                             f"voxel-level: genus {m.genus}, {m.components} "
                             f"component{'s' if m.components != 1 else ''})  ")
            else:
                lines.append("*measures: computing...*  ")
            lines.append(f"**Compute** {info['seconds']:.2f} s workspace"
                         + (f", {info['shell_seconds']:.2f} s shell" if info.get("shell_seconds") else ""))
        else:
            lines.append("*workspace: computing...*")
        if ori is not None and ori.settings.z0 == s.z0 and ori.design == s.design and ori.settings.joints == s.joints:
            sat = {x.index for x in figures.orientation_saturation(ori)}
            flag = {k: (" (lower bound ⚠)" if k in sat else "") for k in ("TI_1", "TI_2")}
            lines.append(f"**TI₁** {_fmt(ori.ti1, 4)}{flag['TI_1']}  **TI₂** {_fmt(ori.ti2, 4)}{flag['TI_2']} "
                         f"deg·units  (z0 = {ori.settings.z0:g})")
            if sat:
                lines.append(f"⚠ {md_text(figures.saturation_warning(ori), 600)}")
        else:
            lines.append("**TI₁ / TI₂** *computing...*")
        if res is not None:
            where = "" if inside is None else (" · inside the workspace" if inside else " · outside the workspace")
            if res.feasible:
                lines.append(f"**Pose** reachable{where}")
            else:
                lines.append(f"**Pose** {md_text(res.message)}{where}")
        if self.design_error:
            lines.append(f"**Design not applied:** {md_text(self.design_error)}")
        self.panels.numbers.content = "\n\n".join(lines)

    # ----- input handlers -----------------------------------------------------------------------
    def on_design_input(self) -> None:
        """A design slider or the arc-range convention changed. Reading the sliders and applying the
        design happen under ``input_lock`` (viser runs one session's callbacks concurrently; the newest
        slider values must win). Worker threads never take ``input_lock``, so it cannot invert the
        ``view_lock`` -> ``lock`` order of :meth:`_publish`."""
        p = self.panels
        typed = [k for k in DESIGN_KEYS
                 if not DESIGN_SLIDERS[k].lo <= float(p.design[k].value) <= DESIGN_SLIDERS[k].hi]
        with self.input_lock:
            if self._design_timer is not None:
                self._design_timer.cancel()
                self._design_timer = None
            if typed:
                # a value outside the slider's Table I range can only come from the number box, where
                # every keystroke arrives ("80" is "8" first): apply it once typing pauses
                self._design_timer = threading.Timer(TYPING_PAUSE, self._callback(self._apply_typed_design))
                self._design_timer.daemon = True
                self._design_timer.start()
                return
            self._on_design_input_locked()

    def _apply_typed_design(self) -> None:
        with self.input_lock:
            self._design_timer = None
            self._on_design_input_locked()

    def _on_design_input_locked(self) -> None:
        p = self.panels
        fields: dict[str, Any] = {k: float(p.design[k].value) for k in DESIGN_KEYS}
        fields["eta_range"] = str(p.eta_range.value)
        try:
            design = Design(**fields)
        except ParameterError as exc:
            self.design_error = f"{exc.field} = {exc.value:g} is invalid; valid range {exc.valid}" \
                if isinstance(exc.value, float) else str(exc)
            p.design_message.content = f"**Not applied:** {md_text(self.design_error)}. The last valid design stays."
            p.design_message.visible = True
            self._render_numbers()
            return
        self.design_error = None
        p.design_message.visible = False
        self.apply_design(design)

    def apply_design(self, design: Design) -> None:
        """Make ``design`` current: carriages, mechanism, workspace job, URL."""
        with self.lock:
            s = self.state
            if design == s.design:
                return
            d, eta = list(s.d), list(s.eta)
            notes = []
            lo, hi = design.eta_limits
            for i in range(3):
                if d[i] > design.d_s:
                    notes.append(f"{D_KEYS[i]} {d[i]:g} -> {design.d_s:g}")
                    d[i] = design.d_s
                e = min(max(eta[i], lo), hi)
                if e != eta[i]:
                    notes.append(f"{ETA_KEYS[i]} {eta[i]:g} -> {e:g}")
                    eta[i] = e
            self.state = s.replace(design=design, d=tuple(d), eta=tuple(eta))
        self._set_carriage_slider_ranges(design, d, eta)
        if notes and self.state.carriages == "manual":
            self._notify("Carriages moved into the new strokes", ", ".join(notes), color="orange")
        self.update_mechanism()
        self.submit_workspace()
        self.schedule_url()

    def _set_carriage_slider_ranges(self, design: Design, d: list[float], eta: list[float]) -> None:
        p = self.panels
        lo, hi = design.eta_limits
        with self.programmatic():
            for i in range(3):
                p.d[i].max = max(design.d_s, 1e-6)
                p.d[i].value = d[i]
                p.eta[i].min = lo
                p.eta[i].max = max(hi, lo + 1e-6)
                p.eta[i].value = eta[i]

    def on_joints_input(self) -> None:
        """A Joints control changed: the core validates the values; a valid set recomputes the
        workspace, the orientation maps and the pose's IK with the new limits."""
        with self.input_lock:
            joints, error = self.panels.joints.read()
            msg = self.panels.joints.message
            if error:
                msg.content = f"**Not applied:** {md_text(error)}. The last valid joints stay."
                msg.visible = True
                return
            msg.visible = False
            with self.lock:
                if joints == self.state.joints:
                    return
                self.state = self.state.replace(joints=joints)
        self.update_mechanism()
        self.submit_workspace()
        self.schedule_url()

    def reset_design(self) -> None:
        """Reset the design sliders to the paper's defaults (Fig. 3 design)."""
        self.load_design(Design())

    def on_voxel(self) -> None:
        """The voxel slider moved: recompute the workspace at the new resolution."""
        with self.lock:
            self.state = self.state.replace(voxel=float(self.panels.voxel.value))
        self.submit_workspace()
        self.schedule_url()

    def on_pose_input(self, orientation_changed: bool) -> None:
        """A pose slider moved: IK only for x, y, z; the orientation also recomputes the workspace."""
        p = self.panels
        with self.lock:  # read the sliders under the lock: a concurrent older callback cannot write last
            vals = {k: float(p.pose[k].value) for k in POSE_KEYS}
            old = self.state.pose
            try:
                pose = Pose(**vals)
            except ParameterError as exc:  # a typed value outside the pose's valid range
                self._notify("Pose not applied", str(exc), color="orange")
                return
            self.state = self.state.replace(pose=pose)
        self.update_mechanism()
        if orientation_changed and (old.psi, old.theta, old.phi) != (pose.psi, pose.theta, pose.phi):
            self.submit_workspace()
        self.schedule_url()

    def _callback_gizmo(self, _event: Any = None) -> None:
        if self.closed or self._is_programmatic():
            return
        try:
            self.on_gizmo_drag()
        except Exception:  # noqa: BLE001
            log.exception("gizmo callback failed")

    def on_gizmo_drag(self) -> None:
        """The platform was dragged: set the pose sliders from the gizmo (0.1 resolution)."""
        import viser.transforms as vtf

        from paraspace.kinematics.rotation import euler_zyx_from_matrix

        pos = np.asarray(self.gizmo.position, float)
        rot = vtf.SO3(np.asarray(self.gizmo.wxyz, float)).as_matrix()
        psi, theta, phi = np.degrees(euler_zyx_from_matrix(rot))
        vals = {"x": pos[0], "y": pos[1], "z": pos[2], "psi": psi, "theta": theta, "phi": phi}
        vals = {k: round(float(v), 1) + 0.0 for k, v in vals.items()}
        bad = [f"{k} = {v:g} outside {POSE_RANGES[k].text()}" for k, v in vals.items()
               if not POSE_RANGES[k].lo <= v <= POSE_RANGES[k].hi]
        if bad:
            self._notify("Pose not applied", "; ".join(bad) + " (valid range)", color="orange")
            with self.programmatic():
                self.gizmo.position = self.state.pose.position
                self.gizmo.wxyz = self.mechanism.platform.wxyz
            return
        with self.programmatic():
            for k in POSE_KEYS:
                h = self.panels.pose[k]
                h.min, h.max = slider_span(POSE_SLIDERS[k].lo, POSE_SLIDERS[k].hi, vals[k])
                h.value = vals[k]
        with self.lock:
            old = self.state.pose
            pose = Pose(**vals)
            self.state = self.state.replace(pose=pose)
        self.update_mechanism()
        if (old.psi, old.theta, old.phi) != (pose.psi, pose.theta, pose.phi):
            self.submit_workspace()
        self.schedule_url()

    def on_gizmo_toggle(self) -> None:
        """Show or hide the drag gizmo on the platform."""
        self.gizmo.visible = bool(self.panels.gizmo.value)

    def on_carriage_mode(self) -> None:
        """auto <-> manual. Entering manual starts from the resolved carriage values."""
        mode = str(self.panels.carriages.value)
        p = self.panels
        with self.lock:
            res = self.resolution
            s = self.state
            if mode == "manual" and res is not None:
                d = tuple(float(np.clip(round(v, 2), 0.0, s.design.d_s)) for v in res.d)
                lo, hi = s.design.eta_limits
                eta = tuple(float(np.clip(round(v, 2), lo, hi)) + 0.0 for v in res.eta)
            else:
                d, eta = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
            self.state = s.replace(carriages=mode, d=d, eta=eta)  # type: ignore[arg-type]
        with self.programmatic():
            for i in range(3):
                p.d[i].value = d[i]
                p.eta[i].value = eta[i]
                p.d[i].visible = mode == "manual"
                p.eta[i].visible = mode == "manual"
        self.update_mechanism()
        self.schedule_url()

    def on_manual_carriage(self) -> None:
        """A hand-set carriage slider moved (manual mode): IK with those carriage values."""
        p = self.panels
        with self.lock:
            if self.state.carriages != "manual":
                return
            d = tuple(float(h.value) for h in p.d)
            eta = tuple(float(h.value) for h in p.eta)
            self.state = self.state.replace(d=d, eta=eta)  # type: ignore[arg-type]
        self.update_mechanism()
        self.schedule_url()

    # ----- view -----------------------------------------------------------------------------------
    def _framing_box(self) -> tuple[np.ndarray, np.ndarray]:
        """The box to frame: the shell's (or, before one exists, the reach of the design)."""
        mesh = self.shell.source if getattr(self, "shell", None) is not None else None
        if mesh is not None and len(mesh.vertices):
            return mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
        d = self.state.design
        R = d.r + 0.6 * d.l_max
        return np.array([-R, -R, 0.0]), np.array([R, R, d.l_max])

    def set_camera(self, preset: str) -> None:
        """Move this client's camera to a preset (iso, top, bottom, side) framing the workspace's box
        (see :func:`camera_framing`; the control panel's share of the window is left free)."""
        lo, hi = self._framing_box()
        cam = self.client.camera
        try:
            fov, aspect = float(cam.fov), float(cam.aspect)
        except Exception:  # noqa: BLE001 - before the browser reported its camera
            fov, aspect = math.radians(50.0), 16.0 / 9.0
        position, look_at = camera_framing(lo, hi, preset, fov, aspect)
        with self.client.atomic():
            cam.up_direction = (0.0, 0.0, 1.0)
            # position first: viser moves look_at along with the position, then aims at look_at
            cam.position = tuple(position)
            cam.look_at = tuple(look_at)

    def recolour_shell(self) -> None:
        """The View tab's "shell colour": height z (the shell's own colours) or the local dexterity
        1/kappa (app/dexterity_colour.py), computed in the background for the shell on screen."""
        bundle = self.bundle
        if bundle is None:
            return
        if str(self.panels.shell_colour.value) == COLOUR_MODES[0]:
            self._show_mesh(bundle.mesh)
            zr = self.shell.z_range()
            if zr is not None:
                self.panels.legend.show_z_range(*zr)
            return
        s = self.state
        if str(self.panels.shell_colour.value) == COLOUR_MODES[2]:
            self._colour_by_limit(bundle, s)
            return

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            from paraspace.kinematics.dexterity import dexterity_field

            res = compute_workspace(s.design, self._ws_settings(s, DEXTERITY_VOXEL), cancel=cancel)
            dex = dexterity_field(res, 0.005)
            return field_colours(bundle.mesh, dex, res) + (dex,)

        def done(job: Job) -> None:
            if job.status != "done" or self.bundle is not bundle or \
                    str(self.panels.shell_colour.value) == COLOUR_MODES[0]:
                return
            mesh, lo, hi, dex = job.result
            self._show_mesh(mesh)
            self.panels.legend.show_field_range(
                lo, hi, "1/kappa (eq. (26), L = a/2)",
                f"Shell colour = local dexterity 1/kappa at the resolved carriages, from {lo:.3g} to {hi:.3g} "
                f"(h = {DEXTERITY_VOXEL:g}); GCI (mean) {dex.gci:.3g}")

        try:
            self.jobs.submit(fn, kind="dexterity", client=self.job_client, supersede=True, on_done=done)
        except (LimitExceeded, RuntimeError) as exc:
            self._notify("Dexterity colours not started", str(exc))

    def _colour_by_limit(self, bundle: ShellBundle, s: ExplorerState) -> None:
        """The shell coloured by the limit that bounds the workspace there (background job)."""
        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            mesh = bundle.mesh
            labels = binding_labels(s.design, bundle.result.settings, mesh.vertices, mesh.vertex_normals,
                                    bundle.result.grid.h)
            out = mesh.copy()
            out.visual.vertex_colors = np.array([LIMIT_COLOURS[x] + (255,) for x in labels], np.uint8)
            counts = {k: labels.count(k) for k in LIMIT_COLOURS if labels.count(k)}
            return out, counts

        def done(job: Job) -> None:
            if job.status != "done" or self.bundle is not bundle or \
                    str(self.panels.shell_colour.value) != COLOUR_MODES[2]:
                return
            mesh, counts = job.result
            self._show_mesh(mesh)
            total = sum(counts.values()) or 1
            names = {"l_max": "red", "l_min": "blue", "carriage strokes": "orange", "joint cones": "purple",
                     "interference": "green", "other": "grey"}
            self.panels.legend.caption.content = "Shell colour = the limit that bounds the workspace there: " + \
                ", ".join(f"{names[k]} {k} ({100 * v / total:.0f} %)" for k, v in counts.items())

        try:
            self.jobs.submit(fn, kind="dexterity", client=self.job_client, supersede=True, on_done=done)
        except (LimitExceeded, RuntimeError) as exc:
            self._notify("Limit colours not started", str(exc))

    def _show_mesh(self, mesh: Any) -> None:
        with self.view_lock:
            if self.closed:
                return
            s = self.state
            with self.client.atomic():
                self.shell.show(mesh, s.opacity, s.cut, s.cut_z, s.cut_keep)

    def fit_view(self) -> None:
        """The Fit view button: frame the workspace with the current preset's direction."""
        self.set_camera(self.state.view)

    def on_view(self, preset: str) -> None:
        """A camera preset button was clicked."""
        with self.lock:
            self.state = self.state.replace(view=preset)  # type: ignore[arg-type]
        self.set_camera(preset)
        self.schedule_url()

    def on_view_settings(self) -> None:
        """Cut plane or opacity changed: re-send the shell on screen (no recomputation)."""
        p = self.panels
        with self.lock:
            self.state = self.state.replace(cut=bool(p.cut.value), cut_z=float(p.cut_z.value),
                                            cut_keep=str(p.cut_keep.value), opacity=float(p.opacity.value))
        self.refresh_shell()
        self.schedule_url()

    def refresh_shell(self) -> None:
        """Re-send the shell on screen with the current view settings."""
        with self.view_lock:
            s = self.state
            with self.client.atomic():
                size = self.shell.refresh(s.opacity, s.cut, s.cut_z, s.cut_keep)
            self._show_payload(size)

    def _show_payload(self, size: int) -> None:
        self.panels.payload.content = (f"shell on screen: {self.shell.last_faces:,} faces, "
                                       f"{size / 1e6:.2f} MB (GLB)")

    # ----- workspace job -------------------------------------------------------------------------
    def _ws_key(self, s: ExplorerState, voxel: float) -> tuple:
        return (s.design.key(), (s.pose.psi, s.pose.theta, s.pose.phi), float(voxel), s.joints.key())

    def submit_workspace(self) -> None:
        """(Re)compute the workspace for the current design/orientation/voxel; the last call wins."""
        with self.lock:
            self._ws_gen += 1
            gen = self._ws_gen
            s = self.state
            # maps of another design are stale: never show them, and free the worker at once
            stale_maps = self._or_key is not None and self._or_key != (s.design.key(), s.z0, s.joints.key())
            if stale_maps:
                self._or_gen += 1
                self._or_key = None
                stale_job, self._or_job = self._or_job, None
        if stale_maps:
            self._cancel_job(stale_job)
            with self.lock:
                if not self.closed:
                    self.panels.orientation_status.content = "waiting for the new design's workspace..."
        try:  # the same grid limit as the API, before any work is queued
            check_workspace_grid(s.design, self._ws_settings(s, s.voxel), self.explorer.max_voxels)
        except ParameterError as exc:
            self._cancel_job(self._ws_job)
            self._set_status(gen, f"**not started:** {md_text(exc)}", 0.0, running=False)
            self._notify("Grid too large", str(exc), color="orange")
            return
        cache = self.explorer.shell_cache
        key = self._ws_key(s, s.voxel)
        hit = cache.get(key)
        if hit is not None and hit.measures is not None:
            self._cancel_job(self._ws_job)
            self._publish(gen, hit, preview=False, seconds=hit.result.compute_seconds, from_cache=True)
            self._publish_measures(gen, hit)
            self._set_status(gen, f"full workspace h = {s.voxel:g} (cached)", 100.0, running=False)
            self.submit_orientation()
            return
        self._event("workspace-submit")
        fn = self._workspace_fn(gen, s)
        try:
            job = self.jobs.submit(fn, kind="workspace", client=self.job_client, supersede=True,
                                            on_progress=lambda j, g=gen: self._on_ws_progress(g, j),
                                            on_done=lambda j, g=gen: self._on_ws_done(g, j))
        except LimitExceeded as exc:
            self._set_status(gen, f"not started: {md_text(exc)}", 0.0, running=False)
            return
        except RuntimeError as exc:  # shut down
            self._set_status(gen, f"not started: {md_text(exc)}", 0.0, running=False)
            return
        with self.lock:
            if gen == self._ws_gen:
                self._ws_job = job
        self._mark_stale()
        self._set_status(gen, "queued...", 0.0, running=True)

    def _mark_stale(self) -> None:
        """The shell on screen belongs to an older state while a new one computes: say so on it and
        in the legend (cleared when the new shell is shown)."""
        with self.view_lock:
            if self.closed or self.shell.source is None:
                return
            with self.client.atomic():
                self.shell.set_stale("previous result - recomputing")
                zr = self.shell.z_range()
                if zr is not None:
                    self.panels.legend.show_z_range(*zr, stale=True)

    def _workspace_fn(self, gen: int, s: ExplorerState) -> Callable[[Callable[[float, str], None], threading.Event], Any]:
        design = s.design
        voxel = s.voxel
        cache = self.explorer.shell_cache

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> ShellBundle:
            t0 = time.perf_counter()
            full_key = self._ws_key(s, voxel)
            if voxel < PREVIEW_VOXEL:
                pkey = self._ws_key(s, PREVIEW_VOXEL)
                pre = cache.get(pkey)
                if pre is None:
                    res = compute_workspace(design, self._ws_settings(s, PREVIEW_VOXEL),
                                            progress=lambda f, m: progress(0.12 * f, f"preview: {m}"), cancel=cancel)
                    t1 = time.perf_counter()
                    pre = ShellBundle(res, make_shell(res, PREVIEW_FACES))
                    pre.shell_seconds = time.perf_counter() - t1
                    pre.measures = _measure(res)
                    pre.bracket = _bracket(res)
                    cache.put(pkey, pre)
                if cancel.is_set():
                    raise Cancelled()
                self._publish(gen, pre, preview=True, seconds=time.perf_counter() - t0)
                self._publish_measures(gen, pre, preview=True)
                progress(0.15, f"full workspace h = {voxel:g}...")
            res = compute_workspace(design, self._ws_settings(s, voxel),
                                    progress=lambda f, m: progress(0.15 + 0.6 * f, f"full h = {voxel:g}: {m}"),
                                    cancel=cancel)
            progress(0.78, "meshing the shell...")
            t1 = time.perf_counter()
            bundle = ShellBundle(res, make_shell(res, FULL_FACES))
            bundle.shell_seconds = time.perf_counter() - t1
            if cancel.is_set():
                raise Cancelled()
            self._publish(gen, bundle, preview=False, seconds=time.perf_counter() - t0)
            progress(0.9, "measuring (voids, genus, hollowness)...")
            bundle.measures = _measure(res)
            bundle.bracket = _bracket(res)
            cache.put(full_key, bundle)
            if cancel.is_set():
                raise Cancelled()
            self._publish_measures(gen, bundle)
            return bundle

        return fn

    def _throttled(self, what: str, interval: float) -> bool:
        """True when a GUI update of kind ``what`` should be skipped (one per ``interval`` seconds).

        Every GUI message makes the browser redraw; on software WebGL a redraw costs a few hundred
        milliseconds, so progress updates are rate-limited.
        """
        now = time.perf_counter()
        with self.lock:
            if now - self._last_update.get(what, -1e9) < interval:
                return True
            self._last_update[what] = now
            return False

    def _on_ws_progress(self, gen: int, job: Job) -> None:
        if self._throttled("ws-progress", PROGRESS_INTERVAL):
            return
        self._set_status(gen, md_text(job.message), 100.0 * job.progress, running=True)

    def _on_ws_done(self, gen: int, job: Job) -> None:
        if self.closed:
            return
        if job.status == "done":
            b: ShellBundle = job.result
            self._set_status(gen, f"full workspace h = {b.result.grid.h:g}: {b.result.compute_seconds:.2f} s "
                                  f"+ shell {b.shell_seconds:.2f} s", 100.0, running=False)
            with self.lock:
                latest = gen == self._ws_gen
            if latest:
                self.submit_orientation()
        elif job.status == "failed":
            self._set_status(gen, f"**failed:** {md_text(job.error)}", 0.0, running=False)
        else:
            with self.lock:
                latest = gen == self._ws_gen
            if latest:  # stopped by the user (a superseded job is followed by a newer one)
                self._set_status(gen, "stopped; the shell shows the last finished result", 0.0, running=False)

    def _set_status(self, gen: int, text: str, percent: float, running: bool) -> None:
        with self.lock:
            if gen != self._ws_gen or self.closed:
                return
            p = self.panels
            p.status.content = text
            p.progress.value = float(min(100.0, max(0.0, percent)))
            p.progress.animated = running
            p.stop.visible = running

    def _publish(self, gen: int, bundle: ShellBundle, preview: bool, seconds: float,
                 from_cache: bool = False) -> bool:
        """Show a shell if ``gen`` is still the latest request; returns whether it was shown."""
        with self.view_lock:
            with self.lock:
                if gen != self._ws_gen or self.closed:
                    return False
                s = self.state
            with self.client.atomic():
                size = self.shell.show(bundle.mesh, s.opacity, s.cut, s.cut_z, s.cut_keep)
                self.shell.set_stale(None)
                zr = self.shell.z_range()
                if zr is not None:
                    self.panels.legend.show_z_range(*zr)
            with self.lock:
                if preview:
                    self.preview = bundle
                else:
                    self.bundle = bundle
                self._ws_info = {"volume": bundle.result.volume, "h": bundle.result.grid.h, "preview": preview,
                                 "seconds": bundle.result.compute_seconds, "shell_seconds": bundle.shell_seconds,
                                 "measures": None, "gen": gen, "cached": from_cache}
                first = not self._framed
                self._framed = True
            if first:  # the first shell: frame it (later shells keep the user's camera)
                self.set_camera(s.view)
            self._show_payload(size)
            self.payloads["preview" if preview else "full"] = size
        self.client.flush()
        self._event("preview-shown" if preview else "full-shown")
        self._render_numbers()
        return True

    def _publish_measures(self, gen: int, bundle: ShellBundle, preview: bool = False) -> None:
        with self.lock:
            if gen != self._ws_gen or self.closed:
                return
            if self._ws_info.get("preview", False) != preview:
                return
            self._ws_info["measures"] = bundle.measures
            self._ws_info["bracket"] = bundle.bracket
        self._render_numbers()
        if not preview:
            self.compare.refresh()
        self._event("measures-preview" if preview else "measures-full")

    def stop_workspace(self) -> None:
        """The Stop button: cancel the running workspace job and go back to the state of the shell on
        screen (design, orientation, voxel, joints), so the controls, the numbers and the link all
        describe a result that exists (issue 8 defect 10)."""
        self._cancel_job(self._ws_job)
        shown = self.bundle
        if shown is None:
            return
        r = shown.result
        psi, theta, phi = r.settings.orientation
        with self.input_lock:
            with self.lock:
                s = self.state
                back = s.replace(design=r.design, voxel=float(r.settings.voxel), joints=r.settings.joints,
                                 pose=dataclasses.replace(s.pose, psi=psi, theta=theta, phi=phi))
                if back == s:
                    return
                self._ws_gen += 1  # late progress of the cancelled job must not touch the status
                self.state = back
            p = self.panels
            with self.programmatic():
                self._show_design(r.design)
                p.voxel.value = float(r.settings.voxel)
                for k, v in (("psi", psi), ("theta", theta), ("phi", phi)):
                    p.pose[k].value = v
                p.joints.show(r.settings.joints)
        self._set_carriage_slider_ranges(r.design, list(self.state.d), list(self.state.eta))
        self.shell.set_stale(None)
        zr = self.shell.z_range()
        if zr is not None:
            self.panels.legend.show_z_range(*zr)
        self._set_status(self._ws_gen, "stopped: back to the design on screen", 100.0, running=False)
        self.update_mechanism()
        self.schedule_url()

    def _cancel_job(self, job: Optional[Job]) -> None:
        if job is not None and not job.is_final:
            self.explorer.jobs.cancel(job.id)

    # ----- orientation maps ------------------------------------------------------------------------
    def on_z0(self) -> None:
        """The height of the orientation-map lines changed: recompute the maps."""
        with self.lock:
            self.state = self.state.replace(z0=float(self.panels.z0.value))
        self.submit_orientation()
        self.schedule_url()

    def submit_orientation(self) -> None:
        """Recompute the orientation maps and TI_1/TI_2 for the current design and z0."""
        with self.lock:
            self._or_gen += 1
            gen = self._or_gen
            s = self.state
            key = (s.design.key(), s.z0, s.joints.key())
            self._or_key = key
        hit = self.explorer.orientation_cache.get(key)
        if hit is not None:
            self._cancel_job(self._or_job)
            self._publish_orientation(gen, *hit)
            return

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            res = orientation_workspace(s.design, OrientationSettings(z0=s.z0, joints=s.joints),
                                        progress=lambda f, m: progress(0.85 * f, m), cancel=cancel)
            progress(0.9, "drawing...")
            spec = figures.orientation_spec(res, s.z0)
            self.explorer.orientation_cache.put(key, (res, spec))
            return res, spec

        def done(job: Job) -> None:
            if job.status == "done":
                self._publish_orientation(gen, *job.result)
            elif job.status == "failed":
                self._set_orientation_status(gen, f"**failed:** {md_text(job.error)}")

        try:
            job = self.jobs.submit(
                fn, kind="orientation", client=self.job_client, supersede=True, on_done=done,
                on_progress=lambda j: None if self._throttled("or-progress", 4 * PROGRESS_INTERVAL) else
                self._set_orientation_status(gen, f"computing... {100 * j.progress:.0f} %"))
        except (LimitExceeded, RuntimeError) as exc:
            self._set_orientation_status(gen, f"not started: {md_text(exc)}")
            return
        with self.lock:
            if gen == self._or_gen:
                self._or_job = job
        self._set_orientation_status(gen, "computing...")

    def _set_orientation_status(self, gen: int, text: str) -> None:
        with self.lock:
            if gen != self._or_gen or self.closed:
                return
            self.panels.orientation_status.content = text

    def _publish_orientation(self, gen: int, res: Any, spec: figures.FigureSpec) -> None:
        fig = figures.to_plotly(spec)
        warning = figures.saturation_warning(res)
        with self.lock:
            if gen != self._or_gen or self.closed:
                return
            self.orientation = res
            self._orientation_spec = spec
            self._clear_exports("orientation")
            self.panels.orientation_plot.aspect = spec.aspect
            self.panels.orientation_plot.figure = fig
            self.panels.orientation_status.content = (
                f"TI₁ = {_fmt(res.ti1, 4)}, TI₂ = {_fmt(res.ti2, 4)} deg·units (z0 = {res.settings.z0:g}; "
                f"{res.compute_seconds:.2f} s). Dashed boxes: the Δ extents of eq. (28)."
                + (f"  \n⚠ {md_text(warning, 600)}" if warning else ""))
        self._render_numbers()
        self._event("orientation-shown")

    def _clear_exports(self, which: str) -> None:
        for k in [k for k in self._exports if k[0] == which]:
            del self._exports[k]

    def download_plot(self, which: str, fmt: str) -> None:
        """Send the plot ``which`` (``"orientation"``, ``"sweep"``, ``"surface"``) as it is on screen,
        as a static ``fmt`` file (``"png"`` at ``figures.EXPORT_DPI`` dpi or ``"svg"``)."""
        with self.lock:
            spec = {"orientation": self._orientation_spec,
                    "sweep": (self._sweep or {}).get("spec"), "surface": (self._surface or {}).get("spec")}[which]
            hit = self._exports.get((which, fmt))
        if spec is None:
            self._notify("Not ready", "this plot has not been computed yet", color="orange")
            return
        if hit is not None and hit[0] is spec:
            data = hit[1]
        else:
            data = figures.export(spec, fmt)
            with self.lock:
                self._exports[(which, fmt)] = (spec, data)
        self.client.send_file_download(f"{spec.filename}.{fmt}", data, save_immediately=True)

    # ----- parameter studies --------------------------------------------------------------------------
    def run_sweep(self) -> None:
        """Volume against one design parameter (Fig. 4) on request, with progress and Stop."""
        from paraspace.kinematics.sweep import study_values, sweep_1d

        p = self.panels
        param = str(p.sweep_param.value)
        measure = str(p.sweep_measure.value)
        n = int(p.sweep_points.value)
        voxel = float(p.study_voxel.value)
        s = self.state
        values = study_values(param, n)
        settings = self._ws_settings(s, voxel)
        cache = self.explorer.study_cache

        # TI_1/TI_2 need the orientation maps of every point (at the current z0)
        ori = OrientationSettings(z0=s.z0, joints=s.joints) if measure in ("TI_1", "TI_2") else None

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> dict:
            rows = sweep_1d(s.design, param, values, settings, orientation=ori,
                            progress=lambda f, m: progress(0.95 * f, m), cancel=cancel, cache=cache)
            current = float(getattr(s.design, param))
            cur_row = sweep_1d(s.design, param, [current], settings, orientation=ori, cancel=cancel, cache=cache)[0]
            out = {"param": param, "rows": rows, "current": current, "current_row": cur_row,
                   "current_volume": cur_row["volume"], "voxel": voxel, "design": s.design, "orientation": settings.orientation}
            out["spec"] = self._sweep_spec(out, measure)
            out["figure"] = figures.to_plotly(out["spec"])
            return out

        def done(job: Job) -> None:
            p.sweep_stop.visible = False
            p.sweep_run.disabled = False
            if job.status == "done":
                self._show_sweep(job.result)
                p.sweep_progress.visible = False
                p.sweep_csv.disabled = False
            else:
                p.sweep_progress.visible = False
                if job.status == "failed":
                    self._notify("Sweep failed", str(job.error))

        self._sweep_job = self._start_study(fn, "sweep", p.sweep_progress, p.sweep_stop, p.sweep_run, done)

    def run_surface(self) -> None:
        """Volume over the (a, d_s) grid (Fig. 5) on request, with progress and Stop."""
        from paraspace.kinematics.sweep import study_values, sweep_1d, sweep_2d

        p = self.panels
        n = int(p.surface_points.value)
        voxel = float(p.study_voxel.value)
        s = self.state
        xs = study_values("a", n)
        ys = [v for v in study_values("d_s", n) if v <= s.design.r]
        settings = self._ws_settings(s, voxel)
        cache = self.explorer.study_cache

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> dict:
            out = sweep_2d(s.design, "a", xs, "d_s", ys, settings, progress=lambda f, m: progress(0.97 * f, m),
                           cancel=cancel, cache=cache)
            cur = sweep_1d(s.design, "a", [s.design.a], settings, cancel=cancel, cache=cache)[0]
            spec = figures.study_spec(out["values_x"], out["values_y"], out["volume"], param_x="a", param_y="d_s",
                                      current=(s.design.a, s.design.d_s), current_value=cur["volume"], voxel=voxel)
            return {**out, "spec": spec, "figure": figures.to_plotly(spec), "voxel": voxel, "design": s.design,
                    "orientation": settings.orientation}

        def done(job: Job) -> None:
            p.surface_stop.visible = False
            p.surface_run.disabled = False
            p.surface_progress.visible = False
            if job.status == "done":
                with self.lock:
                    self._surface = job.result
                    self._clear_exports("surface")
                p.surface_plot.aspect = job.result["spec"].aspect
                p.surface_plot.figure = job.result["figure"]
                p.surface_plot.visible = True
                p.surface_csv.disabled = False
                p.surface_png.disabled = False
                p.surface_svg.disabled = False
            elif job.status == "failed":
                self._notify("Study failed", str(job.error))

        self._surface_job = self._start_study(fn, "surface", p.surface_progress, p.surface_stop, p.surface_run, done)

    def _start_study(self, fn: Any, kind: str, bar: Any, stop: Any, run: Any,
                     done: Callable[[Job], None]) -> Optional[Job]:
        def on_progress(job: Job) -> None:
            if not self._throttled(kind + "-progress", PROGRESS_INTERVAL):
                bar.value = 100.0 * job.progress
        try:
            job = self.jobs.submit(fn, kind=kind, client=self.job_client, supersede=True,
                                            on_done=done, on_progress=on_progress)
        except (LimitExceeded, RuntimeError) as exc:
            self._notify("Not started", str(exc), color="orange")
            return None
        bar.value = 0.0
        bar.visible = True
        bar.animated = True
        stop.visible = True
        run.disabled = True
        return job

    @staticmethod
    def _sweep_spec(data: dict, measure: str) -> figures.FigureSpec:
        cur = data["current_row"].get(measure)
        return figures.sweep_spec(data["rows"], data["param"], measure, current=data["current"],
                                  current_value=None if cur is None else float(cur), voxel=data["voxel"])

    def _show_sweep(self, data: dict) -> None:
        p = self.panels
        with self.lock:
            self._sweep = data
            self._clear_exports("sweep")
        p.sweep_plot.aspect = data["spec"].aspect
        p.sweep_plot.figure = data["figure"]
        p.sweep_plot.visible = True
        p.sweep_png.disabled = False
        p.sweep_svg.disabled = False

    def on_sweep_measure(self) -> None:
        """The sweep's measure menu changed: redraw the last sweep when its rows carry that measure."""
        measure = str(self.panels.sweep_measure.value)
        data = self._sweep
        if data is None:
            return
        if not any(measure in r for r in data["rows"]):
            self._notify("Run the sweep again", f"the last sweep did not compute {measure}; press Run sweep",
                         color="orange")
            return
        spec = self._sweep_spec(data, measure)
        self._show_sweep({**data, "spec": spec, "figure": figures.to_plotly(spec)})

    # ----- downloads --------------------------------------------------------------------------------

    def download_sweep_csv(self) -> None:
        """Send the last volume-vs-parameter sweep as CSV (one row per value)."""
        data = self._sweep
        if data is None:
            return
        cols = ["value", "volume", "voids", "void_ratio", "hollowness", "components", "genus",
                "boundary_closed", "boundary_complete"]
        buf = io.StringIO()
        w = csv.writer(buf)
        w.writerow([data["param"]] + cols[1:])
        for r in data["rows"]:
            w.writerow([r.get(c) for c in cols])
        self.client.send_file_download(f"paraspace_sweep_{data['param']}.csv", buf.getvalue().encode(),
                                       save_immediately=True)

    def download_surface_csv(self) -> None:
        """Send the last (a, d_s) study as CSV (one row per grid point)."""
        data = self._surface
        if data is None:
            return
        buf = io.StringIO()
        w = csv.writer(buf)
        w.writerow(["a", "d_s", "volume", "voids", "hollowness", "components", "genus", "boundary_closed"])
        for pt in data["points"]:
            w.writerow([pt["x"], pt["y"], pt.get("volume"), pt.get("voids"), pt.get("hollowness"),
                        pt.get("components"), pt.get("genus"), pt.get("boundary_closed")])
        self.client.send_file_download("paraspace_volume_a_d_s.csv", buf.getvalue().encode(), save_immediately=True)

    def download_shell(self, fmt: str) -> None:
        """Send the full-resolution (uncut, not re-meshed) shell as STL, PLY or GLB: the marching-
        cubes surface of the voxel grid, watertight, as ``paraspace workspace --export`` writes it
        (the view shows a lighter re-mesh of it)."""
        from paraspace.kinematics.shell import export_shell, workspace_shell

        b = self.bundle
        if b is None:
            self._notify("Not ready", "the full workspace is still being computed", color="orange")
            return
        try:
            mesh = workspace_shell(b.result)
            data = export_shell(mesh, fmt)
        except ValueError as exc:  # e.g. an empty workspace has no shell
            self._notify("No shell to download", str(exc), color="orange")
            return
        self.client.send_file_download(f"paraspace_workspace.{fmt}", data, save_immediately=True)
        self._notify("Shell downloaded", f"full-resolution shell at h = {b.result.grid.h:g}: "
                     f"{len(mesh.faces):,} faces, watertight, volume {mesh.volume:.4g} units³ "
                     f"(the view shows a {len(b.mesh.faces):,}-face re-mesh of it)", color="blue")

    def measures_document(self) -> dict:
        """JSON document of the current design, pose, settings, measures and indices."""
        with self.lock:
            s = self.state
            b = self.bundle
            ori = self.orientation
            res = self.resolution
        doc: dict[str, Any] = {
            "link": self.link(),
            "design": s.design.to_dict(),
            "pose": s.pose.to_dict(),
            "workspace_settings": None if b is None else dataclasses.asdict(b.result.settings),
            "grid": None if b is None else b.result.grid.to_dict(),
            "compute_seconds": None if b is None else b.result.compute_seconds,
            "measures": None if b is None or b.measures is None else b.measures.to_dict(),
            "orientation": None if ori is None else ori.to_dict(),
            "pose_resolution": None if res is None else res.to_dict(),
        }
        return doc

    def download_measures(self) -> None:
        """Send :meth:`measures_document` as JSON."""
        doc = self.measures_document()
        data = json.dumps(doc, indent=2, default=_json_default).encode()
        self.client.send_file_download("paraspace_measures.json", data, save_immediately=True)

    # ----- URL --------------------------------------------------------------------------------------
    def query(self) -> str:
        """The query string of the current state (only the explorer's own keys), plus the Optimize
        panel's settings that differ from its defaults."""
        with self.lock:
            q = encode_query(self.state)
        if self.optimize is not None:
            extra = [(k, v) for k, v in self.optimize.query().items() if v != _OPT_DEFAULT_QUERY.get(k)]
            if extra:
                q += "&" + urllib.parse.urlencode(extra, safe=",")
        return q

    def link(self) -> str:
        """The shareable link of the current state."""
        return f"{self.base_url}?{self.query()}"

    def schedule_url(self) -> None:
        """Rewrite the address bar after :data:`URL_DEBOUNCE` seconds without further changes."""
        with self.lock:
            if self._url_timer is not None:
                self._url_timer.cancel()
            t = threading.Timer(URL_DEBOUNCE, self._sync_url_now)
            t.daemon = True
            self._url_timer = t
        t.start()

    def _sync_url_now(self) -> None:
        if self.closed:
            return
        q = self.query()
        if q == self.last_query:
            return
        self.last_query = q
        jsbridge.replace_query(self.client, q)
        self.panels.link.value = f"{self.base_url}?{q}"
        self._event("url")

    def copy_link(self) -> None:
        """Bring the address bar up to date and try to copy the link to the clipboard."""
        self._sync_url_now()
        ok = jsbridge.copy_to_clipboard(self.client, self.link())
        if ok:
            self._notify("Link copied", "the link to this design, pose and view is on the clipboard", color="green")
        else:
            self._notify("Link not copied", "the browser did not allow the clipboard here; select the link in "
                                            "the text field above and copy it (Ctrl+C)", color="orange")

    # ----- teardown --------------------------------------------------------------------------------
    def close(self) -> None:
        """The browser left: cancel its jobs and timers."""
        self.closed = True
        with self.lock:
            if self._url_timer is not None:
                self._url_timer.cancel()
            if self._design_timer is not None:
                self._design_timer.cancel()
        for job in self.explorer.jobs.active(self.job_client):
            self.explorer.jobs.cancel(job.id)


def _state_badge(status: str) -> str:
    text = LEG_STATE_TEXT.get(status, status)
    if status == "inside":
        return f"({text})"
    return f"**({text})**"


def _measure(result: WorkspaceResult) -> Any:
    from paraspace.kinematics.measures import measure_workspace

    return measure_workspace(result)


#: Boundary refinements of the explorer's certified bracket (one: about 1 s at h = 2; the CLI and
#: the API default to two).
EXPLORER_BRACKET_REFINE = 1


def _bracket(result: WorkspaceResult) -> Any:
    """The certified bracket shown in the numbers panel (``None`` with leg interference, which the
    bracket does not model)."""
    from paraspace.kinematics.bracket import bracket_of

    if result.settings.joints.min_distance > 0.0:
        return None
    return bracket_of(result, refine=EXPLORER_BRACKET_REFINE)


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    return str(obj)


# --------------------------------------------------------------------------------------------
# the server


class Explorer:
    """The viser server with one :class:`ClientSession` per browser.

    Args:
        host: interface to bind (default: localhost only).
        port: port (viser moves to the next free one when busy; read :attr:`port`). 0: any free port.
        jobs: the shared :class:`~app.jobs.JobManager` (a private one with 2 workers if ``None``).
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 8080, jobs: Optional[JobManager] = None,
                 max_voxels: int = MAX_VOXELS) -> None:
        self.host = host
        self.max_voxels = max_voxels  # the API's grid limit (app/limits.py), whatever a link asks for
        self._requested_port = port
        self.jobs = jobs if jobs is not None else JobManager(max_workers=2)
        self._own_jobs = jobs is None
        self.server: Optional[viser.ViserServer] = None
        self.sessions: dict[int, ClientSession] = {}
        self._sessions_lock = threading.Lock()
        # bounded by bytes (a voxel-1 result holds ~25 MB of grid): see app/bytecache.py
        self.shell_cache = ByteLRU(256 << 20)
        self.orientation_cache = ByteLRU(64 << 20)
        from paraspace.kinematics.sweep import ResultCache

        self.study_cache = ResultCache(max_entries=1024)
        self.optimize_results = ResultStore(16)  # finished Optimize runs by settings (a shared link reopens them)
        self.paper_results: dict = {}  # the Paper tab's comparison, by voxel (a few kB)
        self.warm = threading.Event()
        self.connect_seconds: list[float] = []

    @property
    def port(self) -> int:
        """The port the server listens on (after :meth:`start`)."""
        if self.server is None:
            raise RuntimeError("the explorer is not started")
        return int(self.server.get_port())

    @property
    def url(self) -> str:
        """``http://host:port/`` of the explorer."""
        host = self.host if self.host not in ("0.0.0.0", "::") else "127.0.0.1"
        return f"http://{host}:{self.port}/"

    def start(self) -> "Explorer":
        """Start the viser server (returns at once; the numba kernels warm up in the background)."""
        if self.server is not None:
            return self
        threading.Thread(target=self._warm_up, name="paraspace-warmup", daemon=True).start()
        pagehook.install()  # links carry only explorer keys; the page connects only to this server
        server = viser.ViserServer(host=self.host, port=self._requested_port, verbose=False)
        server.gui.configure_theme(show_share_button=False, control_width="large",
                                   brand_color=(40, 110, 180))
        server.scene.set_up_direction("+z")
        server.scene.configure_environment_map(None)
        # shadows double the geometry passes; software WebGL (no GPU) pays for every pass
        server.scene.configure_default_lights(True, cast_shadow=False)
        server.on_client_connect(self._on_connect)
        server.on_client_disconnect(self._on_disconnect)
        self.server = server
        return self

    def _warm_up(self) -> None:
        try:
            warm_up()
            from paraspace.kinematics.shell import workspace_shell  # noqa: F401 - import cost off the first request
        except Exception:  # noqa: BLE001
            log.exception("warm-up failed")
        finally:
            self.warm.set()

    def stop(self) -> None:
        """Stop the server, cancel this explorer's jobs (and the job manager if it owns it)."""
        with self._sessions_lock:
            sessions = list(self.sessions.values())
            self.sessions.clear()
        for s in sessions:
            s.close()
        if self.server is not None:
            self.server.stop()
            self.server = None
        if self._own_jobs:
            self.jobs.shutdown(wait=False)

    def _on_connect(self, client: viser.ClientHandle) -> None:
        t0 = time.perf_counter()
        loc = jsbridge.read_location(client, timeout=5.0)
        search, base = loc if loc is not None else ("", self.url.rstrip("/") + "/")
        state, messages = parse_query(search)
        session = ClientSession(self, client, state, base or self.url, messages, panel_pairs(search))
        with self._sessions_lock:
            self.sessions[client.client_id] = session
        try:
            session.build()
        except Exception as exc:  # noqa: BLE001 - say so on the page instead of leaving it at "starting..."
            log.exception("building the explorer for client %s failed", client.client_id)
            why = ("the server's disk is full (No space left on device)"
                   if isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT)
                   else f"{type(exc).__name__}: {exc}")
            try:
                client.gui.add_markdown(f"**The explorer could not start this page:** {md_text(why)}. "
                                        "Reload to try again; the REST API may still answer.")
                client.add_notification("The explorer could not start", plain_text(why, 300), color="red")
            except Exception:  # noqa: BLE001 - the client may be gone
                pass
            return
        self.connect_seconds.append(time.perf_counter() - t0)

    def _on_disconnect(self, client: viser.ClientHandle) -> None:
        with self._sessions_lock:
            session = self.sessions.pop(client.client_id, None)
        if session is not None:
            session.close()

    def session(self, client_id: int) -> Optional[ClientSession]:
        """The session of a connected client (``None`` if unknown)."""
        with self._sessions_lock:
            return self.sessions.get(client_id)


def main(host: str = "127.0.0.1", port: int = 8080) -> None:  # pragma: no cover - manual use
    """Run the explorer alone until interrupted."""
    exp = Explorer(host, port).start()
    print(f"paraspace explorer: {exp.url}", flush=True)
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        exp.stop()


if __name__ == "__main__":  # pragma: no cover
    main()
