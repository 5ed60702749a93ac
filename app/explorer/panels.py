"""Layout of one browser's control panel: every GUI element of the explorer, no behaviour.

:func:`build_panels` creates the elements on a client's ``client.gui`` (so they belong to that
browser only) from an :class:`~app.urlstate.ExplorerState` and returns them in a :class:`Panels`;
the panel controllers (``app/*_controller.py``, wired by :mod:`app.explorer`) attach the callbacks.
Layout, top to bottom:

* URL messages (only when the opened link had bad fields);
* "Workspace" status: progress bar, one status line, Stop;
* "Numbers": volume, voids, hollowness, boundary, genus, components, TI_1/TI_2, compute time,
  the pose verdict;
* tabs Design | Pose | View | Plots | Share.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import viser

import paraspace
from paraspace.kinematics.design import ETA_RANGES, PARAMS, Design, paper_range_text
from paraspace.kinematics.settings import ORIENTATION

from .. import figures
from ..urlstate import (
    CAMERA_PRESETS,
    CUT_KEEPS,
    D_KEYS,
    DESIGN_KEYS,
    DESIGN_RANGES,
    DESIGN_SLIDERS,
    ETA_KEYS,
    POSE_KEYS,
    POSE_SLIDERS,
    SETTING_SLIDERS,
    ExplorerState,
)
from .dexterity_colour import COLOUR_MODES
from .joints_panel import JointsControls, build_joints_folder
from .lazy_plot import LazyPlot
from .legend import LegendPanel, build_legend_folder
from .typed_values import hold_typed_values

POSE_HINTS: dict[str, str] = {
    "x": "platform centre P, x (length units)", "y": "platform centre P, y (length units)",
    "z": "platform centre P, height (length units); the slider spans the design's reach, 0 to l_min + l_s",
    "psi": "Euler angle about z (eq. 2: R1 = Rz(psi) Ry(theta) Rx(phi)), degrees",
    "theta": "Euler angle about y, degrees", "phi": "Euler angle about x, degrees",
}
#: pose slider labels: the key and its unit
POSE_LABELS: dict[str, str] = {"x": "x", "y": "y", "z": "z", "psi": "psi (deg)", "theta": "theta (deg)",
                               "phi": "phi (deg)"}
STUDY_PARAMS: tuple[str, ...] = DESIGN_KEYS


@dataclasses.dataclass
class Panels:
    """Handles of one client's GUI (see the module docstring)."""

    url_messages: Any
    progress: Any
    status: Any
    stop: Any
    numbers: Any
    summary: Any
    tabs: Any
    legend: LegendPanel
    # design
    design_tab: Any
    design: dict[str, Any]
    eta_range: Any
    reset: Any
    voxel: Any
    design_message: Any
    joints: JointsControls
    # pose
    pose_tab: Any
    plots_tab: Any
    pose: dict[str, Any]
    gizmo: Any
    carriages: Any
    d: list[Any]
    eta: list[Any]
    pose_table: Any
    # view
    view_buttons: Any
    fit_view: Any
    shell_colour: Any
    cut: Any
    cut_z: Any
    cut_keep: Any
    opacity: Any
    payload: Any
    # plots
    z0: Any
    scan_range: Any
    scan_step: Any
    orientation_status: Any
    orientation_plot: Any
    orientation_png: Any
    orientation_svg: Any
    study_voxel: Any
    sweep_param: Any
    sweep_measure: Any
    sweep_points: Any
    sweep_run: Any
    sweep_stop: Any
    sweep_progress: Any
    sweep_status: Any
    sweep_plot: Any
    sweep_csv: Any
    sweep_png: Any
    sweep_svg: Any
    surface_points: Any
    surface_run: Any
    surface_stop: Any
    surface_progress: Any
    surface_status: Any
    surface_plot: Any
    surface_csv: Any
    surface_png: Any
    surface_svg: Any
    # share
    link: Any
    copy_link: Any
    download_stl: Any
    download_ply: Any
    download_glb: Any
    download_json: Any
    download_report: Any
    report_status: Any
    version: Any
    #: the mechanism selector at the top of the Design tab (app/mechanism_panel.py; built by the session)
    mechanism: Any = None


#: ``order`` of the folders below the tab group (viser sorts a container's children by ``order``;
#: the default is the creation count, so these stay below every tab added later).
LOWER_ORDER = 1.0e6


def slider_span(lo: float, hi: float, value: float) -> tuple[float, float]:
    """A slider's ``(min, max)``: its range widened to hold ``value`` (a value typed in the number
    box or restored from a link may lie outside the Table I range; the slider must still show it)."""
    return min(lo, value), max(hi, value)


