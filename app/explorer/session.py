"""What one browser's explorer shares between its panel controllers: :class:`SessionContext`.

Every browser (viser client) gets one context: its GUI and scene handles, the current
:class:`~app.urlstate.ExplorerState` (the ``state`` of the data path slider -> state -> job ->
engine -> mesh -> scene), the results on screen (shell, preview, IK, orientation maps), the locks
that order concurrent callbacks, the session's view of the job manager (:class:`SessionJobs`) and
the small helpers every controller uses (:meth:`SessionContext.programmatic`,
:meth:`SessionContext.callback`, :meth:`SessionContext.notify`, :meth:`SessionContext.event`), and
:class:`NewestMessage`, which keeps a control's newest client value from a server write's race.

It holds state, not behaviour: what a panel does lives in its controller (``app/*_controller.py``,
``app/numbers_panel.py``), which reads and writes this context. Lock order: ``view_lock`` before
``lock``; ``input_lock`` is taken only by GUI callbacks (never by job threads) and before ``lock``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import threading
import time
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any, Generic, Protocol, TypeVar

import viser

from paraspace.kinematics.redundancy import Resolution

from ..jobs import Job, JobManager
from ..textsafe import plain_text
from ..urlstate import MAX_PINS, ExplorerState

if TYPE_CHECKING:  # pragma: no cover - types only
    from paraspace.kinematics.bracket import VolumeBracket
    from paraspace.kinematics.bytecache import ByteLRU
    from paraspace.kinematics.measures import WorkspaceMeasures
    from paraspace.kinematics.orientation import OrientationResult
    from paraspace.kinematics.sweep import ResultCache

    from .panels import Panels
    from .scene import ShellScene
    from .workspace_job import ShellBundle

log = logging.getLogger(__name__)

#: Smallest interval between two progress updates of one bar, seconds (see SessionContext.throttled).
PROGRESS_INTERVAL = 0.25

T = TypeVar("T")


class NewestMessage(Generic[T]):
    """The value of a control's newest client message, until a callback takes it.

    viser stores a client's value in the control's handle and then runs the handle's callbacks: a
    coroutine at once, on its event loop and in the order of the messages; a plain function later, on
    a thread. A write of the same handle by the server on another thread in between (a colour job's
    failure resetting the shell colour, the drag before's pose written into the gizmo, Stop's controls)
    replaces the client's value before the thread callback reads it, and that input is lost: CI saw it
    twice (a second selection of the mechanism, a gizmo drag). :meth:`watch` records ``read()`` on the
    event loop for every client message; the thread callback takes the newest record (:meth:`take`) and
    clears it in one locked step (a record falling between a read and a clear would be lost too).
    ``take`` returns ``None`` when an earlier callback already took it.
    """

    def __init__(self, read: Callable[[], T]) -> None:
        self._read = read
        self._value: T | None = None
        self._lock = threading.Lock()

    def watch(self, handle: Any) -> None:
        """Record ``read()`` whenever a client's message changes ``handle`` (call it before the
        handle's thread callbacks are attached)."""
        async def record(event: Any) -> None:
            if event.client is not None:
                value = self._read()
                with self._lock:
                    self._value = value
        handle.on_update(record)

    def take(self) -> T | None:
        """The newest recorded value, cleared in the same step; ``None`` if there is none."""
        with self._lock:
            value, self._value = self._value, None
        return value

    def peek(self) -> T | None:
        """The newest recorded value, left in place (for tests)."""
        with self._lock:
            return self._value


class ExplorerServices(Protocol):
    """What a browser's session uses of the server that owns it (:class:`~app.explorer.Explorer`)."""

    jobs: JobManager
    server: viser.ViserServer | None
    max_voxels: int
    shell_cache: ByteLRU
    orientation_cache: ByteLRU
    study_cache: ResultCache


