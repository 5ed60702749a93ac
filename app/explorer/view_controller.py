"""The View tab: camera presets and Fit view, cut plane and opacity, and the shell's colouring.

The last step of the data path slider -> state -> job -> engine -> mesh -> scene is the scene, and
this module changes only how the scene shows the shell on screen -- never the workspace:
:func:`camera_framing` frames the workspace's box in the part of the window the control panel leaves
free; :meth:`ViewController.on_view_settings` re-sends the shell with a new cut or opacity;
:meth:`ViewController.recolour_shell` swaps the height colours for the local dexterity or the
binding limit (``app/dexterity_colour.py``, computed in a background job for the shell on screen).
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any

import numpy as np

from paraspace.kinematics.workspace import compute_workspace

from ..jobs import Job, LimitExceeded
from ..urlstate import ExplorerState
from .dexterity_colour import (
    COLOUR_MODES,
    DEXTERITY_VOXEL,
    LIMIT_COLOUR_NAMES,
    LIMIT_COLOURS,
    USAGE_MODES,
    binding_labels,
    field_colours,
    values_colours,
)
from .session import NewestMessage, SessionContext
from .workspace_job import ShellBundle, ws_settings

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


class ViewController:
    """Camera, cut, opacity and shell colour of one session (module docstring).

    Args:
        ctx: the session's shared state (the shell on screen is ``ctx.shell`` / ``ctx.bundle``).
        on_state_change: called after a view setting changed the state (the link follows).
    """

    def __init__(self, ctx: SessionContext, *, on_state_change: Callable[[], None]) -> None:
        self.ctx = ctx
        self.on_state_change = on_state_change
        self.show_grid: Callable[[bool], None] | None = None  # the floor grid's visibility (the mechanism's)
        #: the shell colour of the user's newest choice, until a callback applies it: a colour job that
        #: fails writes the height mode into the dropdown from its thread, which could replace a choice
        #: made meanwhile before its callback read it (NewestMessage)
        self.colour_chosen: NewestMessage[str] = NewestMessage(lambda: str(self.ctx.panels.shell_colour.value))

    def wire(self) -> None:
        """Attach the View tab's controls."""
        p, cb = self.ctx.panels, self.ctx.callback
        p.view_buttons.on_click(cb(lambda: self.on_view(str(p.view_buttons.value))))
        p.fit_view.on_click(cb(self.fit_view))
        self.colour_chosen.watch(p.shell_colour)
        p.shell_colour.on_update(cb(self.recolour_shell))
        for h in (p.cut, p.cut_z, p.cut_keep, p.opacity):
            h.on_update(cb(self.on_view_settings))

    # ----- camera ---------------------------------------------------------------------------------
    def _framing_box(self) -> tuple[np.ndarray, np.ndarray]:
        """The box to frame: the shell's (or, before one exists, the reach of the design); for a
        mechanism of the selector, together with its drawing (base and platform joints)."""
        mesh = self.ctx.shell.source if self.ctx.shell is not None else None
        drawn = self.ctx.mechanism_pose if self.ctx.state.mechanism is not None else None
        if drawn is not None:
            pts = np.vstack([drawn.base, drawn.top] + ([mesh.vertices] if mesh is not None and len(mesh.vertices)
                                                       else []))
            return pts.min(axis=0), pts.max(axis=0)
        if mesh is not None and len(mesh.vertices):
            return mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
        d = self.ctx.state.design
        R = d.r + 0.6 * d.l_max
        return np.array([-R, -R, 0.0]), np.array([R, R, d.l_max])

    def set_camera(self, preset: str) -> None:
        """Move this client's camera to a preset (iso, top, bottom, side) framing the workspace's box
        (see :func:`camera_framing`; the control panel's share of the window is left free)."""
        lo, hi = self._framing_box()
        client = self.ctx.client
        cam = client.camera
        try:
            fov, aspect = float(cam.fov), float(cam.aspect)
        except Exception:  # noqa: BLE001 - before the browser reported its camera
            fov, aspect = math.radians(50.0), 16.0 / 9.0
        position, look_at = camera_framing(lo, hi, preset, fov, aspect)
        if self.show_grid is not None:  # from below, the floor grid would only hide the workspace's underside
            self.show_grid(preset != "bottom")
        with client.atomic():
            cam.up_direction = (0.0, 0.0, 1.0)
            # position first: viser moves look_at along with the position, then aims at look_at
            cam.position = tuple(position)
            cam.look_at = tuple(look_at)

    def fit_view(self) -> None:
        """The Fit view button: frame the workspace with the current preset's direction."""
        self.set_camera(self.ctx.state.view)

    def on_view(self, preset: str) -> None:
        """A camera preset button was clicked."""
        self.ctx.update_state(view=preset)
        self.set_camera(preset)
        self.on_state_change()

    # ----- cut and opacity ----------------------------------------------------------------------
    def on_view_settings(self) -> None:
        """Cut plane or opacity changed: re-send the shell on screen (no recomputation)."""
        p = self.ctx.panels
        self.ctx.update_state(cut=bool(p.cut.value), cut_z=float(p.cut_z.value), cut_keep=str(p.cut_keep.value),
                              opacity=float(p.opacity.value))
        self.refresh_shell()
        self.on_state_change()

    def refresh_shell(self) -> None:
        """Re-send the shell on screen with the current view settings."""
        ctx = self.ctx
        with ctx.view_lock:
            s = ctx.state
            assert ctx.shell is not None  # built before the controllers are wired
            with ctx.client.atomic():
                size = ctx.shell.refresh(s.opacity, s.cut, s.cut_z, s.cut_keep)
            self.show_payload(size)

    def show_payload(self, size: int) -> None:
        """Say how large the shell on screen is (faces, GLB bytes)."""
        assert self.ctx.shell is not None  # built before the controllers are wired
        self.ctx.panels.payload.content = (f"shell on screen: {self.ctx.shell.last_faces:,} faces, "
                                           f"{size / 1e6:.2f} MB (GLB)")

    def _show_mesh(self, mesh: Any) -> None:
        ctx = self.ctx
        with ctx.view_lock:
            if ctx.closed:
                return
            s = ctx.state
            assert ctx.shell is not None  # built before the controllers are wired
            with ctx.client.atomic():
                ctx.shell.show(mesh, s.opacity, s.cut, s.cut_z, s.cut_keep)

    # ----- shell colour -------------------------------------------------------------------------
    def recolour_shell(self) -> None:
        """The View tab's "shell colour": height z (the shell's own colours) or the local dexterity
        1/kappa (app/dexterity_colour.py), computed in the background for the shell on screen."""
        ctx = self.ctx
        chosen = self.colour_chosen.take()
        bundle = ctx.bundle
        if bundle is None:
            return
        mode = str(ctx.panels.shell_colour.value)
        if chosen is not None and chosen != mode:  # a job's reset came after the choice: the choice wins
            with ctx.programmatic():
                ctx.panels.shell_colour.value = mode = chosen
        link = ctx.state.mechanism
        if link is not None and mode != COLOUR_MODES[0]:  # the colour fields are the paper design's
            ctx.notify("Shell coloured by height", f"shell colour = {mode}: {link.not_yet()}", color="orange")
            mode = COLOUR_MODES[0]
        if mode == COLOUR_MODES[0]:
            self._show_height(bundle)
            return
        s = ctx.state
        if mode == COLOUR_MODES[2]:
            ctx.panels.legend.show_computing("shell colour = binding limit", "Shell colour = binding limit")
            self._colour_by_limit(bundle, s)
            return
        if mode in USAGE_MODES:
            self._colour_by_usage(bundle, s, mode)
            return
        ctx.panels.legend.show_computing("shell colour = dexterity 1/kappa", "Shell colour = dexterity 1/kappa")

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            from paraspace.kinematics.dexterity import dexterity_field

            res = compute_workspace(s.design, ws_settings(s, DEXTERITY_VOXEL), cancel=cancel)
            dex = dexterity_field(res, 0.005, cancel=cancel)
            return field_colours(bundle.mesh, dex, res) + (dex,)

        def done(job: Job) -> None:
            if not self._colours_ready(job, bundle, COLOUR_MODES[1]):
                return
            mesh, lo, hi, dex = job.result
            self._show_mesh(mesh)
            ctx.panels.legend.show_field_range(
                lo, hi, "1/kappa (eq. (26), L = a/2)",
                f"Shell colour = local dexterity 1/kappa at the resolved carriages, from {lo:.3g} to {hi:.3g} "
                f"(h = {DEXTERITY_VOXEL:g}); GCI (mean) {dex.gci:.3g}"
                + ("" if dex.check is None or dex.check.tolerance_held else f". {dex.check.message}"))

        self._submit_colours(fn, done, "Dexterity colours not started")

    def _colour_by_usage(self, bundle: ShellBundle, s: ExplorerState, mode: str) -> None:
        """The shell coloured by an actuator-usage map (kinematics.usage) on a coarse grid, in the
        background; the Legend gives the map's range and its mean over the workspace."""
        ctx = self.ctx
        key, label, what = USAGE_MODES[mode]
        ctx.panels.legend.show_computing(f"shell colour = {mode}", f"Shell colour = {mode}")

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            from paraspace.kinematics.usage import actuator_usage

            res = compute_workspace(s.design, ws_settings(s, DEXTERITY_VOXEL), cancel=cancel)
            values = getattr(actuator_usage(res, cancel=cancel), key)
            mesh, lo, hi = values_colours(bundle.mesh, values, res.grid.origin, res.grid.h)
            finite = values[np.isfinite(values)]
            return mesh, lo, hi, float(finite.mean()) if finite.size else float("nan")

        def done(job: Job) -> None:
            if not self._colours_ready(job, bundle, mode):
                return
            mesh, lo, hi, mean = job.result
            self._show_mesh(mesh)
            ctx.panels.legend.show_field_range(
                lo, hi, label, f"Shell colour = {what}, from {lo:.3g} to {hi:.3g} (h = {DEXTERITY_VOXEL:g}); "
                f"mean over the workspace {mean:.3g}", title=f"shell colour = {mode}")

        self._submit_colours(fn, done, f"{mode} colours not started")

    def _colour_by_limit(self, bundle: ShellBundle, s: ExplorerState) -> None:
        """The shell coloured by the limit that bounds the workspace there (background job)."""
        ctx = self.ctx

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            mesh = bundle.mesh
            labels = binding_labels(s.design, bundle.result.settings, mesh.vertices, mesh.vertex_normals,
                                    bundle.result.grid.h)
            out = mesh.copy()
            out.visual.vertex_colors = np.array([LIMIT_COLOURS[x] + (255,) for x in labels], np.uint8)  # type: ignore[union-attr]
            counts = {k: labels.count(k) for k in LIMIT_COLOURS if labels.count(k)}
            return out, counts

        def done(job: Job) -> None:
            if not self._colours_ready(job, bundle, COLOUR_MODES[2]):
                return
            mesh, counts = job.result
            self._show_mesh(mesh)
            total = sum(counts.values()) or 1
            ctx.panels.legend.show_categories(
                "shell colour = binding limit",
                tuple((f"{k} {100 * v / total:.0f} %", LIMIT_COLOURS[k]) for k, v in counts.items()),
                "Shell colour = the limit that bounds the workspace there: "
                + ", ".join(f"{LIMIT_COLOUR_NAMES[k]} {k} ({100 * v / total:.0f} %)" for k, v in counts.items()))

        self._submit_colours(fn, done, "Limit colours not started")

    def _show_height(self, bundle: ShellBundle) -> None:
        """The shell in its own (height) colours, with their key in the Legend."""
        ctx = self.ctx
        self._show_mesh(bundle.mesh)
        assert ctx.shell is not None  # built before the controllers are wired
        zr = ctx.shell.z_range()
        if zr is not None:
            ctx.panels.legend.show_z_range(*zr)

    def _colours_ready(self, job: Job, bundle: ShellBundle, mode: str) -> bool:
        """Whether the colour job ``job`` of ``mode`` holds colours to show: it is done, and its shell
        and mode are still on screen. One that ended otherwise for the shell and mode on screen (failed,
        or cancelled by anything but a newer request, which changes the mode or the bundle first): the
        shell shows its height colours again, the dropdown says so (choosing the mode again retries),
        and the Legend and a toast say which mode failed and why, instead of "computing..." forever."""
        ctx = self.ctx
        if ctx.bundle is not bundle or str(ctx.panels.shell_colour.value) != mode:
            return False
        if job.status == "done":
            return True
        why = job.error or job.message or job.status
        with ctx.programmatic():
            ctx.panels.shell_colour.value = COLOUR_MODES[0]
        self._show_height(bundle)
        ctx.panels.legend.show_not_computed(f"shell colour = {mode}", f"Shell colour = {mode}", why)
        if job.status == "failed":
            ctx.notify(f"Shell colour = {mode} failed", f"{why}; the shell keeps its height colours")
        return False

    def _submit_colours(self, fn: Any, done: Callable[[Job], None], refused: str) -> None:
        ctx = self.ctx
        try:
            ctx.jobs.submit(fn, kind="dexterity", client=ctx.job_client, supersede=True, on_done=done)
        except (LimitExceeded, RuntimeError) as exc:
            ctx.notify(refused, str(exc))