def pose_slider_span(key: str, design: Design, value: float) -> tuple[float, float]:
    """The pose slider ``key``'s ``(min, max)`` for ``design``: the height ``z`` spans the design's
    reach ``[0, l_min + l_s]`` (no platform centre rises above its longest leg: the base joints lie
    in z = 0), rounded up to 5 units; the others their fixed range. Widened to hold ``value``."""
    rng = POSE_SLIDERS[key]
    hi = 5.0 * math.ceil((design.l_min + design.l_s) / 5.0) if key == "z" else rng.hi
    return slider_span(rng.lo, hi, value)


#: Measures offered by the sweep's "measure" menu (``app.figures.MEASURES`` names).
SWEEP_MEASURES: tuple[str, ...] = ("volume", "hollowness", "void_ratio", "solidity", "voids", "components", "genus",
                                   "TI_1", "TI_2")
#: plotly options of the explorer's plots: zoom/pan/reset kept, plotly's own picture button removed
#: (the PNG and SVG buttons below each plot give the print-quality files).
PLOT_CONFIG: dict[str, Any] = {"displaylogo": False, "responsive": True,
                               "modeBarButtonsToRemove": ["toImage", "lasso2d", "select2d"]}


def _plot(gui: viser.GuiApi, container: Any, text: str, visible: bool = True) -> LazyPlot:
    """An interactive plotly plot (``app.figures``) in ``container``, created at its first figure
    (:class:`~app.lazy_plot.LazyPlot`: plotly.js then loads after the first shell); ``text`` holds
    its place until then."""
    return LazyPlot(gui, container, text, config=PLOT_CONFIG, visible=visible)


def _downloads(gui: viser.GuiApi, disabled: bool = True) -> tuple[Any, Any]:
    """The PNG and SVG download buttons of one plot, side by side."""
    png = gui.add_button(f"PNG ({figures.EXPORT_DPI} dpi)", icon=viser.Icon.DOWNLOAD, disabled=disabled)
    svg = gui.add_button("SVG", icon=viser.Icon.DOWNLOAD, disabled=disabled)
    return png, svg