@dataclasses.dataclass(frozen=True)
class ShellInfo:
    """The shell on screen, as the numbers panel shows it.

    Attributes:
        volume: the workspace volume, units³ (voxel count times ``h³``).
        h: the voxel edge of the grid it was computed on.
        preview: a coarse preview (``True``) or the full result.
        seconds: the workspace computation time, s.
        shell_seconds: the display shell's construction time, s.
        gen: the workspace controller's generation that published it (a newer one supersedes it).
        cached: it came from the shared result cache.
        measures: its measures, ``None`` until they are computed.
        bracket: its certified volume bracket, ``None`` unless asked for and computed.
        stopped: the user stopped the job before its measures were computed (they are not coming).
        bracket_note: why the certified bracket is not coming (its job was refused or failed), or ``None``.
    """

    volume: float
    h: float
    preview: bool
    seconds: float
    shell_seconds: float
    gen: int
    cached: bool
    measures: WorkspaceMeasures | None = None
    bracket: VolumeBracket | None = None
    stopped: bool = False
    bracket_note: str | None = None


#: The kinds of job a browser's session runs, each superseding its predecessor (at most one
#: unfinished job per kind), and ``"pin"``, one job per pinned design (at most ``MAX_PINS``).
SESSION_JOB_KINDS = frozenset({
    "workspace", "bracket", "orientation", "views", "dexterous", "optimize", "paper", "report",
    "task", "tilt", "usage", "dexterity", "sweep", "surface"})

#: A session's limit of unfinished jobs: what its own controls can have running at once, so the
#: jobs that follow a result (orientation maps, the certified bracket, the pins) are never refused
#: because of each other. The manager's total limit still bounds all browsers together.
SESSION_JOB_LIMIT = len(SESSION_JOB_KINDS) + MAX_PINS


class SessionJobs:
    """The job manager as one browser's session sees it: the same jobs, but progress and completion
    callbacks are dropped once the browser has left (no GUI writes to a closed connection), and
    the client's limit is :data:`SESSION_JOB_LIMIT` (each kind of :data:`SESSION_JOB_KINDS`
    supersedes its last job; pins are bounded by ``MAX_PINS``)."""

    def __init__(self, jobs: JobManager, is_closed: Callable[[], bool]) -> None:
        self._jobs = jobs
        self._closed = is_closed

    def submit(self, fn: Any, *, kind: str, supersede: bool = False, on_done: Callable[[Job], None] | None = None,
               on_progress: Callable[[Job], None] | None = None, **kw: Any) -> Job:
        if kind == "pin":
            if supersede:
                raise ValueError("pin jobs never supersede each other (one per pinned design)")
        elif kind not in SESSION_JOB_KINDS or not supersede:
            raise ValueError(f"session job kind {kind!r} must be one of SESSION_JOB_KINDS and supersede "
                             "its last job, so that SESSION_JOB_LIMIT bounds the session's jobs")

        def alive(cb: Callable[[Job], None] | None) -> Callable[[Job], None] | None:
            if cb is None:
                return None
            return lambda job: None if self._closed() else cb(job)
        return self._jobs.submit(fn, kind=kind, supersede=supersede, on_done=alive(on_done),
                                 on_progress=alive(on_progress), client_limit=SESSION_JOB_LIMIT, **kw)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._jobs, name)


