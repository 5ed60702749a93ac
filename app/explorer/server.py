"""paraspace explorer: the interactive workspace explorer in the browser (viser).

Every browser (viser client) gets its own :class:`ClientSession`: its own control panel on
``client.gui`` and its own 3-D scene on ``client.scene``, built from the link it was opened with
(:mod:`app.urlstate`). One user's slider never moves another's. All callbacks run on viser's
thread pool, concurrently.

The data path is one straight line, each step in a module named for it:

* **slider -> state**: ``design_controller.py`` (design, voxel, joints), ``pose_controller.py``
  (pose, gizmo, carriages), ``view_controller.py`` (camera, cut, opacity, shell colour) write the
  session's :class:`~app.urlstate.ExplorerState`, held with the results on screen by the shared
  :class:`~app.session.SessionContext` (``session.py``).
* **state -> job**: ``workspace_controller.py`` submits a ``"workspace"`` job to the shared
  :class:`~app.jobs.JobManager` with ``supersede=True`` (the last slider value wins); a pose change
  (x, y, z) needs no job: inverse kinematics (about 2 ms) moves the mechanism at once.
* **job -> engine -> mesh**: ``workspace_job.py`` computes a coarse preview (h = 6), then the full
  workspace, its display shell and its measures.
* **mesh -> scene**: ``workspace_controller.py`` publishes each shell (a per-session generation
  counter keeps a stale job from overwriting a newer result); the numbers panel
  (``numbers_panel.py``) follows; a finished workspace starts the orientation maps
  (``orientation_controller.py``).

Beside it: ``share_controller.py`` rewrites the address bar after any change (debounced,
``history.replaceState``) and serves the Share tab's link and downloads; ``studies_controller.py``
runs the Fig. 4 / Fig. 5 studies on request; ``plot_exports.py`` sends the plots as PNG/SVG; the
Compare, Paper, Optimize, tilt and total-orientation panels have their own modules.
:class:`ClientSession` builds these for one browser, wires them and closes them.

Finished results are kept in a small LRU shared by all sessions (results are immutable), so
returning to a design -- or a second browser opening the same link -- shows it at once.
"""

from __future__ import annotations

import errno
import logging
import threading
import time
from typing import Any

import viser

from paraspace.kinematics.bytecache import ByteLRU
from paraspace.kinematics.design import Design
from paraspace.kinematics.warmup import warm_up

from .. import memory
from ..hostcheck import HostPolicy
from ..jobs import JobManager
from ..limits import MAX_VOXELS
from ..textsafe import md_text, plain_text
from ..urlstate import ExplorerState, TaskLink, panel_pairs, parse_query
from . import jsbridge, pagehook
from .compare_panel import CompareHooks, ComparePanel
from .design_controller import DesignController
from .dexterous_panel import DexterousPanel
from .lazy_plot import hold_plots
from .mechanism_panel import MechanismController, NotYetNotes, build_mechanism_controls
from .numbers_panel import NumbersPanel
from .optimize_panel import OptimizePanel
from .orientation_controller import OrientationController
from .panels import build_panels
from .paper_panel import PaperPanel
from .plot_exports import PlotExports
from .pose_controller import PoseController, resolve
from .scene import MechanismScene, ShellScene
from .session import SessionContext
from .share_controller import ShareController
from .studies_controller import StudiesController
from .task_panel import TaskHooks, TaskPanel
from .tilt_panel import TiltPanel
from .usage_panel import UsagePanel
from .view_controller import ViewController
from .workspace_controller import WorkspaceController
from .workspace_job import cached_bundle, compute_bundle

__all__ = ["ClientSession", "Explorer", "main"]

log = logging.getLogger(__name__)


# --------------------------------------------------------------------------------------------
# one browser


def _shared(name: str, doc: str) -> Any:
    """A read-only attribute of the session that is the shared context's ``name``."""
    return property(lambda self: getattr(self.ctx, name), doc=doc)


