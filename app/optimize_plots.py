"""Pictures and tables of an optimisation's Pareto front (``kinematics.optimize``).

Two figure builders over the JSON form of :class:`~kinematics.optimize.OptimizeResult`
(``result.to_dict()``), kept together so they can move into a shared plotting module later:

* :func:`front_png`: matplotlib, for the command line (2 objectives: a scatter of the front;
  1 objective: the best value per generation; 3 or more: parallel coordinates, each axis scaled
  to the front's range, "better" up);
* :func:`front_figure`: plotly, for the explorer (same choice of plot, interactive).

:func:`front_rows` flattens the front for CSV and tables. Nothing here computes a measure: every
number shown is a field of the result.
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Sequence
from typing import Any

from .fileout import write_atomic

__all__ = ["front_rows", "front_csv", "front_png", "front_figure", "objective_labels"]


def objective_labels(result: dict) -> list[str]:
    """The objectives as the user wrote them (``"volume"``, ``"-footprint"``)."""
    return list(result["settings"]["objectives"])


def _value(entry: dict, label: str) -> float | None:
    v = entry["measures"].get(label.lstrip("-"))
    return None if v is None else float(v)


def front_rows(result: dict) -> list[dict[str, Any]]:
    """One flat dict per front design: ``index``, the free parameters, then every scalar measure."""
    params = list(result["settings"]["params"])
    rows = []
    for i, e in enumerate(result["front"]):
        row: dict[str, Any] = {"index": i}
        row.update({p: e["design"][p] for p in params})
        row.update({k: v for k, v in e["design"].items() if k not in params})
        row.update({k: v for k, v in e["measures"].items() if isinstance(v, (int, float, str, bool)) or v is None})
        rows.append(row)
    return rows


def front_csv(result: dict) -> str:
    """:func:`front_rows` as CSV text (header from the union of the rows' keys, in order)."""
    rows = front_rows(result)
    keys: list[str] = []
    for r in rows:
        keys.extend(k for k in r if k not in keys)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=keys or ["index"], lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow(r)
    return buf.getvalue()


def _design_text(entry: dict, params: Sequence[str]) -> str:
    return ", ".join(f"{p}={entry['design'][p]:g}" for p in params)


def front_png(result: dict, path: str, *, highlight: dict | None = None) -> None:
    """Write a PNG of the front (see module docstring). ``highlight``: an extra point
    ``{"label": str, "measures": {...}}`` drawn as a star (e.g. the paper's design)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    labels = objective_labels(result)
    front = result["front"]
    fig, ax = plt.subplots(figsize=(6.4, 4.6), dpi=120)
    if len(labels) == 1:
        best = [g["best"].get(labels[0]) for g in result["generations"]]
        ax.plot(range(1, len(best) + 1), best, "o-")
        ax.set_xlabel("generation")
        ax.set_ylabel(f"best {labels[0].lstrip('-')}")
    elif len(labels) == 2:
        xs = [_value(e, labels[1]) for e in front]
        ys = [_value(e, labels[0]) for e in front]
        ax.plot(xs, ys, "o", color="tab:blue",  # type: ignore[arg-type]  # None plots as a gap
                label=f"Pareto front ({len(front)} designs)")
        if highlight is not None:
            ax.plot([highlight["measures"][labels[1].lstrip("-")]], [highlight["measures"][labels[0].lstrip("-")]],
                    "*", color="tab:red", markersize=14, label=highlight.get("label", "design"))
        ax.set_xlabel(f"{labels[1].lstrip('-')} ({'minimised' if labels[1].startswith('-') else 'maximised'})")
        ax.set_ylabel(f"{labels[0].lstrip('-')} ({'minimised' if labels[0].startswith('-') else 'maximised'})")
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
    else:
        vals = np.array([[_value(e, lb) for lb in labels] for e in front], dtype=float)
        lo, hi = np.nanmin(vals, axis=0), np.nanmax(vals, axis=0)
        span = np.where(hi > lo, hi - lo, 1.0)
        norm = (vals - lo) / span
        for k, lb in enumerate(labels):  # "better" is up on every axis
            if lb.startswith("-"):
                norm[:, k] = 1.0 - norm[:, k]
        for row in norm:
            ax.plot(range(len(labels)), row, "-", alpha=0.5)
        ax.set_xticks(range(len(labels)))
        ax.set_xticklabels([f"{lb.lstrip('-')}\n[{lo[k]:.3g}, {hi[k]:.3g}]" for k, lb in enumerate(labels)], fontsize=8)
        ax.set_ylabel("scaled to the front's range (better up)")
        ax.set_ylim(-0.05, 1.05)
    hv = result.get("hypervolume") or []
    ax.set_title(f"{len(front)} Pareto-optimal designs over {', '.join(result['settings']['params'])}"
                 + (f"; hypervolume {hv[-1]:.3g}" if hv else ""), fontsize=9)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format=os.path.splitext(os.fspath(path))[1].lstrip(".").lower() or "png")
    plt.close(fig)
    write_atomic(path, buf.getvalue())


def front_figure(result: dict, *, selected: int | None = None) -> Any:
    """An interactive plotly figure of the front (scatter for 2 objectives, parallel coordinates
    for 3 or more, best-per-generation for 1); hover shows each design's free parameters and its
    index in the front (the index the explorer's design list uses). ``selected`` is ringed."""
    import plotly.graph_objects as go

    labels = objective_labels(result)
    params = list(result["settings"]["params"])
    front = result["front"]
    fig = go.Figure()
    if len(labels) == 1:
        best = [g["best"].get(labels[0]) for g in result["generations"]]
        fig.add_trace(go.Scatter(x=list(range(1, len(best) + 1)), y=best, mode="lines+markers", name="best"))
        fig.update_layout(xaxis_title="generation", yaxis_title=f"best {labels[0].lstrip('-')}")
    elif len(labels) == 2:
        text = [f"#{i}: {_design_text(e, params)}" for i, e in enumerate(front)]
        fig.add_trace(go.Scatter(x=[_value(e, labels[1]) for e in front], y=[_value(e, labels[0]) for e in front],
                                 mode="markers", text=text, hoverinfo="text+x+y", name="front"))
        if selected is not None and 0 <= selected < len(front):
            e = front[selected]
            fig.add_trace(go.Scatter(x=[_value(e, labels[1])], y=[_value(e, labels[0])], mode="markers",
                                     marker={"size": 16, "symbol": "circle-open", "color": "red"},
                                     name=f"#{selected}", hoverinfo="skip"))
        fig.update_layout(xaxis_title=labels[1].lstrip("-") + (" (min)" if labels[1].startswith("-") else " (max)"),
                          yaxis_title=labels[0].lstrip("-") + (" (min)" if labels[0].startswith("-") else " (max)"),
                          showlegend=False)
    else:
        dims = [{"label": lb.lstrip("-") + (" (min)" if lb.startswith("-") else " (max)"),
                 "values": [_value(e, lb) for e in front]} for lb in labels]
        dims.insert(0, {"label": "#", "values": list(range(len(front)))})
        fig.add_trace(go.Parcoords(dimensions=dims, line={"color": list(range(len(front))), "colorscale": "Viridis"}))
    fig.update_layout(margin={"l": 50, "r": 10, "t": 10, "b": 40}, height=320)
    return fig