class SessionContext:
    """State, handles and helpers of one browser, shared by its panel controllers (module docstring).

    Args:
        explorer: the owning :class:`~app.explorer.Explorer` (shared job manager, caches, grid limit).
        client: the viser client.
        state: initial state (from the link).
        base_url: the page's URL without query (for the Share tab's link).
        messages: problems found in the link (shown on screen).
    """

    def __init__(self, explorer: ExplorerServices, client: viser.ClientHandle, state: ExplorerState,
                 base_url: str, messages: list[str]) -> None:
        self.explorer = explorer
        self.client = client
        self.job_client = f"viser-{client.client_id}"
        self.jobs = SessionJobs(explorer.jobs, lambda: self.closed)
        self.lock = threading.RLock()
        self.view_lock = threading.Lock()
        self.input_lock = threading.RLock()  # serialises design input (see DesignController.on_design_input)
        self.mech_lock = threading.Lock()
        self.state = state
        self.base_url = base_url
        self.url_messages = list(messages)
        #: The browser never told the page's link: the address bar is never rewritten (it keeps the link).
        self.link_unread = False
        self._closed = False
        self._tls = threading.local()
        self._last_update: dict[str, float] = {}
        # GUI and scene handles (set by ClientSession.build)
        self.panels: Panels
        self.shell: ShellScene | None = None
        # what is on screen (written by the controllers, read by the numbers panel and the downloads)
        self.bundle: ShellBundle | None = None  # full result on screen
        self.preview: ShellBundle | None = None
        self.ws_info: ShellInfo | None = None  # the shell on screen (None before one)
        #: why the workspace of the state on screen is not computed (its grid refused), or None
        self.ws_refused: str | None = None
        self.resolution: Resolution | None = None  # the paper design's IK (None for the selector's mechanism)
        self.mechanism_ik: list[Any] | None = None  # the selector's mechanism: mechanism_ik per chain
        self.mechanism_pose: Any = None  # ... and its drawing's geometry (app/mechanism_scene.MechanismPose)
        self.in_workspace: bool | None = None
        self.orientation: OrientationResult | None = None  # the orientation maps on screen
        self.design_error: str | None = None
        self.task_line: str | None = None  # the Task tab's answer in one line, for the Numbers
        self.payloads: dict[str, int] = {}  # GLB bytes of the last preview/full shell sent
        self.events: list[tuple[float, str]] = []  # (time, what) for tests/benchmarks

    # ----- lifetime -----------------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        """The browser has left: the session was closed, or viser no longer lists the client as
        connected. viser closes the connection before it runs the disconnect callbacks (which close
        the session), so a job or timer that writes to the GUI in between must see it here: the
        write would go nowhere (viser warns about it)."""
        if self._closed:
            return True
        server = self.explorer.server
        return server is None or self.client.client_id not in server.get_clients()

    @closed.setter
    def closed(self, value: bool) -> None:
        self._closed = value

    # ----- state --------------------------------------------------------------------------------
    def update_state(self, **changes: Any) -> ExplorerState:
        """Replace fields of the current state (under ``lock``); returns the new state."""
        with self.lock:
            self.state = self.state.replace(**changes)
            return self.state

    # ----- callbacks ----------------------------------------------------------------------------
    @contextlib.contextmanager
    def programmatic(self) -> Iterator[None]:
        """GUI values assigned inside this block do not count as user input (same thread only)."""
        self._tls.depth = getattr(self._tls, "depth", 0) + 1
        try:
            yield
        finally:
            self._tls.depth -= 1

    def is_programmatic(self) -> bool:
        """True inside :meth:`programmatic` on this thread."""
        return getattr(self._tls, "depth", 0) > 0

    def callback(self, fn: Callable[[], None]) -> Callable[[Any], None]:
        """Wrap a handler: ignore programmatic changes and closed sessions; log failures."""
        def handler(_event: Any = None) -> None:
            if self.closed or self.is_programmatic():
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

    def throttled(self, what: str, interval: float) -> bool:
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

    # ----- jobs, messages, events -----------------------------------------------------------------
    def cancel_job(self, job: Job | None) -> None:
        """Cancel ``job`` unless it is ``None`` or finished."""
        if job is not None and not job.is_final:
            self.explorer.jobs.cancel(job.id)

    def event(self, what: str) -> None:
        """Record ``what`` happened now (for tests and benchmarks; the last few hundred are kept)."""
        self.events.append((time.perf_counter(), what))
        if len(self.events) > 500:
            del self.events[:250]

    def notify(self, title: str, body: str, color: str = "red") -> None:
        """A toast on this browser (``body`` shown as plain text)."""
        try:
            self.client.add_notification(title, plain_text(body, 600), auto_close_seconds=8.0,  # type: ignore[call-overload]
                                         color=color)
        except Exception:  # noqa: BLE001
            log.debug("notification failed", exc_info=True)