class ClientSession:
    """One browser's explorer: builds its panels and scene, its controllers around one shared
    :class:`~app.session.SessionContext`, wires them, and closes them (module docstring). The
    attributes below read the context; what the session does is done through its controllers
    (``design_controller``, ``pose_controller``, ``workspace_controller``, ...).

    Args:
        explorer: the owning :class:`Explorer` (shared job manager and caches).
        client: the viser client.
        state: initial state (from the link).
        base_url: the page's URL without query (for the Share tab's link).
        messages: problems found in the link (shown on screen).
        optimize_query: the link's ``opt_*`` entries (the Optimize panel's settings).
    """

    def __init__(self, explorer: Explorer, client: viser.ClientHandle, state: ExplorerState,
                 base_url: str, messages: list[str], optimize_query: dict[str, str] | None = None) -> None:
        self.explorer = explorer
        self.client = client
        self.ctx = ctx = SessionContext(explorer, client, state, base_url, messages)
        self.optimize_query = dict(optimize_query or {})
        self.optimize: OptimizePanel | None = None
        self.ready = threading.Event()  # set when the GUI is built and wired
        # the plots' plotly.js goes to the page once it has drawn its first shell (lazy_plot, the gate)
        self.plot_gate = hold_plots(client.gui, lambda: jsbridge.wait_drawn(client, ShellScene.NAME,
                                                                            timeout=PLOTS_WAIT_SECONDS))
        self.numbers = NumbersPanel(ctx)
        self.share_controller = ShareController(ctx)
        url = self.share_controller.schedule_url
        self.exports = PlotExports(ctx)
        self.view_controller = ViewController(ctx, on_state_change=url)
        self.orientation_controller = OrientationController(ctx, numbers=self.numbers, exports=self.exports,
                                                            on_state_change=url)
        self.studies_controller = StudiesController(ctx, exports=self.exports)
        self.workspace_controller = WorkspaceController(
            ctx, orientation=self.orientation_controller, numbers=self.numbers, view=self.view_controller,
            on_measures=self._after_measures,
            show_controls=self._show_result, on_state_change=self._after_stop)
        self.pose_controller = PoseController(ctx, numbers=self.numbers,
                                              submit_workspace=self.workspace_controller.submit, on_state_change=url)
        self.design_controller = DesignController(ctx, numbers=self.numbers,
                                                  update_mechanism=self.pose_controller.update_mechanism,
                                                  submit_workspace=self.workspace_controller.submit,
                                                  on_state_change=url)
        self.notes = NotYetNotes()  # panels on the paper's design only say so for another mechanism
        self.mechanism_controller = MechanismController(ctx, update_mechanism=self.pose_controller.update_mechanism,
                                                        submit_workspace=self.workspace_controller.submit,
                                                        on_state_change=url, notes=self.notes)

    # ----- build --------------------------------------------------------------------------------
    def build(self) -> None:
        """Create this client's GUI and scene and start the first computations."""
        ctx, client = self.ctx, self.client
        s = ctx.state
        ctx.panels = build_panels(client.gui, s)
        with ctx.panels.design_tab:  # the selector, at the top of the Design tab
            ctx.panels.mechanism = build_mechanism_controls(client.gui, s)
        self._build_optimize_tab()
        notify = ctx.notify
        notes, p = self.notes, ctx.panels
        with ctx.panels.pose_tab:
            notes.add(client.gui, "Manual carriages, tilt and torsion, the dexterous workspace", (p.carriages,))
            self.tilt = TiltPanel(client.gui, ctx.jobs, client=ctx.job_client,
                                  get_input=lambda: (ctx.state.design, ctx.state.pose.position, ctx.state.joints),
                                  notify=notify)
            self.dexterous = DexterousPanel(client.gui, client.scene, ctx.jobs, client=ctx.job_client,
                                            get_input=lambda: (ctx.state.design, ctx.state.joints), notify=notify)
        notes.attach("Manual carriages, tilt and torsion, the dexterous workspace",
                     (self.tilt.run, self.dexterous.show))
        cache = self.explorer.shell_cache
        with ctx.panels.tabs.add_tab("Compare", viser.Icon.GIT_COMPARE):
            notes.add(client.gui, "Compare pins")
            self.compare = ComparePanel(client.gui, client.scene, ctx.jobs, ctx.job_client,
                                        CompareHooks(get_state=lambda: ctx.state, set_pins=self._set_pins,
                                                     bundle_for=lambda st: cached_bundle(cache, st),
                                                     compute_bundle=lambda st, pr, c: compute_bundle(cache, st, pr, c),
                                                     current_bundle=lambda: ctx.bundle,
                                                     load_design=self.design_controller.load_design, notify=notify,
                                                     current_indices=self._current_indices))
        notes.attach("Compare pins", (self.compare.pin_button, self.compare.views_button))
        self.orientation_controller.on_shown = self._after_measures  # the table, and the notes kept
        with ctx.panels.plots_tab:
            self.usage = UsagePanel(client.gui, ctx.jobs, ctx.job_client,
                                    get_input=lambda: (ctx.state.design, ctx.state.joints))
            notes.add(client.gui, "The Fig. 4 / Fig. 5 studies and the actuator usage",
                      (p.sweep_run, p.surface_run, self.usage.run))
        with ctx.panels.tabs.add_tab("Task", viser.Icon.TARGET):
            notes.add(client.gui, "The Task tab")
            self.task = TaskPanel(client.gui, client.scene, ctx.jobs, ctx.job_client,
                                  TaskHooks(get_input=lambda: (ctx.state.design, ctx.state.joints, ctx.state.voxel),
                                            get_task=lambda: ctx.state.task, set_task=self._set_task,
                                            move_to=self.pose_controller.set_pose, notify=notify,
                                            show_in_numbers=self._show_task_line))
        notes.attach("The Task tab", (self.task.run,))
        with ctx.panels.tabs.add_tab("Paper", viser.Icon.BOOK):
            notes.add(client.gui, "The Paper tab")
            self.paper = PaperPanel(client.gui, ctx.jobs, client=ctx.job_client,
                                    cache=self.explorer.paper_results, notify=notify)
        notes.attach("The Paper tab", (self.paper.run,))
        jsbridge.show_panel(client)  # the GUI is complete: the page may show its panel (app/pagehook.py)
        if ctx.closed:  # the browser left while its GUI was being built
            return
        res = resolve(s)
        ctx.resolution = res
        with client.atomic():
            self.pose_controller.build_scene(res)
            grid = self.pose_controller.mechanism.grid
            self.view_controller.show_grid = lambda on: setattr(grid, "visible", on)
            ctx.shell = ShellScene(client.scene, is_closed=lambda: ctx.closed)
        for controller in (self.mechanism_controller, self.design_controller, self.pose_controller,
                           self.view_controller, self.workspace_controller, self.orientation_controller,
                           self.studies_controller, self.share_controller):
            controller.wire()
        self.share_controller.show_link_messages()
        self.pose_controller.update_mechanism()  # pose marker, gizmo, tables
        self.view_controller.set_camera(s.view)
        self.share_controller.sync_url_now()
        self.workspace_controller.submit()
        if s.pins:
            self.compare.set_mechanism(None if s.mechanism is None else s.mechanism.label)
            self.compare.restore(s.pins)
        self.ready.set()

    def _build_optimize_tab(self) -> None:
        """The Optimize tab (app/optimize_panel.py): a bounded multi-objective run of this session's
        design, its front, "Load this design"; its settings travel in the link (opt_* keys)."""
        ctx = self.ctx
        with ctx.panels.tabs.add_tab("Optimize", viser.Icon.CHART_DOTS):
            self.notes.add(self.client.gui, "The optimiser")
            self.optimize = OptimizePanel(
                self.client.gui, ctx.jobs, client=ctx.job_client,
                get_design=lambda: ctx.state.design, load_design=self.design_controller.load_design,
                get_joints=lambda: ctx.state.joints,
                cache=self.explorer.study_cache, results=self.explorer.optimize_results,
                on_settings_change=lambda _q: self.share_controller.schedule_url())
        self.notes.attach("The optimiser", (self.optimize.run_button,))
        self.share_controller.optimize = self.optimize
        if self.optimize_query:
            ctx.url_messages += self.optimize.apply_query(self.optimize_query)

    def _set_pins(self, designs: tuple[Design, ...]) -> None:
        """The Compare tab's pinned designs changed: they go into the state and the link."""
        self.ctx.update_state(pins=tuple(designs))
        self.share_controller.schedule_url()

    def _show_task_line(self, line: str | None) -> None:
        """The Task tab's answer in the Numbers panel."""
        self.ctx.task_line = line
        self.numbers.render()

    def _set_task(self, task: TaskLink | None) -> None:
        """The Task tab's region task (or none): it goes into the state and the link."""
        self.ctx.update_state(task=task)
        self.share_controller.schedule_url()

    def _current_indices(self) -> tuple[float, float, bool, bool] | None:
        """TI_1, TI_2 (and whether each is a lower bound) of the orientation maps on screen, when they
        are of the current design and settings."""
        from .compare_panel import index_row

        ctx = self.ctx
        with ctx.lock:
            ori, s = ctx.orientation, ctx.state
        if ori is None or ori.design != s.design or ori.settings != s.orientation_settings():
            return None
        return index_row(ori)

    def _after_measures(self) -> None:
        """The full result's measures are on screen: the Compare table follows (its buttons keep the
        selector's notes: disabled for another mechanism than the paper's)."""
        link = self.ctx.state.mechanism
        self.compare.set_mechanism(None if link is None else link.label)
        self.compare.refresh()
        self.notes.show(link)

    def _show_result(self, r: Any) -> None:
        """Stop went back to the result on screen: its design or mechanism into the controls."""
        self.design_controller.show_result(r)
        self.mechanism_controller.show(self.ctx.state.mechanism)

    def _after_stop(self) -> None:
        """Stop put the state back to the shell on screen: the mechanism and the link follow."""
        self.pose_controller.update_mechanism()
        self.share_controller.schedule_url()

    # ----- teardown --------------------------------------------------------------------------------
    def close(self) -> None:
        """The browser left: cancel its jobs and timers."""
        self.ctx.closed = True
        self.plot_gate.close()
        self.share_controller.close()
        self.design_controller.close()
        for job in self.explorer.jobs.active(self.ctx.job_client):
            self.explorer.jobs.cancel(job.id)

    # ----- what the session shows (the shared context) --------------------------------------------
    state = _shared("state", "The current :class:`~app.urlstate.ExplorerState`.")
    panels = _shared("panels", "The GUI handles (:class:`~app.panels.Panels`).")
    shell = _shared("shell", "The shell in the scene (:class:`~app.scene.ShellScene`).")
    bundle = _shared("bundle", "The full workspace on screen (:class:`~app.workspace_job.ShellBundle`).")
    preview = _shared("preview", "The last preview shown.")
    resolution = _shared("resolution", "The pose's IK on screen.")
    in_workspace = _shared("in_workspace", "Whether the pose is inside the workspace.")
    orientation = _shared("orientation", "The orientation maps on screen.")
    design_error = _shared("design_error", "Why the last design input was not applied (or ``None``).")
    payloads = _shared("payloads", "GLB bytes of the last preview/full shell sent.")
    events = _shared("events", "(time, what) of what happened, for tests and benchmarks.")
    closed = _shared("closed", "The browser has left.")
    jobs = _shared("jobs", "The job manager as this session sees it (:class:`~app.session.SessionJobs`).")
    job_client = _shared("job_client", "This session's client name in the job manager.")
    lock = _shared("lock", "The session's state lock.")
    url_messages = _shared("url_messages", "Problems of the link the page was opened with.")

    @property
    def mechanism(self) -> MechanismScene:
        """The mechanism in the scene (:class:`~app.scene.MechanismScene`)."""
        return self.pose_controller.mechanism

    @property
    def gizmo(self) -> viser.TransformControlsHandle:
        """The drag gizmo on the platform."""
        return self.pose_controller.gizmo


