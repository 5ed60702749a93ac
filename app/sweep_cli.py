"""``paraspace sweep``: workspace measures against one design parameter or over a grid of two (paper
Figs. 4 and 5), in this process or on Dask (:mod:`kinematics.sweep`, :mod:`kinematics.distributed`),
with a CSV, JSON and a plot; ``--mechanism PRESET`` sweeps a preset's parameter.
"""

from __future__ import annotations

import argparse
import csv
import io
import os
import sys
from collections.abc import Sequence
from typing import Any

from paraspace.kinematics.design import PARAMS, Design, ParameterError

from .cli_flags import (
    DESIGN_FLAGS,
    JOINT_FLAGS,
    SCAN_FLAGS,
    add_design_flags,
    add_joint_flags,
    add_scan_flags,
    design_of,
    emit_json,
    floats_of,
    given,
    joints_of,
    length_step_of,
    scan_of,
    voxel_of,
)
from .fileout import write_atomic
from .progressline import progress_line
from .task_cli import add_study_task_flags, study_task

#: ``sweep`` flags that only the paper's design study has
_SWEEP_PAPER_ONLY = {"--plot": "plot", "--z0": "z0", **{flag: f"scan_{name}" for flag, name in SCAN_FLAGS.items()}}


def _preset_row(row: dict, names: Sequence[str]) -> dict:
    """A preset sweep's row: the swept parameters' values first, then the measures (the bookkeeping of
    sweep_1d, sweep_2d and sweep_grid and the full design dict left out; ``ok``/``error`` kept)."""
    design = row.get("design") or {}
    skip = {"param", "value", "param_x", "param_y", "x", "y", "ix", "iy", "params", "index", "design"}
    return {**{n: design.get(n) for n in names}, **{k: v for k, v in row.items() if k not in skip}}


def _sweep_mechanism(ns: argparse.Namespace) -> int:
    """``paraspace sweep --mechanism PRESET --param NAME --values ... [--param2 NAME --values2 ...]
    [--set NAME=VALUE]... [--workers N | --scheduler ADDR]``: workspace measures over one or two of the
    preset's parameters (kinematics/sweep.py on a PresetDesign; Dask: kinematics/distributed.py)."""
    import functools

    from paraspace.kinematics.mechanism_workspace import warm_up_general
    from paraspace.kinematics.presets import PRESETS, PresetDesign
    from paraspace.kinematics.sweep import evaluate_design, sweep_1d, sweep_2d
    from paraspace.kinematics.workspace import WorkspaceSettings, warm_up

    from .mechanism_cli import _param_values

    if ns.mechanism not in PRESETS:
        raise ParameterError("--mechanism", ns.mechanism, f"a preset ({', '.join(PRESETS)}): a sweep varies a "
                                                          "preset's parameter")
    for flag, dest in {**DESIGN_FLAGS, **JOINT_FLAGS, **_SWEEP_PAPER_ONLY}.items():
        if given(ns, flag, dest):
            raise ParameterError(flag, getattr(ns, dest), "not with --mechanism (a preset's sweep: --param NAME "
                                 "--values V1,V2,... [--param2 NAME --values2 ...] [--set NAME=VALUE]... [--voxel H] "
                                 "[--workers N | --scheduler ADDR] [--json] [--csv FILE])")
    for flag, dest in (("--box", "box"), ("--cylinder", "cylinder"), ("--sphere", "sphere"), ("--points", "points")):
        if getattr(ns, dest, None) is not None:
            raise ParameterError(flag, getattr(ns, dest), "not with --mechanism: task measures exist for the "
                                                          "paper's model only")
    if (ns.param2 is None) != (ns.values2 is None):
        raise ParameterError("param2", ns.param2, "given together with --values2")
    design = PresetDesign.of(ns.mechanism, _param_values(ns.set))
    length_step = length_step_of(ns)
    values = floats_of("values", ns.values)
    values2 = None if ns.values2 is None else floats_of("values2", ns.values2)
    settings = WorkspaceSettings(voxel=voxel_of(ns))
    names = [ns.param] + ([] if ns.param2 is None else [ns.param2])
    distributed = ns.scheduler is not None or ns.workers is not None
    warm_up()
    warm_up_general()
    progress, done = progress_line("sweep")
    try:
        if distributed:
            from paraspace.kinematics.distributed import sweep_grid

            grid = {ns.param: values, **({} if values2 is None else {ns.param2: values2})}
            raw = sweep_grid(design, grid, settings, scheduler=ns.scheduler, n_workers=ns.workers, progress=progress,
                             evaluate=functools.partial(evaluate_design, length_step=length_step))
        elif values2 is not None:
            raw = sweep_2d(design, ns.param, values, ns.param2, values2, settings, progress=progress,
                           length_step=length_step)["points"]
        else:
            raw = sweep_1d(design, ns.param, values, settings, progress=progress, length_step=length_step)
    finally:
        done()
    rows = [_preset_row(r, names) for r in raw]
    failed = [r for r in rows if r.get("ok") is False]
    if ns.csv:
        write_atomic(ns.csv, rows_to_csv(rows))
    if ns.json:
        emit_json(rows)
    else:
        sys.stdout.write(rows_to_csv(rows))
    if failed:
        sys.stderr.write(f"paraspace: error: {len(failed)} of {len(rows)} points failed "
                         f"(first: {failed[0].get('error', '?')})\n")
        return 1
    return 0