def build_panels(gui: viser.GuiApi, state: ExplorerState) -> Panels:
    """Create every GUI element on ``gui`` (a client's ``client.gui``) showing ``state``."""
    # Top to bottom: the job's status line and the pinned numbers strip (always in view), then the
    # tabs (a design slider and the volume are visible together at 1440x900), then the full
    # Numbers and the Legend, which the user opens when needed. Tabs added later (Compare, Paper,
    # Optimize) join the same tab group; the folders below keep their place with ``order``.
    url_messages = gui.add_markdown("", visible=False)
    progress = gui.add_progress_bar(0.0, animated=False)
    status = gui.add_markdown("*starting...*")
    stop = gui.add_button("Stop computation", color="red", icon=viser.Icon.PLAYER_STOP, visible=False)
    summary = gui.add_markdown("*computing...*")
    tabs = gui.add_tab_group()
    with gui.add_folder("Numbers", expand_by_default=True, order=LOWER_ORDER):
        numbers = gui.add_markdown("*computing...*")
    legend = build_legend_folder(gui, order=LOWER_ORDER + 1)

    design_tab = tabs.add_tab("Design", viser.Icon.RULER_MEASURE)
    with design_tab:
        design = {}
        for key in DESIGN_KEYS:
            rng = DESIGN_SLIDERS[key]
            spec = PARAMS[key]
            value = float(getattr(state.design, key))
            lo, hi = slider_span(rng.lo, rng.hi, value)
            design[key] = hold_typed_values(gui.add_slider(
                spec.label, min=lo, max=hi, step=rng.step, initial_value=value,
                hint=f"{spec.description}; {paper_range_text(key)}; type values in "
                     f"{DESIGN_RANGES[key].text(spec.unit)} in the box"))
        eta_range = gui.add_dropdown("eta_range", ETA_RANGES, initial_value=state.design.eta_range,
                                     hint="arc stroke: centered [-eta_s/2, eta_s/2] or from-zero [0, eta_s]")
        design_message = gui.add_markdown("", visible=False)
        reset = gui.add_button("Reset to paper defaults", icon=viser.Icon.RESTORE)
        rng = SETTING_SLIDERS["voxel"]
        voxel = hold_typed_values(gui.add_slider(
            "voxel h", *slider_span(rng.lo, rng.hi, state.voxel), step=rng.step, initial_value=state.voxel,
            hint="voxel edge of the full workspace computation (preview: h = 6)"))
        joints = build_joints_folder(gui, state.joints)

    pose_tab = tabs.add_tab("Pose", viser.Icon.ARROWS_MOVE)
    with pose_tab:
        pose = {}
        for key in POSE_KEYS:
            rng = POSE_SLIDERS[key]
            value = float(getattr(state.pose, key))
            lo, hi = pose_slider_span(key, state.design, value)
            pose[key] = hold_typed_values(gui.add_slider(POSE_LABELS[key], min=lo, max=hi, step=rng.step,
                                                         initial_value=value, hint=POSE_HINTS[key]))
        gizmo = gui.add_checkbox("drag gizmo", True, hint="show the drag handle on the platform")
        carriages = gui.add_dropdown("carriages", ("auto", "manual"), initial_value=state.carriages,
                                     hint="auto: redundancy resolved (max leg margin); manual: set d_i, eta_i")
        d, eta = [], []
        lo, hi = state.design.eta_limits
        for i in range(3):
            d.append(gui.add_slider(D_KEYS[i], min=0.0, max=max(state.design.d_s, 1e-6), step=0.1,
                                    initial_value=float(state.d[i]), visible=state.carriages == "manual",
                                    hint=f"radial carriage of chain {i + 1}, [0, d_s]"))
        for i in range(3):
            eta.append(gui.add_slider(ETA_KEYS[i], min=lo, max=max(hi, lo + 1e-6), step=0.1,
                                      initial_value=float(state.eta[i]), visible=state.carriages == "manual",
                                      hint=f"arc carriage of chain {i + 1}, degrees"))
        pose_table = gui.add_markdown("")

    with tabs.add_tab("View", viser.Icon.EYE):
        view_buttons = gui.add_button_group("camera", CAMERA_PRESETS)
        fit_view = gui.add_button("Fit view", icon=viser.Icon.FOCUS_CENTERED,
                                  hint="frame the workspace in the part of the window the panel leaves free")
        cut = gui.add_checkbox("cut plane", state.cut, hint="cut the shell by a horizontal plane")
        rng = SETTING_SLIDERS["cut_z"]
        cut_z = hold_typed_values(gui.add_slider("cut height", *slider_span(rng.lo, rng.hi, state.cut_z),
                                                 step=rng.step, initial_value=state.cut_z))
        cut_keep = gui.add_dropdown("keep", CUT_KEEPS, initial_value=state.cut_keep,
                                    hint="which side of the cut plane stays visible")
        shell_colour = gui.add_dropdown("shell colour", COLOUR_MODES, initial_value=COLOUR_MODES[0],
                                        hint="height z; the local dexterity 1/kappa (eq. (26)); the limit that "
                                             "bounds the workspace there; how much of the leg stroke, or how "
                                             "large a joint angle, the resolved carriages use (computed at h = 6 "
                                             "in the background)")
        rng = SETTING_SLIDERS["opacity"]
        opacity = hold_typed_values(gui.add_slider(
            "shell opacity", *slider_span(rng.lo, rng.hi, state.opacity), step=rng.step,
            initial_value=state.opacity))
        payload = gui.add_markdown("")

    plots_tab = tabs.add_tab("Plots", viser.Icon.CHART_LINE)
    with plots_tab:
        with gui.add_folder("Orientation maps (Fig. 3 e-g)", expand_by_default=True) as orientation_folder:
            rng = SETTING_SLIDERS["z0"]
            z0 = hold_typed_values(gui.add_slider("z0", *slider_span(rng.lo, rng.hi, state.z0), step=rng.step,
                                                  initial_value=state.z0, hint="height of the x and y' lines"))
            scan_range, scan_step = (
                hold_typed_values(gui.add_slider(
                    label, *slider_span(rng.lo, rng.hi, value), step=rng.step, initial_value=value,
                    hint=f"{ORIENTATION[key].label}; type values in {ORIENTATION[key].range_text()}"))
                for label, key, rng, value in (
                    ("scan ± (deg)", "angle_range", SETTING_SLIDERS["angle_range"], state.angle_range),
                    ("scan step (deg)", "angle_step", SETTING_SLIDERS["angle_step"], state.angle_step)))
            orientation_status = gui.add_markdown("*waiting for the workspace...*")
            orientation_plot = _plot(gui, orientation_folder, "the orientation maps appear here")
            orientation_png, orientation_svg = _downloads(gui, disabled=False)
        study_voxel = gui.add_slider("study voxel h", min=2.0, max=10.0, step=1.0, initial_value=4.0,
                                     hint="voxel edge used by the parameter studies below")
        with gui.add_folder("Volume vs parameter (Fig. 4)", expand_by_default=False) as sweep_folder:
            sweep_param = gui.add_dropdown("parameter", STUDY_PARAMS, initial_value="a")
            sweep_measure = gui.add_dropdown("measure", SWEEP_MEASURES, initial_value="volume",
                                             hint="the plotted measure; TI_1/TI_2 add the orientation maps of "
                                                  "every point, at the scan settings above")
            sweep_points = gui.add_slider("points", min=3, max=31, step=1, initial_value=10)
            sweep_run = gui.add_button("Run sweep", icon=viser.Icon.PLAYER_PLAY)
            sweep_stop = gui.add_button("Stop sweep", color="red", icon=viser.Icon.PLAYER_STOP, visible=False)
            sweep_progress = gui.add_progress_bar(0.0, visible=False)
            sweep_status = gui.add_markdown("")
            sweep_plot = _plot(gui, sweep_folder, "", visible=False)
            sweep_csv = gui.add_button("Download CSV", icon=viser.Icon.DOWNLOAD, disabled=True)
            sweep_png, sweep_svg = _downloads(gui)
        with gui.add_folder("Volume over (a, d_s) (Fig. 5)", expand_by_default=False) as surface_folder:
            surface_points = gui.add_slider("grid points per axis", min=3, max=15, step=1, initial_value=7)
            surface_run = gui.add_button("Run (a, d_s) study", icon=viser.Icon.PLAYER_PLAY)
            surface_stop = gui.add_button("Stop study", color="red", icon=viser.Icon.PLAYER_STOP, visible=False)
            surface_progress = gui.add_progress_bar(0.0, visible=False)
            surface_status = gui.add_markdown("")
            surface_plot = _plot(gui, surface_folder, "", visible=False)
            surface_csv = gui.add_button("Download CSV", icon=viser.Icon.DOWNLOAD, disabled=True)
            surface_png, surface_svg = _downloads(gui)

    with tabs.add_tab("Share", viser.Icon.SHARE):
        link = gui.add_text("link", "", hint="this link restores the design, pose and view")
        copy_link = gui.add_button("Copy link", icon=viser.Icon.COPY)
        gui.add_markdown("**Downloads**")
        download_stl = gui.add_button("Shell STL", icon=viser.Icon.DOWNLOAD)
        download_ply = gui.add_button("Shell PLY", icon=viser.Icon.DOWNLOAD)
        download_glb = gui.add_button("Shell GLB", icon=viser.Icon.DOWNLOAD)
        download_json = gui.add_button("Measures JSON", icon=viser.Icon.DOWNLOAD)
        download_report = gui.add_button("Design report (HTML)", icon=viser.Icon.FILE_DESCRIPTION,
                                         hint="one self-contained page: parameters, mechanism, the shell's four "
                                              "views, every measure with its definition, orientation maps, the "
                                              "pinned design beside it, this link; print it to PDF from the browser")
        report_status = gui.add_markdown("")
        version = gui.add_markdown(f"paraspace {paraspace.__version__} (the same version as "
                                   "`paraspace --version` and `/api/v1/health`)")

    return Panels(
        url_messages=url_messages, progress=progress, status=status, stop=stop, numbers=numbers, summary=summary,
        tabs=tabs,
        legend=legend,
        design_tab=design_tab,
        design=design, eta_range=eta_range, reset=reset, voxel=voxel, design_message=design_message, joints=joints,
        pose_tab=pose_tab, plots_tab=plots_tab, pose=pose, gizmo=gizmo, carriages=carriages, d=d, eta=eta,
        pose_table=pose_table,
        view_buttons=view_buttons, fit_view=fit_view, shell_colour=shell_colour, cut=cut, cut_z=cut_z,
        cut_keep=cut_keep, opacity=opacity,
        payload=payload,
        z0=z0, orientation_status=orientation_status, orientation_plot=orientation_plot,
        scan_range=scan_range, scan_step=scan_step,
        orientation_png=orientation_png, orientation_svg=orientation_svg, study_voxel=study_voxel,
        sweep_param=sweep_param, sweep_measure=sweep_measure,
        sweep_points=sweep_points, sweep_run=sweep_run, sweep_stop=sweep_stop, sweep_progress=sweep_progress,
        sweep_status=sweep_status,
        sweep_plot=sweep_plot, sweep_csv=sweep_csv, sweep_png=sweep_png, sweep_svg=sweep_svg,
        surface_points=surface_points,
        surface_run=surface_run, surface_stop=surface_stop, surface_progress=surface_progress,
        surface_status=surface_status,
        surface_plot=surface_plot, surface_csv=surface_csv, surface_png=surface_png, surface_svg=surface_svg,
        link=link, copy_link=copy_link, download_stl=download_stl, download_ply=download_ply,
        download_glb=download_glb, download_json=download_json,
        download_report=download_report, report_status=report_status, version=version,
    )