# --------------------------------------------------------------------------------------------
# the server


#: Seconds a page's first plot waits for the browser to draw the first shell (the plot gate of
#: :mod:`paraspace.app.explorer.lazy_plot`); the page itself gives up after 5 s without a shell.
PLOTS_WAIT_SECONDS = 8.0
#: Seconds a new page's browser gets to tell the server its link (``location.search``) before the
#: page is built on the defaults (with a message; its address bar is then never rewritten).
LINK_READ_SECONDS = 60.0


class Explorer:
    """The viser server with one :class:`ClientSession` per browser.

    Args:
        host: interface to bind (default: localhost only).
        port: port (viser moves to the next free one when busy; read :attr:`port`). 0: any free port.
        jobs: the shared :class:`~app.jobs.JobManager` (a private one with 2 workers if ``None``).
        hosts: the host and origin rules of every request (:mod:`paraspace.app.hostcheck`;
            default: the loopback names and ``host``, the page's own origin only).
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 8080, jobs: JobManager | None = None,
                 max_voxels: int = MAX_VOXELS, hosts: HostPolicy | None = None) -> None:
        self.host = host
        self.hosts = hosts  # allowed hosts and origins (app/hostcheck.py); None: the bind address's
        self.max_voxels = max_voxels  # the API's grid limit (app/limits.py), whatever a link asks for
        self._requested_port = port
        self.jobs = jobs if jobs is not None else JobManager(max_workers=2)
        self._own_jobs = jobs is None
        self.server: viser.ViserServer | None = None
        self.sessions: dict[int, ClientSession] = {}
        self._sessions_lock = threading.Lock()
        # bounded by bytes (a voxel-1 result holds ~25 MB of grid): see kinematics/bytecache.py
        self.shell_cache = ByteLRU(256 << 20)
        self.orientation_cache = ByteLRU(64 << 20)
        from paraspace.kinematics.sweep import ResultCache

        self.study_cache = ResultCache(max_entries=1024)
        # finished Optimize runs by settings (a shared link reopens them)
        self.optimize_results = ByteLRU(16 << 20, max_entries=16)
        self.paper_results = ByteLRU(1 << 20)  # the Paper tab's comparison, by voxel (a few kB)
        self.warm = threading.Event()
        #: Seconds a new page's browser gets to tell its link (a busy browser can take many seconds).
        self.link_read_seconds = LINK_READ_SECONDS
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

    def start(self) -> Explorer:
        """Start the viser server (returns at once; the numba kernels warm up in the background)."""
        if self.server is not None:
            return self
        memory.limit_arenas()  # freed memory returns to the system (app/memory.py)
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
        pagehook.set_policy(self.port, self.hosts or HostPolicy.for_server(self.host, explorer_port=self.port))
        return self

    def set_hosts(self, hosts: HostPolicy) -> None:
        """Apply other host and origin rules (:mod:`paraspace.app.hostcheck`) to this explorer's port."""
        self.hosts = hosts
        if self.server is not None:
            pagehook.set_policy(self.port, hosts)

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
            pagehook.clear_policy(self.port)
            self.server.stop()
            self.server = None
        if self._own_jobs:
            self.jobs.shutdown(wait=False)

    def _on_connect(self, client: viser.ClientHandle) -> None:
        """Build the session of a new page on the state of its link. The link (``location.search``)
        is read from the browser before anything is built or written: a busy browser gets
        :attr:`link_read_seconds` to answer. If it never does, the page says so, shows the paper's
        design and its address bar is never rewritten (its link is kept for a reload)."""
        t0 = time.perf_counter()
        loc = jsbridge.read_location(client, timeout=self.link_read_seconds)
        search, base = loc if loc is not None else ("", self.url.rstrip("/") + "/")
        state, messages = parse_query(search)
        if loc is None:
            messages = [f"this page's link could not be read from the browser within {self.link_read_seconds:g} s; "
                        "the paper's default design is shown and the address bar keeps the link: reload the "
                        "page to open it"]
        session = ClientSession(self, client, state, base or self.url, messages, panel_pairs(search))
        session.ctx.link_unread = loc is None
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
                jsbridge.show_panel(client)
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
            # nobody fetches a departed page's job results; then give the freed heap back (app/memory.py)
            self.jobs.forget_client(session.ctx.job_client)
            memory.trim_soon()

    def session(self, client_id: int) -> ClientSession | None:
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
