"""Plots of the explorer, drawn with matplotlib (offline, identical on screen and in the PNG download).

* :func:`orientation_figure` -- paper Fig. 3(e)-(g): along the z, y' and x lines, the feasible
  (angle, position) samples of the three rotations phi (about z), tau (about y') and psi (about x),
  each region's Δ extents drawn as a dashed box and written in the legend.
* :func:`sweep_figure` -- paper Fig. 4: workspace volume against one design parameter, the current
  value marked.
* :func:`surface_figure` -- paper Fig. 5: volume over the (a, d_s) grid as a heat map, the current
  design marked.

Figures are built with the object API (``matplotlib.figure.Figure``), which is safe to use from
worker threads (no pyplot state). :func:`render` turns a figure into an RGB array for
``gui.add_image`` and PNG bytes for downloads.
"""

from __future__ import annotations

import io
import math
from typing import Any, Optional, Sequence

import matplotlib

matplotlib.use("Agg")  # noqa: E402 - headless server
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.patches import Patch, Rectangle  # noqa: E402

ROTATION_COLORS: dict[str, str] = {"phi_z": "#1f77b4", "tau_yprime": "#d62728", "psi_x": "#2ca02c"}
ROTATION_LABELS: dict[str, str] = {"phi_z": "φ (about z)", "tau_yprime": "τ (about y')", "psi_x": "ψ (about x)"}
ROTATION_SYMBOLS: dict[str, str] = {"phi_z": "φ", "tau_yprime": "τ", "psi_x": "ψ"}
LINE_TITLES: dict[str, str] = {
    "z": "(e) along z  (x = 0, y' = 0)",
    "y_prime": "(f) along y'  (x = 0, z = z0)",
    "x": "(g) along x  (y' = 0, z = z0)",
}
LINE_AXIS: dict[str, str] = {"z": "z", "y_prime": "y'", "x": "x"}
PARAM_LABELS: dict[str, str] = {
    "a": "a (platform radius)", "b": "b (U-joint spacing)", "d_s": "d_s (radial stroke)",
    "r": "r (base radius)", "l_min": "l_min (min. leg length)", "l_s": "l_s (leg stroke)",
    "eta_s": "η_s (arc stroke, deg)",
}


def render(fig: Figure, dpi: int = 100) -> tuple[np.ndarray, bytes]:
    """Draw ``fig``; returns ``(RGB uint8 array (H, W, 3), PNG bytes)``."""
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    rgba = np.asarray(canvas.buffer_rgba())
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return np.ascontiguousarray(rgba[:, :, :3]), buf.getvalue()


def placeholder_figure(text: str, width: float = 6.0, height: float = 2.0) -> Figure:
    """A small figure that only shows ``text`` (before a computation has run)."""
    fig = Figure(figsize=(width, height), dpi=100)
    ax = fig.add_subplot(111)
    ax.axis("off")
    ax.text(0.5, 0.5, text, ha="center", va="center", fontsize=11, color="#555555", wrap=True)
    return fig


def orientation_figure(result: Any, z0: Optional[float] = None) -> Figure:
    """Paper Fig. 3(e)-(g) from a :class:`kinematics.orientation.OrientationResult`.

    Each panel shows one line; horizontal axis: rotation angle (deg), vertical axis: position on the
    line. Each rotation's feasible samples are filled in its color; its Δ box (angle interval x
    position interval of the region) is dashed, and the legend gives ``Δα x Δs``.
    """
    lines = ("z", "y_prime", "x")
    rots = ("phi_z", "tau_yprime", "psi_x")
    fig = Figure(figsize=(6.4, 12.5), dpi=100, layout="constrained")
    axes = fig.subplots(3, 1)
    for ax, line in zip(axes, lines):
        handles = []
        for rot in rots:
            reg = result.regions.get((line, rot))
            if reg is None:
                continue
            color = ROTATION_COLORS[rot]
            pos = np.asarray(reg.positions, float)
            ang = np.asarray(reg.angles, float)
            feas = np.asarray(reg.feasible, bool)
            if pos.size and ang.size and feas.any():
                hs = (pos[1] - pos[0]) if pos.size > 1 else 1.0
                ha = (ang[1] - ang[0]) if ang.size > 1 else 1.0
                extent = (ang[0] - ha / 2, ang[-1] + ha / 2, pos[0] - hs / 2, pos[-1] + hs / 2)
                cmap = ListedColormap([(0, 0, 0, 0), matplotlib.colors.to_rgba(color, 0.35)])
                ax.imshow(feas.astype(np.uint8), origin="lower", extent=extent, aspect="auto",
                          cmap=cmap, vmin=0, vmax=1, interpolation="nearest")
            sym = ROTATION_SYMBOLS[rot]
            if reg.angle_interval is not None and reg.position_interval is not None:
                a0, a1 = reg.angle_interval
                p0, p1 = reg.position_interval
                ax.add_patch(Rectangle((a0, p0), a1 - a0, p1 - p0, fill=False, ls="--", lw=1.4, ec=color))
                text = (f"{ROTATION_LABELS[rot]}: Δ{sym} = {reg.delta_angle:.4g}°, "
                        f"Δ{LINE_AXIS[line]} = {reg.delta_position:.4g}")
            else:
                text = f"{ROTATION_LABELS[rot]}: no feasible sample"
            handles.append(Patch(facecolor=matplotlib.colors.to_rgba(color, 0.35), edgecolor=color, ls="--",
                                 label=text))
        ax.set_title(LINE_TITLES[line].replace("z0", f"{z0:g}" if z0 is not None else "z0"), fontsize=10)
        ax.set_xlabel("rotation angle (deg)")
        ax.set_ylabel(f"{LINE_AXIS[line]} (position on the line)")
        ax.grid(True, alpha=0.3)
        reg0 = next((result.regions.get((line, r)) for r in rots if result.regions.get((line, r)) is not None), None)
        if reg0 is not None:
            ax.set_xlim(*reg0.angle_range)
            sel = [result.regions[(line, r)].position_interval for r in rots
                   if result.regions.get((line, r)) is not None and result.regions[(line, r)].position_interval]
            if sel:
                lo = min(s[0] for s in sel)
                hi = max(s[1] for s in sel)
                pad = 0.08 * max(hi - lo, 1.0)
                ax.set_ylim(max(reg0.position_range[0], lo - pad), min(reg0.position_range[1], hi + pad))
        ax.legend(handles=handles, fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.22),
                  ncol=1, frameon=False)
    fig.suptitle(f"Orientation workspace   TI₁ = {result.ti1:.6g}   TI₂ = {result.ti2:.6g}", fontsize=11)
    return fig


