"""The Pose tab's "Tilt and torsion here" plot: the orientation capability at the current position.

One button computes :func:`kinematics.tilt_torsion.tilt_torsion_at` for the platform's current
position (with the session's joint options) in the background (about 0.1 s) and draws a polar plot:
the largest reachable tilt (degrees, radial) for every azimuth at zero torsion, the tilt reachable in
every direction as a dashed circle, and the torsion range at zero tilt in the title. A tilt or
torsion limited by the scan (90° / 180°) is said so.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import viser

from ..jobs import Job, JobManager, LimitExceeded
from ..textsafe import md_text
from .lazy_plot import LazyPlot
from .session import SessionJobs


def tilt_polar_figure(report: Any) -> Any:
    """A plotly polar figure of a :class:`~kinematics.tilt_torsion.TiltTorsionReport`."""
    import plotly.graph_objects as go

    az = list(report.azimuths) + [report.azimuths[0]]
    tilt = [v if v is not None else 0.0 for v in report.max_tilt]
    tilt = tilt + [tilt[0]]
    fig = go.Figure()
    fig.add_trace(go.Scatterpolar(r=tilt, theta=az, mode="lines+markers", fill="toself", name="largest tilt",
                                  hovertemplate="azimuth %{theta:.0f}°<br>tilt %{r:.1f}°<extra></extra>",
                                  line={"color": "#1f77b4"}, marker={"size": 4}))
    every = report.min_max_tilt
    if every is not None:
        fig.add_trace(go.Scatterpolar(r=[every] * len(az), theta=az, mode="lines",
                                      name=f"every direction: {every:.1f}°", line={"color": "#d62728", "dash": "dash"},
                                      hoverinfo="skip"))
    tmin, tmax = report.torsion_min, report.torsion_max
    tors = "not reachable" if tmin is None else f"{tmin:.1f}° .. {tmax:.1f}°"
    sat = " (scan limit)" if any(report.torsion_saturated) else ""
    p = report.position
    fig.update_layout(
        title={"text": f"Tilt at P = ({p[0]:.0f}, {p[1]:.0f}, {p[2]:.0f}), zero torsion<br>"
                       f"<sup>torsion at zero tilt: {tors}{sat}</sup>", "x": 0.5, "font": {"size": 12}},
        polar={"radialaxis": {"title": {"text": "tilt (deg)"}, "range": [0, max(10.0, max(tilt) * 1.1)]},
               "angularaxis": {"direction": "counterclockwise", "rotation": 0}},
        legend={"orientation": "h", "y": -0.15}, margin={"l": 30, "r": 30, "t": 70, "b": 40})
    return fig


class TiltPanel:
    """The button and the polar plot (module docstring)."""

    def __init__(self, gui: viser.GuiApi, jobs: JobManager | SessionJobs, *, client: str,
                 get_input: Callable[[], tuple[Any, Any, Any]], notify: Callable[[str, str], None]) -> None:
        self.jobs = jobs
        self.client = client
        self.get_input = get_input  # -> (design, position (3,), joints)
        self.notify = notify
        self.lock = threading.Lock()
        self.job: Job | None = None
        self.report: Any | None = None
        with gui.add_folder("Tilt and torsion here", expand_by_default=False) as folder:
            self.run = gui.add_button("Compute at the current position", icon=viser.Icon.COMPASS)
            self.text = gui.add_markdown("Bonev-Gosselin tilt (any azimuth, zero torsion) and torsion (zero tilt) "
                                         "reachable at the platform's position.")
            self.plot = LazyPlot(gui, folder, aspect=1.0, visible=False)  # plotly.js only once there is a report
        self.run.on_click(lambda _e: self.start())

    def start(self) -> None:
        from paraspace.kinematics.tilt_torsion import tilt_torsion_at

        design, position, joints = self.get_input()

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> Any:
            return tilt_torsion_at(design, position, joints=joints)

        def done(job: Job) -> None:
            self.run.disabled = False
            if job.status == "done":
                rep = job.result
                self.report = rep
                if not rep.reachable:
                    self.text.content = "The zero orientation is not reachable at this position."
                    self.plot.visible = False
                    return
                self.plot.figure = tilt_polar_figure(rep)
                self.plot.visible = True
                every = rep.min_max_tilt
                self.text.content = md_text(
                    f"tilt in every direction: {every:.1f} deg; "
                    f"torsion {rep.torsion_min:.1f} .. {rep.torsion_max:.1f} deg"
                    if every is not None else "tilt: not reachable in some directions")
            elif job.status == "failed":
                self.notify("Tilt and torsion failed", str(job.error))

        try:
            job = self.jobs.submit(fn, kind="tilt", client=self.client, supersede=True, on_done=done)
        except (LimitExceeded, RuntimeError) as exc:
            self.notify("Tilt and torsion not started", str(exc))
            return
        with self.lock:
            self.job = job
        self.run.disabled = True