def backend_workers(ns: argparse.Namespace, auto: bool = True) -> int | None:
    """Local Dask workers of a sweep or optimisation: ``--workers`` as given (0: serially in this
    process); with neither ``--workers`` nor ``--scheduler`` (and ``auto``), the machine's default
    (:func:`kinematics.distributed.default_workers`: a local cluster of half the cores from 8 usable
    cores, else serial)."""
    if ns.workers is not None:
        return None if ns.workers == 0 else ns.workers
    if ns.scheduler is not None or not auto:
        return None
    from paraspace.kinematics.distributed import default_workers

    return default_workers()


def cmd_sweep(ns: argparse.Namespace) -> int:
    from paraspace.kinematics.sweep import sweep_1d, sweep_2d
    from paraspace.kinematics.workspace import WorkspaceSettings, warm_up

    if getattr(ns, "mechanism", None) is not None:
        return _sweep_mechanism(ns)
    if getattr(ns, "set", None):
        raise ParameterError("--set", ns.set[0], "only with --mechanism PRESET")
    design = design_of(ns)
    settings = WorkspaceSettings(voxel=voxel_of(ns), joints=joints_of(ns))
    for field in ("param", "param2"):
        name = getattr(ns, field)
        if name is not None and name not in PARAMS:
            raise ParameterError(field, name, "one of " + ", ".join(PARAMS))
    values = floats_of("values", ns.values)
    if (ns.param2 is None) != (ns.values2 is None):
        raise ParameterError("param2", ns.param2, "given together with --values2")
    orientation = _sweep_orientation(ns)
    task = study_task(ns, settings.joints)
    if ns.plot:
        from paraspace.app.figures import export_format

        try:
            export_format(ns.plot)
        except ValueError as err:
            raise ParameterError("plot", ns.plot, str(err)) from None
    workers = backend_workers(ns, auto=task is None)
    distributed = ns.scheduler is not None or workers is not None
    cores = os.cpu_count() or 1
    if ns.scheduler is None and workers is not None and workers > cores:
        # a local cluster of more single-threaded workers than cores is slower than the serial path
        # (which already uses every core): say so, and run serially
        sys.stderr.write(f"paraspace: --workers {ns.workers} exceeds this machine's {cores} cores; running the "
                         f"sweep serially instead (it uses all {cores} cores)\n")
        distributed = False
    if task is not None and distributed:
        raise ParameterError("workers" if ns.workers is not None else "scheduler", ns.workers or ns.scheduler,
                             "omit it with a task (task sweeps run in this process)")
    warm_up()
    progress, done = progress_line("sweep")
    try:
        if ns.param2 is not None:
            values2 = floats_of("values2", ns.values2)
            if distributed:
                from paraspace.kinematics.distributed import sweep_grid

                rows = sweep_grid(design, {ns.param: values, ns.param2: values2}, settings, orientation=orientation,
                                  scheduler=ns.scheduler, n_workers=workers, progress=progress)
            else:
                rows = sweep_2d(design, ns.param, values, ns.param2, values2, settings, orientation=orientation,
                                progress=progress, task=task)["points"]
        elif distributed:
            from paraspace.kinematics.distributed import sweep_grid

            rows = sweep_grid(design, {ns.param: values}, settings, orientation=orientation, scheduler=ns.scheduler,
                              n_workers=workers, progress=progress)
        else:
            rows = sweep_1d(design, ns.param, values, settings, orientation=orientation, progress=progress,
                            task=task)
    finally:
        done()
    rows = [_with_value(r, ns.param, ns.param2) for r in rows]
    failed = [r for r in rows if r.get("ok") is False]
    if ns.csv:
        write_atomic(ns.csv, rows_to_csv(rows))
    if ns.plot:
        plot_sweep(rows, ns.param, ns.param2, ns.plot, ns.measure, design, settings.voxel)
    if ns.json:
        emit_json(rows)
    else:
        sys.stdout.write(rows_to_csv(rows))
    if failed:  # the rows above say which; the exit status says that the study is incomplete
        sys.stderr.write(f"paraspace: error: {len(failed)} of {len(rows)} points failed "
                         f"(first: {failed[0].get('error', '?')})\n")
        return 1
    return 0


