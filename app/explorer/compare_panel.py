"""The explorer's "Compare" tab: pin a design and compare it with the current one.

* **Pin this design** keeps the current design's workspace as a ghost in the 3-D view (a cage of
  magenta height contours, :func:`ghost_contours`, readable through and beside the current shell's
  height colours, over a faint magenta surface) and its numbers in a table: pinned | current |
  change. The pinned design travels in the link (``pin=...``).
* **Fig. 3 pairs**: one click pins the paper's first variant of a pair (``a = 10``, ``d_s = 10``,
  ``eta_s = 10``, ``l_s = 20``) and makes the second (``80``, ``80``, ``60``, ``80``) current, the
  other parameters at the paper's default design.

The pinned workspace is computed with the current orientation, voxel edge and joint options (a
background job, cached like every shell); the table's current column follows the current design.
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import viser

from paraspace.kinematics.design import Design

from ..jobs import Job, JobManager, LimitExceeded
from ..numfmt import significant
from ..textsafe import md_text
from .scene import glb_with_material, remove_node
from .session import SessionJobs

if TYPE_CHECKING:  # pragma: no cover - types only
    from ..urlstate import ExplorerState
    from .workspace_job import ShellBundle

#: The paper's Fig. 3 pairs: parameter, first (pinned) and second (current) value.
FIG3_PAIRS: tuple[tuple[str, float, float], ...] = (("a", 10.0, 80.0), ("d_s", 10.0, 80.0),
                                                    ("eta_s", 10.0, 60.0), ("l_s", 20.0, 80.0))
GHOST_COLOR = (214, 0, 147, 255)  # magenta: no other element of the view uses it
GHOST_OPACITY = 0.25
#: Horizontal contours of the ghost's cage, and their width in screen pixels.
GHOST_LEVELS = 12
GHOST_LINE_PX = 2.5

#: Rows of the comparison table: (label, how to read it from a bundle, digits or None for text).
ROWS: tuple[tuple[str, Callable[[Any], Any], int | None], ...] = (
    ("volume V (units³)", lambda b: b.result.volume, 4),
    ("hollowness", lambda b: b.measures.hollowness, 3),
    ("void ratio", lambda b: b.measures.void_ratio, 3),
    ("boundary complete", lambda b: b.measures.boundary_complete, None),
    ("width x (units)", lambda b: b.measures.extents[0], 4),
    ("depth y (units)", lambda b: b.measures.extents[1], 4),
    ("height z (units)", lambda b: b.measures.extents[2], 4),
)


def design_text(d: Design) -> str:
    """``a 50, b 14, d_s 50, r 100, l_min 114.5, l_s 50, eta_s 30°`` (and the arc range if not centered)."""
    t = (f"a {d.a:g}, b {d.b:g}, d_s {d.d_s:g}, r {d.r:g}, l_min {d.l_min:g}, l_s {d.l_s:g}, "
         f"eta_s {d.eta_s:g}°")
    return t + ("" if d.eta_range == "centered" else f" ({d.eta_range})")


def comparison_table(pinned: ShellBundle, current: ShellBundle) -> str:
    """Markdown table pinned | current | change (absolute and relative) of two bundles with measures."""
    lines = ["| | pinned | current | change |", "|---|---|---|---|"]
    for label, get, digits in ROWS:
        try:
            a, b = get(pinned), get(current)
        except AttributeError:
            continue
        if digits is None:
            yes = lambda v: "yes" if v else "no"  # noqa: E731
            lines.append(f"| {label} | {yes(a)} | {yes(b)} | {'same' if bool(a) == bool(b) else 'changed'} |")
            continue
        diff = float(b) - float(a)
        rel = f" ({100.0 * diff / abs(a):+.0f} %)" if a else ""
        sign = "+" if diff > 0 else ""
        lines.append(f"| {label} | {significant(a, digits)} | {significant(b, digits)} | "
                     f"{sign}{significant(diff, 3)}{rel} |")
    return "\n".join(lines)


def ghost_contours(mesh: Any, levels: int = GHOST_LEVELS) -> np.ndarray:
    """The pinned shell's cross-sections by ``levels`` horizontal planes equally spaced strictly
    inside its height range, as line segments (N, 2, 3): the ghost's cage."""
    import trimesh

    if mesh is None or len(mesh.faces) == 0:
        return np.zeros((0, 2, 3))
    z0, z1 = (float(v) for v in mesh.bounds[:, 2])
    segs = [trimesh.intersections.mesh_plane(mesh, (0.0, 0.0, 1.0), (0.0, 0.0, z))
            for z in np.linspace(z0, z1, levels + 2)[1:-1]]
    segs = [np.asarray(g, dtype=float).reshape(-1, 2, 3) for g in segs if len(g)]
    return np.concatenate(segs) if segs else np.zeros((0, 2, 3))


def ghost_glb(mesh: Any) -> bytes:
    """The pinned shell as one translucent magenta surface (a GLB)."""
    m = mesh.copy()
    m.visual.vertex_colors = np.tile(np.array(GHOST_COLOR, np.uint8), (len(m.vertices), 1))
    return glb_with_material(m.export(file_type="glb", include_normals=True), GHOST_OPACITY)


@dataclasses.dataclass
class CompareHooks:
    """What the panel needs from its session (kept narrow: state in, state out)."""

    get_state: Callable[[], ExplorerState]
    set_pin: Callable[[Design | None], None]  # stores the pin in the state and the link
    bundle_for: Callable[[ExplorerState], ShellBundle | None]  # the cached bundle with measures, or None
    compute_bundle: Callable[[ExplorerState, Callable[[float, str], None], threading.Event], ShellBundle]
    current_bundle: Callable[[], ShellBundle | None]
    load_design: Callable[[Design], None]
    notify: Callable[[str, str], None]


