"""``paraspace optimize``: the Pareto front of measures over design parameters
(:mod:`kinematics.optimize`), serially or on a warm local Dask cluster, with a CSV and a plot of the
front; ``--mechanism PRESET`` optimises a preset's parameters.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any

from paraspace.kinematics.design import PARAMS, Design, ParameterError

from .cli_flags import (
    add_design_flags,
    add_joint_flags,
    add_scan_flags,
    design_of,
    emit_json,
    joints_of,
    length_step_of,
    mechanism_of,
    scan_of,
    voxel_of,
)
from .fileout import write_atomic
from .mechanism_cli import add_mechanism_flags
from .progressline import progress_scope
from .sweep_cli import backend_workers
from .task_cli import add_study_task_flags, study_task


def _bounds_arg(text: str | None, known: Sequence[str] = tuple(PARAMS)) -> dict[str, tuple[float, float]]:
    """``"l_s=20:100,a=10:90"`` -> ``{"l_s": (20, 100), "a": (10, 90)}`` (names among ``known``)."""
    out: dict[str, tuple[float, float]] = {}
    if not text:
        return out
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        name, sep, rng = part.partition("=")
        lo, sep2, hi = rng.partition(":")
        if not sep or not sep2:
            raise ParameterError("bounds", part, "NAME=LO:HI, comma-separated, e.g. l_s=20:100,a=10:90")
        name = name.strip()
        if name not in known:
            raise ParameterError("bounds", name, "parameters " + ", ".join(known))
        try:
            out[name] = (float(lo), float(hi))
        except ValueError:
            raise ParameterError(name, rng, "LO:HI, two numbers") from None
    return out


def optimize_settings_from_args(ns: argparse.Namespace) -> Any:
    """The core ``OptimizeSettings`` of the ``optimize`` flags (validated by the core)."""
    from paraspace.kinematics.optimize import OptimizeSettings
    from paraspace.kinematics.orientation import OrientationSettings
    from paraspace.kinematics.settings import OPTIMIZE
    from paraspace.kinematics.workspace import WorkspaceSettings

    constraints = [c.strip() for raw in (ns.constraint or []) for c in raw.split(",") if c.strip()]
    preset, values, length_step, known = _optimize_preset(ns)
    general = preset not in (None, "paper")
    joints = joints_of(ns)
    spec = study_task(ns, joints)
    total = None
    if ns.tilt is not None or ns.torsion is not None:
        total = (0.0 if ns.tilt is None else ns.tilt, 0.0 if ns.torsion is None else ns.torsion, ns.task_angle_step)
    from paraspace.kinematics.optimize import DEFAULT_PARAMS

    params = ns.params if ns.params is not None else ",".join(known if general else DEFAULT_PARAMS)
    objectives = ns.objectives if ns.objectives is not None else ("volume,-l_max" if general else "volume,-footprint")
    return OptimizeSettings(
        task=spec, total_orientation=total, preset=preset, preset_values=values, length_step=length_step,
        params=tuple(p.strip() for p in params.split(",")), bounds=_bounds_arg(ns.bounds, known),
        objectives=objectives, constraints=constraints, design=Design() if preset is not None else design_of(ns),
        workspace=WorkspaceSettings(voxel=voxel_of(ns), joints=joints),
        orientation=OrientationSettings(joints=joints, **scan_of(ns)),
        population=int(OPTIMIZE["population"].parse(ns.population)),
        generations=int(OPTIMIZE["generations"].parse(ns.generations)),
        seed=int(OPTIMIZE["seed"].parse(ns.seed)), step=OPTIMIZE["step"].parse(ns.step), algorithm=ns.algorithm)


def _optimize_preset(ns: argparse.Namespace) -> tuple[str | None, dict[str, Any], float, list[str]]:
    """``optimize --mechanism PRESET [--param NAME=VALUE]... [--length-step L]``: ``(preset, its fixed
    values, length_step, the names --params and --bounds may use)``; ``(None, {}, 1, PARAMS)`` without
    ``--mechanism``. A file is refused (the optimiser varies a preset's parameters); so are the design
    flags, and the joint flags with a general preset (by :func:`mechanism_of`)."""
    from paraspace.kinematics.presets import PRESETS

    from .mechanism_cli import _param_values

    if getattr(ns, "mechanism", None) is not None and ns.mechanism not in PRESETS:
        raise ParameterError("--mechanism", ns.mechanism, f"a preset ({', '.join(PRESETS)}): the optimiser varies "
                                                          "a preset's parameters, not a description file's")
    mechanism_of(ns, {})  # refuses the flags a preset replaces (and validates --param)
    if ns.mechanism is None:
        return None, {}, 1.0, list(PARAMS)
    known = [q.name for q in PRESETS[ns.mechanism].params if q.numeric]
    return ns.mechanism, _param_values(ns.param), length_step_of(ns), known


def cmd_optimize(ns: argparse.Namespace) -> int:
    """``paraspace optimize``: the Pareto front of the objectives over the free parameters."""
    from paraspace.kinematics.optimize import optimize
    from paraspace.kinematics.workspace import warm_up

    settings = optimize_settings_from_args(ns)
    if ns.plot and not ns.plot.lower().endswith(".png"):
        raise ParameterError("plot", ns.plot, "a file name ending in .png")
    if ns.scheduler is not None and ns.workers is not None:
        raise ParameterError("workers", ns.workers, "omit it with --scheduler (the scheduler's workers are used)")
    if settings.general:
        from paraspace.kinematics.mechanism_workspace import warm_up_general

        warm_up_general()
    else:
        warm_up()

    with progress_scope("optimize", force=ns.progress) as progress:
        result = optimize(settings, scheduler=ns.scheduler, workers=backend_workers(ns), progress=progress).to_dict()
    from paraspace.app.optimize_plots import front_csv, front_png

    if ns.csv:
        write_atomic(ns.csv, front_csv(result))
    if ns.plot:
        front_png(result, ns.plot)
    if ns.json:
        emit_json(result)
    else:
        labels = result["settings"]["objectives"]
        params = result["settings"]["params"]
        print(f"{len(result['front'])} Pareto-optimal designs ({result['evaluations']} evaluations, "
              f"{result['computed']} computed, {len(result['failed'])} failed, {result['seconds']:.1f} s, "
              f"{result['settings']['algorithm']}, {result['backend']})")
        head = params + [lb.lstrip("-") for lb in labels]
        print("  ".join(f"{h:>12}" for h in head))
        for e in result["front"]:
            vals = [e["design"][p] for p in params] + [e["measures"].get(lb.lstrip("-")) for lb in labels]
            print("  ".join(f"{v:>12.6g}" if isinstance(v, (int, float)) else f"{v!s:>12}" for v in vals))
        hv = result["hypervolume"]
        if hv:
            print("hypervolume per generation: " + " ".join(f"{v:.4g}" for v in hv))
    return 0


def add_optimize_parser(sub: Any) -> None:
    from paraspace.kinematics.objectives import MEASURES
    from paraspace.kinematics.optimize import ALGORITHMS, DEFAULT_PARAMS

    z = sub.add_parser("optimize", help="multi-objective optimal design: the Pareto front over design parameters")
    add_design_flags(z)
    z.add_argument("--params",
                   help=f"free parameters, comma-separated (default {','.join(DEFAULT_PARAMS)}; any of "
                        f"{', '.join(PARAMS)}); the others keep the design flags' values. With --mechanism "
                        "PRESET: the preset's numeric parameters (default all of them), the others --param's "
                        "values or the preset's defaults")
    z.add_argument("--objectives",
                   help="measures, comma-separated; a leading - minimises (default volume,-footprint; with a "
                        "general --mechanism volume,-l_max, and only the position workspace's measures and the "
                        "preset's parameters exist). Measures: " + ", ".join(k for k, m in MEASURES.items()
                                                                            if not m.flag))
    z.add_argument("--constraint", action="append", metavar="C",
                   help="repeatable: a flag (" + ", ".join(k for k, m in MEASURES.items() if m.flag)
                        + ") or MEASURE>=V / MEASURE<=V, e.g. \"volume>=2e6\"")
    z.add_argument("--bounds", help="NAME=LO:HI,... (default: paper Table I's ranges; with --mechanism PRESET each "
                                    "parameter's study range, 'paraspace mechanism presets')")
    from paraspace.kinematics.settings import OPTIMIZE

    for name, note in (("population", ""), ("generations", "; 16 x 12 at h = 4 takes about 50 s here"), ("seed", ""),
                       ("step", "")):
        spec = OPTIMIZE[name]
        z.add_argument(f"--{name}", default=spec.default,
                       help=f"{spec.label}; valid range {spec.range_text()} (default {spec.default:g}{note})")
    z.add_argument("--voxel", default=4.0, help="voxel edge h (default 4)")
    z.add_argument("--algorithm", default="auto", choices=ALGORITHMS,
                   help="auto: NSGA-II up to 2 objectives, NSGA-III from 3")
    z.add_argument("--json", action="store_true", help="one JSON object: front, hypervolume, settings...")
    z.add_argument("--csv", metavar="FILE", help="the front, one design per row")
    z.add_argument("--plot", metavar="FILE.png", help="a picture of the front")
    z.add_argument("--progress", action="store_true",
                   help="show the progress bar on stderr even when it is not a terminal")
    z.add_argument("--scheduler", metavar="ADDR", help="evaluate on a Dask scheduler (e.g. tcp://host:8786)")
    z.add_argument("--workers", type=int, metavar="N",
                   help="evaluate on a local Dask cluster with N workers, kept warm for the run (0: in this process; "
                        "default: half the cores from 8 usable cores, else in this process)")
    add_scan_flags(z)
    add_joint_flags(z)
    add_study_task_flags(z, "the task of task_fraction, task_margin and --constraint contains_task")
    add_mechanism_flags(z)
    z.set_defaults(func=cmd_optimize)
