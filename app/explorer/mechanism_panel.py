"""The Design tab's mechanism selector: the paper's design, another preset with its parameters as
sliders, or an uploaded description file.

**Definition.** The selector's value is ``paper`` (``ExplorerState.mechanism is None``: the Design
tab as before), a preset of :data:`app.mechanism_link.MECH_PRESETS` (a
:class:`~app.mechanism_link.MechanismLink` holding every parameter), or :data:`FILE_OPTION` (the
uploaded TOML/JSON description). A preset parameter's slider is made from its
:class:`~kinematics.presets.PresetParam` alone (label and unit, the study range widened to hold the
value, the valid range ``[lo, hi]`` in its hint, default, its
words as the hint), so every setting is defined once; a value the preset's builder refuses is
not applied and its message (the CLI's ``--param`` message) is shown. An upload is read by
:func:`kinematics.mechanism.loads_mechanism` (at most ``MAX_TEXT_BYTES``); a bad file is refused in
the status line with the parser's message naming the field, and nothing changes.

Panels that compute on the paper's design only say so in words while another mechanism is
selected (:class:`NotYetNotes`: "not for the 6-pups mechanism yet") and their buttons are disabled.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np
import viser

from paraspace.kinematics.design import ParameterError
from paraspace.kinematics.mechanism import MAX_TEXT_BYTES

from ..mechanism_link import FILE, MECH_PRESETS, MechanismLink, file_link, preset_link, preset_params
from ..numfmt import fixed
from ..textsafe import md_text
from ..urlstate import POSE_SLIDERS, ExplorerState, encode_query
from .mechanism_scene import STATE_TEXT, MechanismPose
from .pagehook import MAX_QUERY_CHARS
from .panels import pose_slider_span, slider_span
from .session import NewestMessage, SessionContext
from .typed_values import hold_typed_values

#: The selector's entry of an uploaded description (offered once a file was read).
FILE_OPTION = "uploaded file"
PAPER = "paper"
#: Order of the selector's elements: before everything else in the Design tab.
TOP_ORDER = -100.0


def option_of(link: MechanismLink | None) -> str:
    """The selector's value for ``link``."""
    if link is None:
        return PAPER
    return FILE_OPTION if link.preset == FILE else link.preset


def _slider_label(name: str, unit: str) -> str:
    return f"{name} ({unit})" if unit else name


@dataclasses.dataclass
class MechanismControls:
    """Handles of the selector, its upload button, its message and each preset's sliders."""

    selector: Any
    upload: Any
    message: Any
    folders: dict[str, Any]
    sliders: dict[str, dict[str, Any]]


def build_mechanism_controls(gui: viser.GuiApi, state: ExplorerState) -> MechanismControls:
    """The selector at the top of the Design tab (call inside the tab), showing ``state``'s mechanism."""
    link = state.mechanism
    options = (PAPER, *MECH_PRESETS) + ((FILE_OPTION,) if link is not None and link.preset == FILE else ())
    selector = gui.add_dropdown("Mechanism", options, initial_value=option_of(link), order=TOP_ORDER,
                                hint="paper: the paper's 3-(arc-P, P, 2-(UPS)) and its Table I design; a preset "
                                     "with its parameters; or an uploaded TOML/JSON description")
    upload = gui.add_upload_button("Upload file...", icon=viser.Icon.UPLOAD, order=TOP_ORDER + 1,
                                   hint=f"a mechanism description, TOML or JSON, at most {MAX_TEXT_BYTES:,} bytes "
                                        "(paraspace mechanism export PRESET writes one to start from)")
    message = gui.add_markdown("", visible=False, order=TOP_ORDER + 2)
    folders: dict[str, Any] = {}
    sliders: dict[str, dict[str, Any]] = {}
    values = dict(link.params) if link is not None else {}
    for k, name in enumerate(MECH_PRESETS):
        shown = link is not None and link.preset == name
        with gui.add_folder(f"{name} parameters", order=TOP_ORDER + 3 + k, visible=shown) as folder:
            folders[name] = folder
            sliders[name] = {}
            for p in preset_params(name):
                v = float(values.get(p.name, p.default)) if shown else float(p.default)
                lo, hi = slider_span(*p.study_range, v)  # the study range, widened to hold the value
                sliders[name][p.name] = hold_typed_values(gui.add_slider(
                    _slider_label(p.name, p.unit), min=lo, max=hi, step=0.5, initial_value=v,
                    hint=f"{p.description}; valid range [{p.lo:g}, {p.hi:g}]{' ' + p.unit if p.unit else ''}"))
    return MechanismControls(selector, upload, message, folders, sliders)


