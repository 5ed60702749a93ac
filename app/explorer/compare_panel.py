"""The explorer's "Compare" tab: pin up to four designs and compare them with the current one.

* **Pin this design** keeps the current design's workspace as a ghost in the 3-D view (a cage of
  height contours in the pin's own colour, :func:`ghost_contours`, readable through and beside the
  current shell's height colours, over a faint surface of the same colour) and its numbers in a
  table across every pinned design and the current one: the parameters (those that differ marked
  ◆), volume, hollowness, void ratio, boundary, extents and, when computed, TI_1 and TI_2 at the
  current orientation-map settings. With one pin the table has a "change" column. The pins travel
  in the link (``pin=...;...``).
* **Unpin** removes the chosen pin; **Unpin all** removes every pin.
* **Fig. 3 pairs**: one click pins the paper's first variant of a pair (``a = 10``, ``d_s = 10``,
  ``eta_s = 10``, ``l_s = 20``) and makes the second (``80``, ``80``, ``60``, ``80``) current, the
  other parameters at the paper's default design; it says what it loaded, and **Undo** puts back
  the design and pins that were there before.
* **Fig. 3 views** draws the shell of every pinned design and the current one in the paper's four
  views (isometric, top, bottom, side) as a small-multiples grid (:func:`app.report.shell_views_png`).

Each pinned workspace is computed with the current orientation, voxel edge and joint options (a
background job, cached like every shell); the table's current column follows the current design.
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import viser

from paraspace.kinematics.design import PARAMS, Design
from paraspace.kinematics.progress import Cancelled

from .. import figures
from ..jobs import Job, JobManager, LimitExceeded
from ..numfmt import significant
from ..textsafe import md_text
from ..urlstate import MAX_PINS
from .scene import glb_with_material, remove_node
from .session import SessionJobs

if TYPE_CHECKING:  # pragma: no cover - types only
    from ..urlstate import ExplorerState
    from .workspace_job import ShellBundle

#: The paper's Fig. 3 pairs: parameter, first (pinned) and second (current) value.
FIG3_PAIRS: tuple[tuple[str, float, float], ...] = (("a", 10.0, 80.0), ("d_s", 10.0, 80.0),
                                                    ("eta_s", 10.0, 60.0), ("l_s", 20.0, 80.0))
#: The pins' colours, in pin order (RGBA), with their names for the legend and the table: colours no
#: other element of the view uses (legs are blue/orange/red, the platform green, the total-orientation
#: workspace purple).
PIN_COLOURS: tuple[tuple[str, tuple[int, int, int, int]], ...] = (
    ("magenta", (214, 0, 147, 255)), ("brown", (140, 81, 10, 255)), ("olive", (128, 128, 0, 255)),
    ("cyan", (0, 170, 200, 255)))
GHOST_COLOR = PIN_COLOURS[0][1]
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


def _cell(v: Any, digits: int | None) -> str:
    if digits is None:
        return "yes" if v else "no"
    return significant(v, digits)


def comparison_table(pinned: Sequence[ShellBundle], current: ShellBundle,
                     indices: Sequence[tuple[Any, ...]] | None = None) -> str:
    """Markdown table of the pinned bundles (in pin order) and the current one: the design
    parameters (those that differ across the columns marked ◆), then :data:`ROWS`, then TI_1 and
    TI_2 when ``indices`` (one ``(TI_1, TI_2[, TI_1 is a lower bound, TI_2 is a lower bound])``
    per column, pins first) are given. With one pin a
    "change" column gives current minus pinned (absolute and relative)."""
    cols = list(pinned) + [current]
    names = [f"pin {k + 1} ({PIN_COLOURS[k % len(PIN_COLOURS)][0]})" for k in range(len(pinned))] + ["current"]
    one = len(pinned) == 1
    lines = ["| | " + " | ".join(names) + (" | change |" if one else " |"),
             "|---" * (len(cols) + 1 + one) + "|"]

    def change_of(a: float, b: float) -> str:
        diff = float(b) - float(a)
        rel = f" ({100.0 * diff / abs(a):+.0f} %)" if a else ""
        return f" {'+' if diff > 0 else ''}{significant(diff, 3)}{rel} |"

    def row(label: str, vals: list[Any], digits: int | None) -> None:
        text = [_cell(v, digits) for v in vals]
        change = ""
        if one:
            a, b = vals
            if digits is None:
                change = " same |" if bool(a) == bool(b) else " changed |"
            else:
                change = change_of(a, b)
        lines.append(f"| {label} | " + " | ".join(text) + " |" + change)

    for key, spec in PARAMS.items():
        vals = [getattr(b.result.design, key) for b in cols]
        mark = " ◆" if len(set(vals)) > 1 else ""
        row(f"{md_text(spec.label)}{mark}", vals, 4)
    for label, get, digits in ROWS:
        try:
            vals = [get(b) for b in cols]
        except AttributeError:
            continue
        row(label, vals, digits)
    lower = False
    if indices is not None and len(indices) == len(cols):
        for k, label in ((0, "TI₁ (deg·units)"), (1, "TI₂ (deg·units)")):
            text = []
            bounds = []
            for ti in indices:
                value, bound = ti[k], ti[2 + k] if len(ti) > 2 else False
                lower = lower or bool(bound)
                bounds.append(bool(bound))
                text.append(("≥ " if bound else "") + significant(value, 4))
            change = ""
            if one:  # a difference with a lower bound is no difference of the indices
                change = " (a lower bound) |" if any(bounds) else change_of(indices[0][k], indices[1][k])
            lines.append(f"| {label} | " + " | ".join(text) + " |" + change)
    return ("\n".join(lines) + "\n\n◆ the parameters that differ"
            + ("; ≥ a lower bound: the rotation range reaches the scan's ends (Plots tab: widen the scan)" if lower
               else ""))


def index_row(ori: Any) -> tuple[float, float, bool, bool]:
    """``(TI_1, TI_2, TI_1 is a lower bound, TI_2 is a lower bound)`` of orientation maps (a lower
    bound where a rotation range reaches the scan's ends, :func:`app.figures.orientation_saturation`)."""
    sat = {x.index for x in figures.orientation_saturation(ori)}
    return float(ori.ti1), float(ori.ti2), "TI_1" in sat, "TI_2" in sat


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


def ghost_glb(mesh: Any, colour: tuple[int, int, int, int] = GHOST_COLOR) -> bytes:
    """The pinned shell as one translucent surface of ``colour`` (a GLB)."""
    m = mesh.copy()
    m.visual.vertex_colors = np.tile(np.array(colour, np.uint8), (len(m.vertices), 1))
    return glb_with_material(m.export(file_type="glb", include_normals=True), GHOST_OPACITY)


@dataclasses.dataclass
class CompareHooks:
    """What the panel needs from its session (kept narrow: state in, state out)."""

    get_state: Callable[[], ExplorerState]
    set_pins: Callable[[tuple[Design, ...]], None]  # stores the pins in the state and the link
    bundle_for: Callable[[ExplorerState], ShellBundle | None]  # the cached bundle with measures, or None
    compute_bundle: Callable[[ExplorerState, Callable[[float, str], None], threading.Event], ShellBundle]
    current_bundle: Callable[[], ShellBundle | None]
    load_design: Callable[[Design], None]
    notify: Callable[[str, str], None]
    #: the current design's TI_1, TI_2 on screen (``None`` until its orientation maps are in)
    current_indices: Callable[[], tuple[float, float, bool, bool] | None] = lambda: None


@dataclasses.dataclass
class Pin:
    """One pinned design: its workspace once computed, its indices, its ghost's scene nodes."""

    design: Design
    colour: tuple[int, int, int, int]
    bundle: ShellBundle | None = None
    indices: tuple[float, float, bool, bool] | None = None  # TI_1, TI_2 and whether each is a lower bound
    job: Job | None = None
    handle: Any | None = None
    cage: Any | None = None
    #: what the ghost on screen shows: (node name, colour, bundle), so the same ghost is not sent twice
    shown: tuple[str, tuple[int, int, int, int], Any] | None = None


class ComparePanel:
    """The Compare tab of one browser (module docstring)."""

    NODE = "/workspace/pinned"

    def __init__(self, gui: viser.GuiApi, scene: viser.SceneApi, jobs: JobManager | SessionJobs, client: str,
                 hooks: CompareHooks) -> None:
        self.gui = gui
        self.scene = scene
        self.jobs = jobs
        self.client = client
        self.hooks = hooks
        self.pins: list[Pin] = []
        self.lock = threading.Lock()
        #: one ghost drawn at a time (the GUI thread and a pin's job may both redraw)
        self.ghost_lock = threading.RLock()
        self.undo_state: tuple[Design, tuple[Design, ...]] | None = None
        self.views_job: Job | None = None
        self.view_images: list[Any] = []
        #: the selected mechanism's label while it is not the paper's: the pins (paper designs) stay
        #: pinned and in the link, but their ghosts and table wait until the paper's mechanism is back
        self.other_mechanism: str | None = None
        #: refreshes run on several threads (GUI callbacks, the ends of pins' jobs, the session when the
        #: current design's measures arrive): each takes a number with its snapshot, and one whose
        #: snapshot is older than the last one written writes nothing, so a late refresh of an older
        #: state never puts back an older table (as the Numbers panel)
        self._taken = 0
        self._written = 0
        self._write_lock = threading.Lock()
        gui.add_markdown(f"Pin up to {MAX_PINS} designs: each keeps its workspace as a ghost in its own colour "
                         "(height contours over a faint surface) and its numbers beside the current design's.")
        self.pin_button = gui.add_button("Pin this design", icon=viser.Icon.PIN)
        self.unpin_choice: Any = gui.add_dropdown("pin to remove", ("pin 1",), initial_value="pin 1", disabled=True)
        self.unpin_button = gui.add_button("Unpin", icon=viser.Icon.PINNED_OFF, disabled=True)
        self.unpin_all_button = gui.add_button("Unpin all", icon=viser.Icon.PINNED_OFF, disabled=True)
        self.show_ghost = gui.add_checkbox("show the pinned workspaces", True)
        self.pairs = gui.add_button_group("Fig. 3 pairs", [f"{p} {a:g}|{b:g}" for p, a, b in FIG3_PAIRS],
                                          hint="pin the paper's first variant and make the second current "
                                               "(the other parameters at the paper's default); Undo puts back "
                                               "your design")
        self.undo_button = gui.add_button("Undo the pair", icon=viser.Icon.ARROW_BACK_UP, visible=False)
        self.pair_note = gui.add_markdown("", visible=False)
        self.title = gui.add_markdown("*nothing pinned*")
        self.table = gui.add_markdown("")
        self.views_button = gui.add_button("Fig. 3 views of these designs", icon=viser.Icon.LAYOUT_GRID,
                                           hint="the shell of every pinned design and the current one in the "
                                                "paper's four views (isometric, top, bottom, side)")
        self.views_status = gui.add_markdown("")
        self.views_folder = gui.add_folder("Fig. 3 views", expand_by_default=True, visible=False)
        self.pin_button.on_click(lambda _e: self.pin(self.hooks.get_state().design))
        self.unpin_button.on_click(lambda _e: self.unpin_index(int(str(self.unpin_choice.value).split()[-1]) - 1))
        self.unpin_all_button.on_click(lambda _e: self.unpin())
        self.show_ghost.on_update(lambda _e: self._show_ghosts())
        self.pairs.on_click(lambda _e: self.load_pair(str(self.pairs.value)))
        self.undo_button.on_click(lambda _e: self.undo_pair())
        self.views_button.on_click(lambda _e: self.draw_views())

    # ----- compatibility: the first pin ----------------------------------------------------------
    @property
    def pinned(self) -> ShellBundle | None:
        """The first pin's bundle (``None`` without a pin or before it is computed)."""
        with self.lock:
            return self.pins[0].bundle if self.pins else None

    @property
    def handle(self) -> Any | None:
        with self.lock:
            return self.pins[0].handle if self.pins else None

    @property
    def cage(self) -> Any | None:
        with self.lock:
            return self.pins[0].cage if self.pins else None

    # ----- actions ------------------------------------------------------------------------------
    def pin(self, design: Design) -> None:
        """Pin ``design`` (with the current orientation, voxel and joints), after the pins there are."""
        with self.lock:
            designs = [p.design for p in self.pins]
        if design in designs:
            self.hooks.notify("Already pinned", f"{design_text(design)} is pin {designs.index(design) + 1}")
            return
        if len(designs) >= MAX_PINS:
            self.hooks.notify("Not pinned", f"at most {MAX_PINS} designs can be pinned; unpin one first")
            return
        self.restore((*designs, design))

    def restore(self, designs: Sequence[Design] | Design | None) -> None:
        """Show the pins of a state (from a link, after :meth:`pin` or an undo): cached, or computed
        in the background. Pins no longer wanted are removed; those kept are not recomputed."""
        if designs is None:
            designs = ()
        elif isinstance(designs, Design):
            designs = (designs,)
        designs = tuple(designs)[:MAX_PINS]
        with self.lock:
            old = {p.design: p for p in self.pins}
            keep = [old.pop(d) if d in old else None for d in designs]
            dropped = list(old.values())
        for p in dropped:
            self._drop(p)
        new_pins = []
        for k, (d, kept) in enumerate(zip(designs, keep)):
            colour = PIN_COLOURS[k % len(PIN_COLOURS)][1]
            if kept is not None and kept.colour != colour:  # its place changed: redraw in its new colour
                self._remove_ghost(kept)
                kept.colour = colour
            new_pins.append(kept if kept is not None else Pin(d, colour))
        with self.lock:
            self.pins = new_pins
        if tuple(self.hooks.get_state().pins) != designs:
            self.hooks.set_pins(designs)
        self.refresh()  # the controls and titles of the new pins before their jobs start
        for p in new_pins:
            if p.bundle is None and (p.job is None or p.job.is_final):
                self._compute(p)
            elif p.bundle is not None and p.handle is None:
                self._show_ghost(p)
        self.refresh()

    def _compute(self, pin: Pin) -> None:
        from paraspace.kinematics.orientation import orientation_workspace

        state = self.hooks.get_state().replace(design=pin.design, pins=())
        osettings = state.orientation_settings()
        hit = self.hooks.bundle_for(state)

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            bundle = hit if hit is not None else self.hooks.compute_bundle(state, progress, cancel)
            ori = orientation_workspace(pin.design, osettings, cancel=cancel)
            return bundle, index_row(ori)

        def done(job: Job) -> None:
            if job.status == "done":
                bundle, indices = job.result
                with self.lock:
                    if pin not in self.pins:
                        return
                    pin.bundle, pin.indices = bundle, indices
                self._show_ghost(pin)
                self.refresh()
            elif job.status == "failed":
                self.hooks.notify("Pinned design not computed", str(job.error))

        if hit is not None:  # the workspace is on hand: show it now, the indices follow
            pin.bundle = hit
            self._show_ghost(pin)
        try:
            pin.job = self.jobs.submit(fn, kind="pin", client=self.client, supersede=False, on_done=done)
        except (LimitExceeded, RuntimeError) as exc:
            self.hooks.notify("Pinned design not computed", str(exc))

    def unpin_index(self, k: int) -> None:
        """Remove pin ``k`` (0-based); the others keep their order (their colours follow their place)."""
        with self.lock:
            designs = [p.design for p in self.pins]
        if 0 <= k < len(designs):
            del designs[k]
            self.restore(tuple(designs))

    def unpin(self) -> None:
        """Forget every pinned design."""
        self.restore(())

    def _drop(self, pin: Pin) -> None:
        if pin.job is not None and not pin.job.is_final:
            self.jobs.cancel(pin.job.id)
        self._remove_ghost(pin)

    def load_pair(self, label: str) -> None:
        """A Fig. 3 pair button: pin the first variant, make the second current, say so, offer Undo."""
        for param, first, second in FIG3_PAIRS:
            if label == f"{param} {first:g}|{second:g}":
                state = self.hooks.get_state()
                self.undo_state = (state.design, tuple(state.pins))
                base = Design()
                self.pair_note.content = (f"Loaded the paper's Fig. 3 pair {md_text(param)} = {first:g} (pinned) "
                                          f"and {md_text(param)} = {second:g} (current), the other parameters at "
                                          "the paper's default; **Undo the pair** puts back your design and pins.")
                self.pair_note.visible = True
                self.undo_button.visible = True
                self.restore((base.replace(**{param: first}),))
                self.hooks.load_design(base.replace(**{param: second}))
                return

    def undo_pair(self) -> None:
        """Put back the design and pins from before the last Fig. 3 pair."""
        if self.undo_state is None:
            return
        design, pins = self.undo_state
        self.undo_state = None
        self.undo_button.visible = False
        self.pair_note.visible = False
        self.restore(pins)
        self.hooks.load_design(design)

    # ----- display ------------------------------------------------------------------------------
    def _update_controls(self, designs: Sequence[Design], other: str | None) -> None:
        """The pin and unpin controls and the pins' titles for the pins ``designs``, with the mechanism
        ``other`` selected (``None``: the paper's; another one cannot be pinned, as its note says)."""
        n = len(designs)
        options = tuple(f"pin {k + 1}" for k in range(max(n, 1)))
        self.unpin_choice.options = options
        if self.unpin_choice.value not in options:
            self.unpin_choice.value = options[-1]
        self.unpin_choice.disabled = self.unpin_button.disabled = self.unpin_all_button.disabled = n == 0
        self.pin_button.disabled = n >= MAX_PINS or other is not None
        if n == 0:
            self.title.content = "*nothing pinned*"
            return
        self.title.content = "  \n".join(
            f"**Pin {k + 1}** ({PIN_COLOURS[k % len(PIN_COLOURS)][0]}): {md_text(design_text(d))}"
            for k, d in enumerate(designs))

    def _remove_ghost(self, pin: Pin) -> None:
        with self.ghost_lock:
            remove_node(pin.handle)
            remove_node(pin.cage)
            pin.handle = pin.cage = None
            pin.shown = None

    def _show_ghosts(self) -> None:
        with self.lock:
            pins = list(self.pins)
        for p in pins:
            self._show_ghost(p)

    def _show_ghost(self, pin: Pin) -> None:
        """Draw ``pin``'s ghost (or take it away when it is hidden or has nothing to show). A ghost
        already on screen for the same node, colour and workspace is kept as it is; a changed one is
        replaced in place (a node added under the same name replaces the old one), so it never blinks."""
        with self.ghost_lock:
            with self.lock:
                k = self.pins.index(pin) if pin in self.pins else None
            mesh = None if pin.bundle is None else pin.bundle.mesh
            if (k is None or self.other_mechanism is not None or not self.show_ghost.value or mesh is None
                    or len(mesh.faces) == 0):
                self._remove_ghost(pin)
                return
            node = self.NODE if k == 0 else f"{self.NODE}_{k + 1}"
            want = (node, pin.colour, pin.bundle)
            if pin.shown is not None and pin.shown[0] == node and pin.shown[1] == pin.colour \
                    and pin.shown[2] is pin.bundle and pin.handle is not None:
                return
            if pin.shown is not None and pin.shown[0] != node:
                self._remove_ghost(pin)  # another place: its old nodes have other names
            glb, cage = ghost_glb(mesh, pin.colour), ghost_contours(mesh)  # both ready before either is shown
            pin.handle = self.scene.add_glb(node, glb, cast_shadow=False, receive_shadow=False)
            if len(cage):
                pin.cage = self.scene.add_line_segments(node + "_cage", cage.astype(np.float32), pin.colour[:3],
                                                        thickness=GHOST_LINE_PX, thickness_units="screen")
            else:
                remove_node(pin.cage)
                pin.cage = None
            pin.shown = want

    def set_mechanism(self, label: str | None) -> None:
        """The selected mechanism (its label, ``None`` for the paper's): the ghosts hide or show again."""
        with self.lock:
            if label == self.other_mechanism:
                return
            self.other_mechanism = label
        self.refresh()  # the table first: once the ghosts are hidden, the table says why
        self._show_ghosts()

    def refresh(self) -> None:
        """Redraw the controls, the titles and the table (the session calls it when the current
        design's measures arrive). The text is built from one snapshot and written only if no
        refresh of a newer snapshot has written before it."""
        with self.lock:
            self._taken += 1
            ticket = self._taken
            pins = list(self.pins)
            other = self.other_mechanism
        table = self._table_text(pins, other)
        with self._write_lock:
            if ticket < self._written:
                return
            self._written = ticket
            self._update_controls([p.design for p in pins], other)
            self.table.content = table

    def _table_text(self, pins: Sequence[Pin], other: str | None) -> str:
        """The table's text for the pins ``pins`` with the mechanism ``other`` selected (``None``: the
        paper's) and the current design as the session has it now."""
        if not pins:
            return ""
        if other is not None:
            which = f"The {len(pins)} pinned designs are" if len(pins) > 1 else "The pinned design is"
            return (f"*{which} of the paper's mechanism, not the {md_text(other)} mechanism: "
                    "shown again when the Mechanism is paper.*")
        if any(p.bundle is None or p.bundle.measures is None for p in pins):
            return "*pinned designs: computing...*"
        current = self.hooks.current_bundle()
        # the shell on screen may still be another mechanism's (the paper's was selected again and its
        # workspace is on its way): its column waits for it, as for measures not in yet
        if (current is None or current.measures is None or current.mechanism is not None
                or current.result.design is None):
            return "*current design: computing...*"
        indices = [p.indices for p in pins] + [self.hooks.current_indices()]
        ok = all(i is not None for i in indices)
        return (f"current: {md_text(design_text(current.result.design))}\n\n"
                + comparison_table([p.bundle for p in pins if p.bundle is not None], current,
                                   indices if ok else None)  # type: ignore[arg-type]
                + ("" if ok else "\n\n*TI₁, TI₂: computing...*"))

    def draw_views(self) -> None:
        """The small-multiples grid: every pinned design's shell and the current one in the four
        Fig. 3 views, drawn in a background job and shown below the button."""
        from ..report import shell_views_png

        with self.lock:
            cols = [(f"pin {k + 1} ({PIN_COLOURS[k % len(PIN_COLOURS)][0]})", p.bundle)
                    for k, p in enumerate(self.pins)]
        cols.append(("current", self.hooks.current_bundle()))
        if any(b is None for _, b in cols):
            self.views_status.content = "*wait until every design's workspace is computed*"
            return

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            out = []
            for k, (name, b) in enumerate(cols):
                if cancel.is_set():
                    raise Cancelled()
                progress(k / len(cols), f"drawing {name}")
                out.append((name, shell_views_png(b.result)))  # type: ignore[union-attr]
            return out

        def done(job: Job) -> None:
            self.views_button.disabled = False
            if job.status != "done":
                self.views_status.content = f"*views not drawn ({job.status})*"
                return
            for h in self.view_images:
                h.remove()
            self.view_images = []
            import io

            from PIL import Image

            with self.views_folder:
                for name, png in job.result:
                    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
                    self.view_images.append(self.gui.add_image(img, label=f"{name}: isometric, top, bottom, side",
                                                               format="png"))
            self.views_folder.visible = True
            self.views_status.content = f"{len(job.result)} designs, four views each, below"

        self.views_button.disabled = True
        self.views_status.content = "drawing the views..."
        try:
            self.views_job = self.jobs.submit(fn, kind="views", client=self.client, supersede=True, on_done=done)
        except (LimitExceeded, RuntimeError) as exc:
            self.views_button.disabled = False
            self.views_status.content = f"views not started: {md_text(str(exc))}"
