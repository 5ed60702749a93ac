"""The Pose tab's "Total-orientation workspace" group: the positions from which every orientation
with tilt <= T (all azimuths) and torsion within ±S is reachable (:mod:`kinematics.dexterous`).

*Show* computes it in the background for the current design and joint options (zero base
orientation, the sample spacing ``angle step``; at h = 6 a few seconds, at h = 2 about a minute on
two cores) and draws it as a purple surface inside the position workspace's shell, with its volume
and its share of the position workspace; *Hide* removes it. The computation is cancellable.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import viser

from paraspace.kinematics.settings import TOTAL_ORIENTATION, Setting

from ..jobs import Job, JobManager, LimitExceeded
from ..numfmt import significant
from ..textsafe import md_text
from .scene import glb_with_material, remove_node
from .session import SessionJobs
from .typed_values import hold_typed_values

if TYPE_CHECKING:  # pragma: no cover - types only
    import trimesh

#: Voxel edge of the total-orientation workspace (coarser than the shell: it costs a workspace
#: test per sampled orientation per voxel).
DEXTEROUS_VOXEL = 6.0
COLOR = (140, 60, 200, 255)
#: Opacity of the total-orientation shell: the position shell and the legs stay visible through it.
OPACITY = 0.55


def _slider(gui: Any, label: str, spec: Setting) -> Any:
    """A slider of one row of :data:`kinematics.settings.TOTAL_ORIENTATION` (range, default, words)."""
    assert spec.slider is not None
    lo, hi, step = spec.slider
    return hold_typed_values(gui.add_slider(label, min=lo, max=hi, step=step, initial_value=float(spec.default),
                                            hint=f"{spec.label}; valid range {spec.range_text()}"))


class DexterousPanel:
    """Sliders, Show / Hide, the purple surface and its numbers (module docstring)."""

    NODE = "/workspace/total_orientation"

    def __init__(self, gui: viser.GuiApi, scene: viser.SceneApi, jobs: JobManager | SessionJobs, *, client: str,
                 get_input: Callable[[], tuple[Any, Any]], notify: Callable[[str, str], None]) -> None:
        self.scene = scene
        self.jobs = jobs
        self.client = client
        self.get_input = get_input  # -> (design, joints)
        self.notify = notify
        self.lock = threading.Lock()
        self.job: Job | None = None
        self._gen = 0  # the latest run's number (:meth:`start`)
        self.handle: Any | None = None
        self.result: Any | None = None
        with gui.add_folder("Total-orientation workspace", expand_by_default=False):
            self.tilt = _slider(gui, "tilt T (deg)", TOTAL_ORIENTATION["tilt"])
            self.torsion = _slider(gui, "torsion S (deg)", TOTAL_ORIENTATION["torsion"])
            self.step = _slider(gui, "angle step (deg)", TOTAL_ORIENTATION["angle_step"])
            self.show = gui.add_button(f"Show (h = {DEXTEROUS_VOXEL:g})", icon=viser.Icon.PLAYER_PLAY)
            # a fine step over wide angles runs for minutes: the run can be stopped like every other job
            self.stop = gui.add_button("Stop", color="red", icon=viser.Icon.PLAYER_STOP, visible=False)
            self.hide = gui.add_button("Hide", icon=viser.Icon.EYE_OFF, disabled=True)
            self.text = gui.add_markdown("The positions from which every such orientation is reachable, drawn "
                                         "in purple inside the workspace.")
        self.show.on_click(lambda _e: self.start())
        self.stop.on_click(lambda _e: self.cancel())
        self.hide.on_click(lambda _e: self.clear())

    def start(self) -> None:
        from paraspace.kinematics.dexterous import total_orientation_workspace
        from paraspace.kinematics.workspace import WorkspaceSettings

        design, joints = self.get_input()
        tilt, torsion, step = float(self.tilt.value), float(self.torsion.value), float(self.step.value)

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            return total_orientation_workspace(design, tilt, torsion, step,
                                               WorkspaceSettings(voxel=DEXTEROUS_VOXEL, joints=joints),
                                               progress=progress, cancel=cancel)

        def on_progress(job: Job) -> None:
            self.text.content = f"computing... {100 * job.progress:.0f} %"

        with self.lock:
            self._gen += 1
            gen = self._gen

        def done(job: Job) -> None:
            with self.lock:
                if gen != self._gen:  # a newer run took over (and cancelled this one)
                    return
            self.show.disabled = False
            self.stop.visible = False
            if job.status == "done":
                self._draw(job.result)
            elif job.status == "failed":
                self.text.content = f"**failed:** {md_text(job.error)}"
            else:
                self.text.content = (f"stopped at {100 * job.progress:.0f} %: nothing new drawn"
                                     + ("; the workspace shown is the one before" if self.handle is not None else ""))

        with self.lock:
            old = self.job
        if old is not None and not old.is_final:
            self.jobs.cancel(old.id)
        try:
            job = self.jobs.submit(fn, kind="dexterous", client=self.client, supersede=True, on_done=done,
                                   on_progress=on_progress)
        except (LimitExceeded, RuntimeError) as exc:
            self.notify("Total-orientation workspace not started", str(exc))
            return
        with self.lock:
            self.job = job
        self.show.disabled = True
        self.stop.visible = True
        self.text.content = "computing..."

    def cancel(self) -> None:
        """The Stop button: cancel the running job (it ends at its next check, and says so)."""
        with self.lock:
            job = self.job
        if job is not None and not job.is_final:
            self.jobs.cancel(job.id)

    def _draw(self, res: Any) -> None:
        """Show ``res``: its shell (built first, the slow part), then its text, then ``result`` last,
        so that a set ``result`` means the panel shows it (a test read the handle between the two
        once on CI)."""
        from paraspace.kinematics.shell import smooth_for_display, workspace_shell

        s = res.summary()
        frac = s["fraction_of_position"]
        text = md_text(
            f"tilt <= {res.tilt:g} deg, torsion within ±{res.torsion:g} deg ({s['orientations']} orientations, "
            f"step {res.step:g} deg): V = {significant(s['volume'], 4)} units³, "
            f"{100 * frac:.1f} % of the position workspace at h = {DEXTEROUS_VOXEL:g}" if frac is not None
            else "empty position workspace")
        glb = None
        if res.voxels:
            # drawn like the position shell: re-meshed, smoothed for display (no h = 6 staircase) and
            # translucent, so that the legs and the position shell stay visible through it
            mesh: trimesh.Trimesh = workspace_shell(res.result, max_faces=30000, color_by_z=False,
                                                    reduction="remesh", volume_rtol=1e-2)
            mesh = smooth_for_display(mesh, volume=res.result.volume)
            mesh.visual.vertex_colors = np.tile(np.array(COLOR, np.uint8), (len(mesh.vertices), 1))  # type: ignore[union-attr]
            glb = glb_with_material(cast(bytes, mesh.export(file_type="glb", include_normals=True)), OPACITY)
        self._remove()
        if glb is not None:
            self.handle = self.scene.add_glb(self.NODE, glb, cast_shadow=False, receive_shadow=False)
            self.hide.disabled = False
        self.text.content = text
        self.result = res

    def _remove(self) -> None:
        remove_node(self.handle)
        self.handle = None

    def clear(self) -> None:
        """The Hide button."""
        self._remove()
        self.hide.disabled = True
