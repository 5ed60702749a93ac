"""The Plots tab's "Actuator usage" folder: histograms of the actuator-usage maps over the workspace.

On request, a background job computes :func:`paraspace.kinematics.usage.actuator_usage` on the
design on screen at h = :data:`~app.explorer.dexterity_colour.DEXTERITY_VOXEL` and draws
:func:`~paraspace.kinematics.usage.usage_summary`'s histograms: the share of the workspace's
voxels against the leg stroke use, the carriage stroke use and the tightest joint angle at the
resolved carriages (the same maps the View tab's "leg stroke use" and "tightest joint angle"
shell colours show). A designer sizes strokes and joints from them: how much of the workspace
needs a leg near its limit, or a joint beyond a given angle.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import numpy as np
import viser

from ..jobs import Job, JobManager, LimitExceeded
from ..textsafe import md_text
from .dexterity_colour import DEXTERITY_VOXEL
from .lazy_plot import LazyPlot
from .session import SessionJobs

#: The histograms, in order: (map, panel title, x-axis title).
PANELS: tuple[tuple[str, str, str], ...] = (
    ("leg_use", "leg stroke use", "|l - l_mid| / (l_s/2): 0 mid-stroke, 1 at a limit"),
    ("stroke_use", "carriage stroke use", "0 mid-stroke, 1 at a stroke end"),
    ("joint_angle", "tightest joint angle", "largest U or S joint angle (deg)"),
)


def usage_figure(summary: dict[str, Any]) -> Any:
    """Three bar charts: the share (%) of the workspace's voxels per bin of each map."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    fig = make_subplots(rows=3, cols=1, vertical_spacing=0.16, subplot_titles=[t for _, t, _ in PANELS])
    for row, (key, _title, x_title) in enumerate(PANELS, start=1):
        h = summary[key]
        counts = np.asarray(h["counts"], float)
        share = 100.0 * counts / max(counts.sum(), 1.0)
        edges = np.asarray(h["edges"], float)
        fig.add_trace(go.Bar(x=0.5 * (edges[:-1] + edges[1:]), y=share, width=np.diff(edges), name=key,
                             marker_color="#0072B2", showlegend=False,
                             hovertemplate="%{x:.3g}: %{y:.1f} % of the voxels<extra></extra>"), row=row, col=1)
        fig.update_xaxes(title_text=x_title, nticks=8, row=row, col=1)
        fig.update_yaxes(title_text="% of voxels", nticks=6, row=row, col=1)
    fig.update_layout(title=dict(text="Actuator usage over the workspace (resolved carriages)", font=dict(size=13)),
                      height=620, margin=dict(l=55, r=10, t=70, b=40), font=dict(size=11), plot_bgcolor="white")
    return fig


class UsagePanel:
    """The folder and its job (module docstring)."""

    def __init__(self, gui: viser.GuiApi, jobs: JobManager | SessionJobs, client: str,
                 get_input: Callable[[], tuple[Any, Any]]) -> None:
        self.jobs = jobs
        self.client = client
        self.get_input = get_input
        self.summary: dict[str, Any] | None = None
        with gui.add_folder("Actuator usage (histograms)", expand_by_default=False) as folder:
            self.run: Any = gui.add_button(f"Compute the usage histograms (h = {DEXTERITY_VOXEL:g})",
                                           icon=viser.Icon.CHART_BAR,
                                           hint="how much of the leg and carriage strokes, and how large a joint "
                                                "angle, the resolved carriages use over the workspace")
            self.text: Any = gui.add_markdown("")
            self.plot = LazyPlot(gui, folder, "", visible=True)
        self.run.on_click(lambda _e: self.start())

    def start(self) -> None:
        """Compute the maps of the design on screen in the background and draw their histograms."""
        from paraspace.kinematics.usage import actuator_usage, usage_summary
        from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

        design, joints = self.get_input()

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            progress(0.1, "the workspace")
            res = compute_workspace(design, WorkspaceSettings(voxel=DEXTERITY_VOXEL, joints=joints), cancel=cancel)
            progress(0.4, "the usage maps")
            return usage_summary(actuator_usage(res, cancel=cancel))

        def done(job: Job) -> None:
            self.run.disabled = False
            if job.status == "done":
                self.summary = job.result
                s = job.result
                self.plot.figure = usage_figure(s)
                self.plot.aspect = 1.4
                leg, joint = s["leg_use"], s["joint_angle"]
                self.text.content = (f"leg stroke use up to {leg['max']:.3g} (mean {leg['mean']:.3g}); "
                                     f"tightest joint angle up to {joint['max']:.3g} deg (mean {joint['mean']:.3g})")
            elif job.status == "failed":
                self.text.content = f"**failed:** {md_text(str(job.error))}"
            else:
                self.text.content = "stopped"

        try:
            self.jobs.submit(fn, kind="usage", client=self.client, supersede=True, on_done=done)
        except (LimitExceeded, RuntimeError) as exc:
            self.text.content = f"not started: {md_text(str(exc))}"
            return
        self.run.disabled = True
        self.text.content = "computing the usage maps..."