def _sweep_orientation(ns: argparse.Namespace) -> Any:
    """The orientation settings of a sweep: ``--z0``, or the paper's z0 = 130 when ``--measure`` is
    TI_1/TI_2 (``None``: no orientation maps), with the joint flags. Checks ``--measure``."""
    from paraspace.app.figures import MEASURES
    from paraspace.kinematics.orientation import OrientationSettings
    from paraspace.kinematics.settings import ORIENTATION

    if ns.measure not in MEASURES:
        raise ParameterError("measure", ns.measure, "one of " + ", ".join(MEASURES))
    if ns.z0 is None:
        if ns.measure not in ("TI_1", "TI_2"):
            scans = [flag for flag, name in SCAN_FLAGS.items() if getattr(ns, f"scan_{name}") is not None]
            if scans:
                raise ParameterError(scans[0].lstrip("-"), getattr(ns, f"scan_{SCAN_FLAGS[scans[0]]}"),
                                     "only with --measure TI_1/TI_2 or --z0 (the orientation maps)")
            return None
        return OrientationSettings(joints=joints_of(ns), **scan_of(ns))
    return OrientationSettings(z0=float(ORIENTATION["z0"].parse(ns.z0)), joints=joints_of(ns), **scan_of(ns))


def _with_value(row: dict, param: str, param2: str | None) -> dict:
    out = dict(row)
    if "value" not in out and param in out.get("design", {}):
        out["value"] = out["design"][param]
    if param2 is not None and "value2" not in out and param2 in out.get("design", {}):
        out["value2"] = out["design"][param2]
    return out


def rows_to_csv(rows: Sequence[dict]) -> str:
    """Flat CSV of sweep rows (scalar columns only)."""
    if not rows:
        return ""
    keys = [k for k, v in rows[0].items() if isinstance(v, (int, float, str, bool)) or v is None]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=keys, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: r.get(k) for k in keys})
    return buf.getvalue()


def plot_sweep(rows: Sequence[dict], param: str, param2: str | None, path: str, measure: str = "volume",
               design: Design | None = None, voxel: float | None = None) -> None:
    """``measure`` against one parameter (paper Fig. 4) or over two (Fig. 5: a 3-D surface and a heat
    map whose cells are centred on the samples), written to ``path`` (.png at 200 dpi, .svg or .pdf)
    with :mod:`paraspace.app.figures`, the explorer's plotting module. ``design`` (the design the
    sweep varies) is marked."""
    from paraspace.app import figures

    fmt = figures.export_format(path)
    if param2 is None:
        cur = float(getattr(design, param)) if design is not None else None
        spec = figures.sweep_spec(rows, param, measure, current=cur, voxel=voxel)
    else:
        xs = sorted({float(r["value"]) for r in rows})
        ys = sorted({float(r["value2"]) for r in rows})
        grid: list[list[Any]] = [[None] * len(xs) for _ in ys]
        for r in rows:
            grid[ys.index(float(r["value2"]))][xs.index(float(r["value"]))] = r.get(measure)
        cur2 = (float(getattr(design, param)), float(getattr(design, param2))) if design is not None else None
        spec = figures.study_spec(xs, ys, grid, param_x=param, param_y=param2, measure=measure, current=cur2,
                                  voxel=voxel)
    write_atomic(path, figures.export(spec, fmt))


def add_sweep_parser(sub: Any) -> None:
    """The ``sweep`` command's flags (its parser among ``sub``)."""
    s = sub.add_parser("sweep", help="measures against one parameter (or a 2-D grid of two)")
    add_design_flags(s)
    s.add_argument("--param", required=True, help="one of " + ", ".join(PARAMS) + " (with --mechanism: one of the "
                                                   "preset's parameters)")
    s.add_argument("--values", required=True, help="comma-separated values")
    s.add_argument("--param2", help="second parameter for a 2-D grid")
    s.add_argument("--values2", help="values of the second parameter")
    s.add_argument("--voxel", default=4.0, help="voxel edge h (default 4)")
    s.add_argument("--json", action="store_true", help="a JSON list of objects with value and volume")
    s.add_argument("--csv", metavar="FILE")
    s.add_argument("--plot", metavar="FILE", help="a picture of the study: .png (200 dpi), .svg or .pdf")
    s.add_argument("--measure", default="volume", metavar="NAME",
                   help="the plotted measure (default volume; hollowness, void_ratio, solidity, voids, genus, ...; "
                        "TI_1/TI_2 need --z0)")
    s.add_argument("--z0", default=None, metavar="Z",
                   help="also compute TI_1, TI_2 of every point at this height of the x and y' lines (paper: 130)")
    s.add_argument("--scheduler", metavar="ADDR", help="run on a Dask scheduler (e.g. tcp://host:8786)")
    s.add_argument("--workers", type=int, metavar="N",
                   help="run on a local Dask cluster with N workers (0: in this process; default: half the cores "
                        "from 8 usable cores, else in this process)")
    s.add_argument("--mechanism", metavar="PRESET", help="sweep a parameter of a mechanism preset instead of the "
                                                         "paper's design (see 'paraspace mechanism presets')")
    s.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="with --mechanism: a fixed parameter of the preset (repeatable)")
    s.add_argument("--length-step", dest="length_step", metavar="L",
                   help="with --mechanism: spacing of a sampled (second) prismatic joint's values, [0.01, 100] "
                        "(default 1)")
    add_scan_flags(s)
    add_joint_flags(s)
    add_study_task_flags(s, "a task: each point also gets task_fraction, task_margin, contains_task")
    s.set_defaults(func=cmd_sweep)