class ComparePanel:
    """The Compare tab of one browser (module docstring)."""

    NODE = "/workspace/pinned"

    def __init__(self, gui: viser.GuiApi, scene: viser.SceneApi, jobs: JobManager | SessionJobs, client: str,
                 hooks: CompareHooks) -> None:
        self.scene = scene
        self.jobs = jobs
        self.client = client
        self.hooks = hooks
        self.pinned: ShellBundle | None = None  # of the pinned design
        self.handle: Any | None = None
        self.cage: Any | None = None
        self.job: Job | None = None
        self.lock = threading.Lock()
        gui.add_markdown("Pin a design to keep its workspace as a magenta ghost (height contours over a faint "
                         "surface) and its numbers beside the current design's.")
        self.pin_button = gui.add_button("Pin this design", icon=viser.Icon.PIN)
        self.unpin_button = gui.add_button("Unpin", icon=viser.Icon.PINNED_OFF, disabled=True)
        self.show_ghost = gui.add_checkbox("show the pinned workspace", True)
        self.pairs = gui.add_button_group("Fig. 3 pairs", [f"{p} {a:g}|{b:g}" for p, a, b in FIG3_PAIRS],
                                          hint="pin the paper's first variant, make the second current")
        self.title = gui.add_markdown("*nothing pinned*")
        self.table = gui.add_markdown("")
        self.pin_button.on_click(lambda _e: self.pin(self.hooks.get_state().design))
        self.unpin_button.on_click(lambda _e: self.unpin())
        self.show_ghost.on_update(lambda _e: self._show_ghost())
        self.pairs.on_click(lambda _e: self.load_pair(str(self.pairs.value)))

    # ----- actions ------------------------------------------------------------------------------
    def pin(self, design: Design) -> None:
        """Pin ``design`` (with the current orientation, voxel and joints)."""
        self.hooks.set_pin(design)
        self.restore(design)

    def restore(self, design: Design | None) -> None:
        """Show the pin of a state (from a link or after :meth:`pin`): cached, or computed in the background."""
        if design is None:
            self.unpin()
            return
        state = self.hooks.get_state().replace(design=design)
        self.title.content = f"**Pinned:** {md_text(design_text(design))} *(computing...)*"
        self.unpin_button.disabled = False
        hit = self.hooks.bundle_for(state)
        if hit is not None:
            self._set_pinned(hit)
            return

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            return self.hooks.compute_bundle(state, progress, cancel)

        def done(job: Job) -> None:
            if job.status == "done":
                self._set_pinned(job.result)
            elif job.status == "failed":
                self.hooks.notify("Pinned design not computed", str(job.error))

        try:
            job = self.jobs.submit(fn, kind="pin", client=self.client, supersede=True, on_done=done)
        except (LimitExceeded, RuntimeError) as exc:
            self.hooks.notify("Pinned design not computed", str(exc))
            return
        with self.lock:
            self.job = job

    def unpin(self) -> None:
        """Forget the pinned design."""
        with self.lock:
            job, self.job = self.job, None
            self.pinned = None
        if job is not None and not job.is_final:
            self.jobs.cancel(job.id)
        if self.hooks.get_state().pin is not None:
            self.hooks.set_pin(None)
        self._remove_ghost()
        self.unpin_button.disabled = True
        self.title.content = "*nothing pinned*"
        self.table.content = ""

    def load_pair(self, label: str) -> None:
        """A Fig. 3 pair button: pin the first variant, make the second current."""
        for param, first, second in FIG3_PAIRS:
            if label == f"{param} {first:g}|{second:g}":
                base = Design()
                self.pin(base.replace(**{param: first}))
                self.hooks.load_design(base.replace(**{param: second}))
                return

    # ----- display ------------------------------------------------------------------------------
    def _set_pinned(self, bundle: ShellBundle) -> None:
        with self.lock:
            self.pinned = bundle
        self.title.content = f"**Pinned:** {md_text(design_text(bundle.result.design))}"
        self._show_ghost()
        self.refresh()

    def _remove_ghost(self) -> None:
        remove_node(self.handle)
        remove_node(self.cage)
        self.handle = self.cage = None

    def _show_ghost(self) -> None:
        pinned = self.pinned
        self._remove_ghost()
        if pinned is None or not self.show_ghost.value or pinned.mesh is None or len(pinned.mesh.faces) == 0:
            return
        self.handle = self.scene.add_glb(self.NODE, ghost_glb(pinned.mesh), cast_shadow=False, receive_shadow=False)
        cage = ghost_contours(pinned.mesh)
        if len(cage):
            self.cage = self.scene.add_line_segments(self.NODE + "_cage", cage.astype(np.float32), GHOST_COLOR[:3],
                                                     thickness=GHOST_LINE_PX, thickness_units="screen")

    def refresh(self) -> None:
        """Redraw the table (the session calls it when the current design's measures arrive)."""
        pinned, current = self.pinned, self.hooks.current_bundle()
        if pinned is None or pinned.measures is None:
            return
        if current is None or current.measures is None:
            self.table.content = "*current design: computing...*"
            return
        self.table.content = (f"current: {md_text(design_text(current.result.design))}\n\n"
                              + comparison_table(pinned, current))