def mechanism_pose_table(link: MechanismLink, iks: list[Any], pose: MechanismPose) -> str:
    """Markdown of the pose's verdict and its table: per chain the carriage values (degrees for a
    revolute joint), the legs' lengths with their states, and the length margin."""
    mech = link.mechanism()
    feasible = pose_feasible(pose.states)
    rows = ["| chain | carriage | legs | margin |", "|---|---|---|---|"]
    k = 0
    for ik, chain in zip(iks, mech.chains):
        q = ", ".join(f"{'η' if j.type == 'revolute' else 's'} {fixed(v)}" for j, v in zip(chain.carriage, ik.q))
        legs = []
        for length in ik.lengths:
            state = pose.states[k]
            k += 1
            legs.append(fixed(length) + ("" if state == "inside" else f" **({STATE_TEXT[state]})**"))
        rows.append(f"| {ik.chain + 1} | {q or 'fixed'} | {'; '.join(legs)} | {fixed(ik.margin)} |")
    verdict = "**reachable**" if feasible else "**not reachable: a leg leaves its length range or its cone**"
    return (f"{verdict}  \n{md_text(link.label)}: carriages resolved (max leg margin; cones not part of the "
            "margin)\n\n" + "\n".join(rows))


def pose_feasible(states: list[str]) -> bool:
    """The pose is reachable at the drawn carriage values: every leg inside its range and cones."""
    return all(st in ("inside", "at_limit") for st in states)


def mechanism_pose_line(pose: MechanismPose | None, inside: bool | None) -> str | None:
    """The Numbers panel's pose line for the selector's mechanism (``None`` before the IK)."""
    if pose is None:
        return None
    where = "" if inside is None else (" · inside the workspace" if inside else " · outside the workspace")
    ok = pose_feasible(pose.states)
    return ("reachable" if ok else "not reachable: a leg leaves its length range or its cone") + where


def mechanism_lines(link: MechanismLink, result: Any | None) -> tuple[str, ...]:
    """The Numbers panel's lines for the selector's mechanism: its name and engine, and the bounds
    of the reachable voxels of ``result`` (cube faces: centres +- h/2) when it is of ``link``."""
    mech = link.mechanism()
    head = f"**Mechanism** {md_text(link.label)}: {md_text(mech.name[:80])}"
    if result is None:
        return (head + "  ",)
    head += f" ({md_text(getattr(result, 'engine', 'general'))} engine)"
    idx = np.argwhere(result.occupancy)
    if len(idx) == 0:
        return (head + "  ",)
    h = result.grid.h
    lo = np.asarray(result.grid.origin, float) + h * idx.min(axis=0) - h / 2
    hi = np.asarray(result.grid.origin, float) + h * idx.max(axis=0) + h / 2
    lo[2] = max(lo[2], result.settings.z_floor)
    box = ", ".join(f"{a} [{fixed(a0)}, {fixed(a1)}]" for a, a0, a1 in zip("xyz", lo, hi))
    return (head + "  ", f"**Bounds** {box}  ")


class NotYetNotes:
    """One note per panel that computes on the paper's design only: hidden for the paper; for another
    mechanism it says "not for the X mechanism yet" and that panel's buttons are disabled."""

    def __init__(self) -> None:
        self.notes: list[tuple[Any, str, tuple[Any, ...]]] = []

    def add(self, gui: viser.GuiApi, what: str, buttons: tuple[Any, ...] = ()) -> None:
        """A note at the top of the current container about ``what`` (e.g. "The Compare tab")."""
        self.notes.append((gui.add_markdown("", visible=False, order=TOP_ORDER), what, buttons))

    def attach(self, what: str, buttons: tuple[Any, ...]) -> None:
        """Add ``buttons`` to the note about ``what`` (panels built after their note)."""
        self.notes = [(n, w, b + buttons if w == what else b) for n, w, b in self.notes]

    def show(self, link: MechanismLink | None) -> None:
        for note, what, buttons in self.notes:
            if link is not None:
                note.content = f"*{md_text(what)}: {md_text(link.not_yet())} (it computes on the paper's design).*"
            note.visible = link is not None
            for b in buttons:
                b.disabled = link is not None