def sweep_figure(param: str, values: Sequence[float], volumes: Sequence[float], current: Optional[float],
                 current_volume: Optional[float] = None, voxel: Optional[float] = None) -> Figure:
    """Paper Fig. 4: volume against ``param``; the current design value marked by a vertical line."""
    fig = Figure(figsize=(6.4, 3.6), dpi=100, layout="constrained")
    ax = fig.add_subplot(111)
    v = np.asarray(values, float)
    vol = np.asarray(volumes, float)
    ax.plot(v, vol, "o-", color="#1f77b4", lw=1.8, ms=4, label="volume V")
    if current is not None:
        ax.axvline(current, color="#d62728", ls="--", lw=1.2, label=f"current {param} = {current:g}")
        if current_volume is not None and math.isfinite(current_volume):
            ax.plot([current], [current_volume], "D", color="#d62728", ms=6)
    ax.set_xlabel(PARAM_LABELS.get(param, param))
    ax.set_ylabel("workspace volume V")
    ax.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"Volume vs {param}" + (f"  (voxel h = {voxel:g})" if voxel else ""), fontsize=10)
    return fig


def surface_figure(xs: Sequence[float], ys: Sequence[float], volume: Sequence[Sequence[float]],
                   current: Optional[tuple[float, float]] = None, voxel: Optional[float] = None,
                   x_name: str = "a", y_name: str = "d_s") -> Figure:
    """Paper Fig. 5 as a heat map: ``volume[iy][ix]`` over ``xs`` x ``ys``; the current design marked."""
    fig = Figure(figsize=(6.4, 5.0), dpi=100, layout="constrained")
    ax = fig.add_subplot(111)
    x = np.asarray(xs, float)
    y = np.asarray(ys, float)
    z = np.asarray(volume, float)
    mesh = ax.pcolormesh(x, y, z, shading="nearest", cmap="viridis")
    cb = fig.colorbar(mesh, ax=ax)
    cb.set_label("workspace volume V")
    cb.formatter.set_powerlimits((0, 0))
    cb.update_ticks()
    if z.size and np.isfinite(z).any():
        iy, ix = np.unravel_index(int(np.nanargmax(z)), z.shape)
        ax.plot([x[ix]], [y[iy]], marker="*", color="white", mec="black", ms=13,
                label=f"max V = {z[iy, ix]:.4g} at {x_name} = {x[ix]:g}, {y_name} = {y[iy]:g}")
    if current is not None:
        ax.plot([current[0]], [current[1]], marker="o", mfc="none", mec="#d62728", mew=2.2, ms=11,
                label=f"current {x_name} = {current[0]:g}, {y_name} = {current[1]:g}")
    ax.set_xlabel(PARAM_LABELS.get(x_name, x_name))
    ax.set_ylabel(PARAM_LABELS.get(y_name, y_name))
    ax.legend(fontsize=8, loc="lower left", framealpha=0.85)
    ax.set_title(f"Volume over ({x_name}, {y_name})" + (f"  (voxel h = {voxel:g})" if voxel else ""), fontsize=10)
    return fig