class MechanismController:
    """The selector, its parameter sliders and the upload of one session (module docstring).

    Args:
        ctx: the session's shared state.
        update_mechanism: redraws the mechanism at the current state (IK).
        submit_workspace: asks for the workspace of the current state.
        on_state_change: called after the mechanism changed the state (the link follows).
        notes: the other panels' notes (:class:`NotYetNotes`).
    """

    def __init__(self, ctx: SessionContext, *, update_mechanism: Callable[[], Any],
                 submit_workspace: Callable[[], None], on_state_change: Callable[[], None],
                 notes: NotYetNotes) -> None:
        self.ctx = ctx
        self.update_mechanism = update_mechanism
        self.submit_workspace = submit_workspace
        self.on_state_change = on_state_change
        self.notes = notes
        self.uploaded: MechanismLink | None = ctx.state.mechanism if option_of(ctx.state.mechanism) == FILE_OPTION \
            else None
        #: the selector's value of the user's newest message, until a callback applies it
        self.chosen: NewestMessage[str] = NewestMessage(lambda: str(self.controls.selector.value))

    @property
    def controls(self) -> MechanismControls:
        return self.ctx.panels.mechanism

    def wire(self) -> None:
        """Attach the selector, the sliders and the upload button; show the state's mechanism."""
        c, cb = self.controls, self.ctx.callback

        self.chosen.watch(c.selector)  # a write by Stop's controls could replace it (NewestMessage)
        c.selector.on_update(cb(self.on_select))
        for sliders in c.sliders.values():
            for h in sliders.values():
                h.on_update(cb(self.on_param))

        def on_upload(event: Any) -> None:
            def read() -> None:
                self.apply_upload(event.target.value.name, event.target.value.content)
            cb(read)(event)

        c.upload.on_upload(on_upload)
        self.show(self.ctx.state.mechanism)

    # ----- what is shown ------------------------------------------------------------------------
    def show(self, link: MechanismLink | None) -> None:
        """The controls for ``link``: the paper's design sliders or the preset's, the notes."""
        p = self.ctx.panels
        c = self.controls
        paper = link is None
        with self.ctx.programmatic():
            c.selector.value = option_of(link)
            for name, folder in c.folders.items():
                folder.visible = link is not None and link.preset == name
            if link is not None and link.preset in c.sliders:
                for key, v in link.params:
                    h = c.sliders[link.preset][key]
                    h.min, h.max = min(h.min, v), max(h.max, v)
                    h.value = v
            for h in (*p.design.values(), p.eta_range, p.reset):
                h.visible = paper
            if p.joints.folder is not None:
                p.joints.folder.visible = paper
            # the height slider spans the paper design's reach, or every height for another mechanism
            z, zv = p.pose["z"], float(self.ctx.state.pose.z)
            z.min, z.max = (pose_slider_span("z", self.ctx.state.design, zv) if paper
                            else slider_span(POSE_SLIDERS["z"].lo, POSE_SLIDERS["z"].hi, zv))
            p.design_message.visible = paper and self.ctx.design_error is not None
        self.notes.show(link)

    def say(self, text: str | None) -> None:
        """The selector's message (``None`` hides it)."""
        self.controls.message.content = text or ""
        self.controls.message.visible = text is not None

    # ----- input ----------------------------------------------------------------------------------
    def on_select(self) -> None:
        """The selector changed: the paper, a preset at its sliders' values, or the uploaded file."""
        with self.ctx.input_lock:
            # the user's newest choice (see wire); else the selector's value, which under this lock is
            # the state's once a callback applied a choice (or a server-side assignment's)
            choice = self.chosen.take()
            if choice is None:
                choice = str(self.controls.selector.value)
            if choice == PAPER:
                self.apply(None)
            elif choice == FILE_OPTION:
                if self.uploaded is not None:
                    self.apply(self.uploaded)
            else:
                self._apply_preset(choice)

    def on_param(self) -> None:
        """A preset parameter's slider moved: the preset with the sliders' values."""
        link = self.ctx.state.mechanism
        if link is None or link.preset not in MECH_PRESETS:
            return
        with self.ctx.input_lock:
            self._apply_preset(link.preset)

    def _apply_preset(self, name: str) -> None:
        values = {k: float(h.value) for k, h in self.controls.sliders[name].items()}
        try:
            link = preset_link(name, values)
        except ParameterError as exc:
            self.say(f"**Not applied:** {md_text(str(exc))}. The mechanism stays as it was.")
            return
        self.apply(link)

    def apply_upload(self, filename: str, content: bytes) -> bool:
        """Read an uploaded description and select it; a bad file is refused (status line, the
        selector's message, a notification) with the parser's message and nothing changes."""
        ctx = self.ctx
        try:
            if len(content) > MAX_TEXT_BYTES:
                raise ParameterError("mechanism", f"{len(content):,} bytes",
                                     f"a description of at most {MAX_TEXT_BYTES:,} bytes")
            link = file_link(content)
        except (ParameterError, UnicodeDecodeError) as exc:
            why = f"{filename[:80]}: {exc}"
            self.say(f"**File not read:** {md_text(why)}. Nothing was changed.")
            ctx.panels.status.content = f"**file not read:** {md_text(why)}"
            ctx.notify("Mechanism file not read", why)
            return False
        with ctx.lock:
            too_long = len(encode_query(ctx.state.replace(mechanism=link))) > MAX_QUERY_CHARS
        if too_long:
            link = dataclasses.replace(link, in_link=False)
        self.uploaded = link
        c = self.controls
        with ctx.programmatic():
            if FILE_OPTION not in c.selector.options:
                c.selector.options = (*c.selector.options, FILE_OPTION)
        self.apply(link)
        self.say(f"Read {md_text(filename[:80])}: {md_text(link.mechanism().name[:80])}."
                 + (" This file is too large to share in a link: the link carries no mechanism." if too_long else ""))
        return True

    def apply(self, link: MechanismLink | None) -> None:
        """Make ``link`` the session's mechanism (``None``: the paper's design): controls, drawing,
        workspace job, link."""
        ctx = self.ctx
        with ctx.lock:
            cur = ctx.state.mechanism
            if cur == link and (link is None or cur is None or link.in_link == cur.in_link):
                self.show(link)
                return
            ctx.state = ctx.state.replace(mechanism=link)
        self.say(None)
        self.show(link)
        self.update_mechanism()
        self.submit_workspace()
        self.on_state_change()
