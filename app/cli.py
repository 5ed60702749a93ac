"""The ``paraspace`` command line.

    paraspace workspace   [design flags] [joint flags] [--voxel H] [--json] [--export FILE.stl|.ply|.obj|.glb]
                          [--bracket [--bracket-refine N]] [--tilt DEG --torsion DEG [--angle-step DEG]]
                          [--dexterity [--kappa-min X]]
    paraspace orientation [design flags] [joint flags] [--z0 Z] [--position-delta per_region|line|phi] [--json]
    paraspace orientation [design flags] [joint flags] --at x,y,z [--azimuth-step DEG] [--json]   (tilt-and-torsion)
    paraspace sweep       [design flags] --param NAME --values V1,V2,... [--param2 NAME --values2 ...]
                          [--voxel H] [--json] [--csv FILE] [--plot FILE.png|.svg|.pdf] [--measure NAME]
                          [--z0 Z] [--scheduler ADDR] [--workers N]
    paraspace optimize    [design flags] --params a,d_s,eta_s,l_s --objectives volume,-footprint
                          [--constraint C] [--bounds l_s=20:100,...] [--population N] [--generations G]
                          [--seed S] [--voxel H] [--json] [--csv F] [--plot F.png] [--scheduler ADDR | --workers N]
                          [joint flags] [--box ... | --cylinder ... | --sphere ... | --points F [--tilt --torsion]]
    paraspace task        [design flags] [joint flags] --box CX,CY,CZ,LX,LY,LZ | --cylinder CX,CY,CZ,R,H |
                          --sphere CX,CY,CZ,R | --points FILE.csv [--tilt DEG] [--torsion DEG] [--voxel H]
                          [--json] [--csv OUT]
    paraspace paper       [--voxel H] [--assumptions K,..] [scan flags] [--fit] [--json]   (every claim, verdicts)
    paraspace report      [design flags] [joint flags] [--compare NAME=V,..]... [--voxel H] --out FILE.html
    paraspace ik          [design flags] --pose x,y,z,psi,theta,phi [--carriage d1,d2,d3,eta1,eta2,eta3] [--json]
    paraspace serve       [--host H] [--port P] [--api-port Q]
    paraspace mechanism   show|export|presets [FILE|PRESET] [--param NAME=VALUE]... [--json] [-o FILE]

Mechanism flags (``workspace``, ``orientation``, ``ik``, ``task``): ``--mechanism FILE|PRESET
[--param NAME=VALUE]... [--length-step L]`` instead of the design flags; ``sweep --mechanism PRESET --param
NAME --values ... [--set NAME=VALUE]...`` sweeps a preset's parameter; ``optimize --mechanism PRESET
[--param NAME=VALUE]... --params NAME,...`` optimises a preset's parameters (kinematics/optimize.py). The
paper preset (or a file equal to it) runs the paper's engine with every option; any other mechanism runs
the general engine (kinematics/mechanism_workspace.py: the position workspace, its measures and shell, its
certified bracket with --bracket-refine, IK; ``--diagnostics`` names the binding limit per chain:
kinematics/mechanism_diagnostics.py; ``workspace --tilt/--torsion`` and ``--dexterity``:
kinematics/mechanism_orientation.py and mechanism_dexterity.py; ``orientation``: the scans and TI along the
mechanism's symmetry lines), and the flags only the paper's engine has (design and joint flags,
--dexterity-mode best, orientation --at, ik --carriage) are refused by name.

Design flags: ``--a --b --d-s --r --l-min --l-s --eta-s --eta-range centered|from-zero``.
Joint flags (``workspace``, ``orientation``, ``sweep``, ``optimize``, ``task``, ``ik``): ``--u-cone DEG --s-cone DEG
[--cone-axis normal|home] --leg-diameter W [--clearance C]``.
Scan flags (``orientation``, ``sweep``, ``optimize``, ``paper``; TI_1 and TI_2): ``--angle-range DEG --angle-step DEG
--position-step S`` (ranges: ``kinematics.settings.ORIENTATION``).
Every command except ``serve`` uses only the numerical core (no web packages are imported).
Bad flags or values exit with status 2 and one line naming the field and its valid range.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import os
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

import paraspace
from paraspace.kinematics.design import PARAMS, Design, ParameterError

from .cli_flags import add_design_flags, add_joint_flags, design_of, joints_of
from .fileout import write_atomic
from .mechanism_cli import add_mechanism_flags
from .numfmt import fixed, significant
from .progressline import progress_line, progress_scope


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, status 2
        self.exit(2, f"paraspace: error: {message}\n")


def _floats(field: str, text: str, count: int | None = None) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",") if v.strip() != ""]
    except ValueError:
        raise ParameterError(field, text, "comma-separated numbers") from None
    if not vals or (count is not None and len(vals) != count):
        raise ParameterError(field, text, f"{count} comma-separated numbers" if count else "at least one number")
    if not all(math.isfinite(v) for v in vals):
        raise ParameterError(field, text, "finite numbers")
    return vals


def _export_shell(result: Any, path: str, fmt: str) -> dict[str, Any]:
    """Write the marching-cubes shell of ``result`` to ``path`` whole (``--export``); its JSON entry."""
    from paraspace.kinematics.shell import export_shell, workspace_shell

    mesh = workspace_shell(result)
    write_atomic(path, export_shell(mesh, fmt))
    return {"file": path, "faces": int(len(mesh.faces)), "mesh_volume": float(mesh.volume)}


#: The orientation scan's flags (``orientation``, ``sweep``, ``optimize``): flag -> table entry name.
SCAN_FLAGS: dict[str, str] = {"--angle-range": "angle_range", "--angle-step": "angle_step",
                              "--position-step": "position_step"}


def _add_scan_flags(p: argparse.ArgumentParser) -> None:
    """The orientation scan's flags, each derived from its entry of ``kinematics.settings.ORIENTATION``
    (help: label, valid range, default)."""
    from paraspace.kinematics.settings import ORIENTATION

    g = p.add_argument_group("orientation scan (TI_1, TI_2)")
    for flag, name in SCAN_FLAGS.items():
        spec = ORIENTATION[name]
        g.add_argument(flag, dest=f"scan_{name}", default=None, metavar="V",
                       help=f"{spec.label}; valid range {spec.range_text()} (default {spec.default:g})")


def _scan(ns: argparse.Namespace) -> dict[str, Any]:
    """The scan flags given, read and checked by their table entries (the others keep their defaults)."""
    from paraspace.kinematics.settings import ORIENTATION

    return {name: float(ORIENTATION[name].parse(getattr(ns, f"scan_{name}"))) for name in SCAN_FLAGS.values()
            if getattr(ns, f"scan_{name}", None) is not None}


def _bracket_refine(ns: argparse.Namespace) -> int:
    """``--bracket-refine``, read by its one definition (kinematics.settings.WORKSPACE)."""
    from paraspace.kinematics.settings import WORKSPACE

    return int(WORKSPACE["bracket_refine"].parse(ns.bracket_refine))


def _voxel(ns: argparse.Namespace) -> float:
    """``--voxel`` read and checked by its table entry (:data:`kinematics.settings.WORKSPACE`)."""
    from paraspace.kinematics.settings import WORKSPACE

    return float(WORKSPACE["voxel"].parse(ns.voxel))


def _float_arg(field: str, raw: Any, valid: str) -> float:
    try:
        v = float(raw)
    except (TypeError, ValueError):
        raise ParameterError(field, raw, f"{valid} (a number)") from None
    if not math.isfinite(v):
        raise ParameterError(field, raw, valid)
    return v


def _emit(obj: Any) -> None:
    json.dump(obj, sys.stdout, indent=2)
    sys.stdout.write("\n")


#: flags that set the paper's design or the global joint options: a mechanism description replaces them
_DESIGN_FLAGS: dict[str, str] = {**{f"--{n.replace('_', '-')}": n for n in PARAMS}, "--eta-range": "eta_range"}
_JOINT_FLAGS: dict[str, str] = {"--u-cone": "theta_u", "--s-cone": "theta_s", "--cone-axis": "cone_axis",
                                "--leg-diameter": "leg_diameter", "--clearance": "clearance"}


def _given(ns: argparse.Namespace, flag: str, dest: str) -> bool:
    """Whether ``flag`` was written on the command line (or its value differs from the default)."""
    tokens = {t.split("=", 1)[0] for t in getattr(ns, "argv", []) if t.startswith("--")}
    if flag in tokens:
        return True
    default = _DEFAULTS.get(dest)
    value = getattr(ns, dest, None)
    return value not in (None, False) and value != default and str(value) != str(default)


_DEFAULTS: dict[str, Any] = {**{n: spec.default for n, spec in PARAMS.items()}, "eta_range": "centered",
                             "cone_axis": "normal", "leg_diameter": 0.0, "clearance": 0.0, "angle_step": 5.0,
                             "dexterity_mode": "resolved", "bracket_refine": 2, "method": "blocks"}


def _mechanism(ns: argparse.Namespace, paper_only: dict[str, str]) -> tuple[Any, Design | None]:
    """``--mechanism FILE|PRESET [--param NAME=VALUE]...``: ``(mechanism, design)`` where ``design`` is the
    equivalent paper :class:`Design` (the paper's engine and every option apply) or ``None`` (a general
    mechanism: the flags of ``paper_only``, the design flags and the joint flags are refused by name).
    Without ``--mechanism``: ``(None, the design flags' Design)``."""
    if getattr(ns, "mechanism", None) is None:
        for flag, dest in (("--param", "param"), ("--length-step", "length_step")):
            if getattr(ns, dest, None):
                raise ParameterError(flag, getattr(ns, dest) if dest != "param" else ns.param[0],
                                     "only with --mechanism FILE|PRESET")
        return None, design_of(ns)
    from paraspace.kinematics.mechanism_workspace import paper_design

    from .mechanism_cli import resolve_mechanism

    for flag, dest in _DESIGN_FLAGS.items():
        if _given(ns, flag, dest):
            raise ParameterError(flag, getattr(ns, dest), "not with --mechanism: set a preset's parameters with "
                                 "--param NAME=VALUE (paraspace mechanism presets lists them)")
    mech = resolve_mechanism(ns.mechanism, ns.param)
    design = paper_design(mech)
    if design is None:
        for flag, dest in _JOINT_FLAGS.items():
            if _given(ns, flag, dest):
                raise ParameterError(flag, getattr(ns, dest), "only for the paper's mechanism: a description "
                                     "carries its own cones (u_cone, s_cone per leg)")
        for flag, dest in paper_only.items():
            if _given(ns, flag, dest):
                raise ParameterError(flag, getattr(ns, dest), f"only for the paper's mechanism, not {mech.name!r}")
    return mech, design


def _length_step(ns: argparse.Namespace) -> float:
    from paraspace.kinematics.mechanism_workspace import check_length_step

    raw = getattr(ns, "length_step", None)
    return check_length_step(_float_arg("length_step", raw, "[0.01, 100]")) if raw is not None else 1.0


def _total_and_dexterity(ns: argparse.Namespace) -> tuple[tuple[float, float, float] | None,
                                                          tuple[float, str] | None]:
    """``--tilt/--torsion/--angle-step`` and ``--dexterity/--kappa-min/--dexterity-mode`` of ``workspace``,
    checked by their table entries: ``((tilt, torsion, step) or None, (kappa_min, mode) or None)``."""
    from paraspace.kinematics.dexterous import check_step, orientation_samples
    from paraspace.kinematics.settings import TOTAL_ORIENTATION

    step = check_step(ns.angle_step)
    total = None
    if ns.tilt is not None or ns.torsion is not None:
        tilt = TOTAL_ORIENTATION["tilt"].parse(0.0 if ns.tilt is None else ns.tilt)
        torsion = TOTAL_ORIENTATION["torsion"].parse(0.0 if ns.torsion is None else ns.torsion)
        orientation_samples(tilt, torsion, step)  # validates tilt and torsion
        total = (float(tilt), float(torsion), step)
    dexterity = None
    if ns.dexterity or ns.kappa_min is not None:
        from paraspace.kinematics.dexterity import MODES, check_kappa_min

        kappa_min = check_kappa_min(0.005 if ns.kappa_min is None else ns.kappa_min)
        if ns.dexterity_mode not in MODES:
            raise ParameterError("dexterity_mode", ns.dexterity_mode, " or ".join(MODES))
        dexterity = (kappa_min, ns.dexterity_mode)
    return total, dexterity


def _dexterity_search(ns: argparse.Namespace) -> dict[str, Any]:
    """``--dexterity-search`` and ``--margin-tolerance``, validated by their definitions
    (kinematics.dexterity.SEARCHES, kinematics.settings.DEXTERITY): keyword arguments of
    ``dexterity_field``; only the ones the user gave."""
    from paraspace.kinematics.dexterity import check_search
    from paraspace.kinematics.settings import DEXTERITY

    out: dict[str, Any] = {}
    if ns.dexterity_search is not None:
        out["search"] = check_search(ns.dexterity_search)
    if ns.margin_tolerance is not None:
        out["margin_tolerance"] = DEXTERITY["margin_tolerance"].parse(ns.margin_tolerance)
    return out


def _add_dexterity(out: dict[str, Any], dex: dict[str, Any]) -> None:
    out["gci"], out["well_conditioned_volume"], out["kappa_min"] = (
        dex["gci"], dex["well_conditioned_volume"], dex["kappa_min"])
    out["dexterity"] = dex
    chk = dex.get("dexterity_check")
    if chk is not None and not chk["tolerance_held"]:  # never silent, with --json too
        print(f"paraspace: warning: {chk['message']}", file=sys.stderr)


def _print_total_and_dexterity(out: dict[str, Any]) -> None:
    if "dexterity" in out:
        d = out["dexterity"]
        print(f"gci             {significant(d['gci'], 4)}  (mean 1/kappa of eq. (26), "
              f"{d['dexterity_mode']} carriages, {d.get('dexterity_search', 'full')} search; "
              f"range {d['inverse_condition_min']:.3g} .. {d['inverse_condition_max']:.3g})")
        print(f"well_cond_volume {significant(d['well_conditioned_volume'], 4)}  (1/kappa >= {d['kappa_min']:g})")
        chk = d.get("dexterity_check")
        if chk is not None:
            print(f"dexterity_check  {chk['message']}")
    if "total_orientation" in out:
        t = out["total_orientation"]
        print(f"total_orient_vol {significant(t['volume'], 4)}  (tilt <= {t['tilt']:g}, "
              f"|torsion| <= {t['torsion']:g} deg; "
              f"{t['orientations']} orientations, step {t['angle_step']:g} deg; {t['seconds']:.1f} s)")


def _workspace_general(ns: argparse.Namespace, mech: Any) -> int:
    """``paraspace workspace --mechanism`` for a general mechanism: the position workspace, its measures
    and the shell (kinematics/mechanism_workspace.py)."""
    from paraspace.kinematics.measures import measure_workspace
    from paraspace.kinematics.mechanism_workspace import compute_mechanism_workspace, warm_up_general
    from paraspace.kinematics.workspace import WorkspaceSettings

    refine = _bracket_refine(ns)
    settings = WorkspaceSettings(voxel=_voxel(ns), method=ns.method, bracket=ns.bracket, bracket_refine=refine)
    length_step = _length_step(ns)
    total, dexterity = _total_and_dexterity(ns)
    search = _dexterity_search(ns) if dexterity is not None else {}
    if dexterity is not None:
        from paraspace.kinematics.mechanism_dexterity import check_general_mode

        check_general_mode(dexterity[1])
    fmt = _export_format(ns)
    warm_up_general()
    with progress_scope("workspace") as progress:
        result = compute_mechanism_workspace(mech, settings, length_step, progress)
    measures = measure_workspace(result)
    out = {"mechanism": mech.to_dict(), "engine": result.engine, **measures.to_dict(),
           "voxel_size": result.grid.h, "voxels": result.voxels, "volume": result.volume,
           "compute_seconds": result.compute_seconds, "grid": result.grid.to_dict(),
           "carriage_samples": list(result.samples), "eta_step": settings.eta_step, "length_step": length_step}
    if ns.bracket:
        out["volume_inner"], out["volume_outer"] = result.volume_inner, result.volume_outer
        out["bracket_seconds"] = result.bracket_seconds
    if dexterity:
        from paraspace.kinematics.mechanism_dexterity import mechanism_dexterity_field

        _add_dexterity(out, mechanism_dexterity_field(result, *dexterity, **search).summary())
    if total:
        from paraspace.kinematics.mechanism_orientation import mechanism_total_orientation

        dx = mechanism_total_orientation(mech, *total, settings, length_step, position=result)
        out["total_orientation"] = {**dx.summary(), "measures": measure_workspace(dx.result).to_dict()}
    if ns.diagnostics and result.engine == "general":  # which limit binds at the surface, per chain
        from paraspace.kinematics.mechanism_diagnostics import mechanism_limit_binding

        out["limit_binding"] = mechanism_limit_binding(result).to_dict()
    if fmt:
        out["export"] = _export_shell(result, ns.export, fmt)
    if ns.json:
        _emit(out)
    else:
        print(f"mechanism       {mech.name}  (general engine; carriage samples per chain "
              f"{', '.join(str(n) for n in result.samples)})")
        print(f"volume          {out['volume']:.6g}  ({out['voxels']} voxels of {out['voxel_size']:g}^3)")
        if ns.bracket:
            print(f"certified       {out['volume_inner']:.6g} <= V <= {out['volume_outer']:.6g}"
                  "  (continuous workspace, general_bracket)")
        for key in ("components", "voids", "void_volume", "void_ratio", "hollowness", "boundary_closed", "genus"):
            if key in out:
                print(f"{key:<15} {out[key]}")
        print(f"bounds          {out.get('bounds')}")
        if "limit_binding" in out:
            print(f"limits          {out['limit_binding']['summary']}")
        print(f"compute_seconds {out['compute_seconds']:.3f}")
        _print_total_and_dexterity(out)
        if fmt:
            print(f"exported        {ns.export} ({out['export']['faces']} faces)")
    return 0


def _export_format(ns: argparse.Namespace) -> str | None:
    if not ns.export:
        return None
    fmt = ns.export.rsplit(".", 1)[-1].lower() if "." in ns.export else ""
    if fmt not in ("stl", "ply", "obj", "glb"):
        raise ParameterError("export", ns.export, "a file name ending in .stl, .ply, .obj or .glb")
    return fmt


#: ``workspace`` flags that only the paper's engine computes
#: ``workspace`` flags that only the paper's engine computes (none left: a general mechanism's bracket
#: refinement, diagnostics, tilt/torsion and dexterity are computed by the general modules)
_WORKSPACE_PAPER_ONLY: dict[str, str] = {}


def cmd_workspace(ns: argparse.Namespace) -> int:
    from paraspace.kinematics.measures import measure_workspace
    from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace, warm_up

    mech, design = _mechanism(ns, _WORKSPACE_PAPER_ONLY)
    if design is None:
        return _workspace_general(ns, mech)
    if mech is not None:
        _length_step(ns)  # validated; the paper's engine solves d exactly and samples no other prismatic joint
    refine = _bracket_refine(ns)
    settings = WorkspaceSettings(voxel=_voxel(ns), diagnostics=ns.diagnostics, method=ns.method, bracket=ns.bracket,
                                 bracket_refine=refine,
                                 joints=joints_of(ns))
    total, dexterity = _total_and_dexterity(ns)
    fmt = _export_format(ns)
    warm_up()
    with progress_scope("workspace") as progress:
        result = compute_workspace(design, settings, progress)
    measures = measure_workspace(result)
    out = {"design": design.to_dict(), "joints": settings.joints.to_dict(), **measures.to_dict(),
           "voxel_size": result.grid.h, "voxels": result.voxels,
           "volume": result.volume, "compute_seconds": result.compute_seconds, "grid": result.grid.to_dict(),
           "eta_samples": result.n_eta}
    if mech is not None:
        out["mechanism"], out["engine"] = mech.to_dict(), "paper"
    if ns.bracket:
        out["volume_inner"], out["volume_outer"] = result.volume_inner, result.volume_outer
        out["bracket_seconds"] = result.bracket_seconds
        out["bracket_refine"] = refine
    if ns.diagnostics:
        from paraspace.kinematics.diagnostics import limit_binding

        out["limit_binding"] = limit_binding(result).to_dict()
    if dexterity:
        from paraspace.kinematics.dexterity import dexterity_field

        _add_dexterity(out, dexterity_field(result, *dexterity, **_dexterity_search(ns)).summary())
    if total:
        from paraspace.kinematics.dexterous import total_orientation_workspace

        dx = total_orientation_workspace(design, *total, settings, position=result)
        out["total_orientation"] = {**dx.summary(), "measures": measure_workspace(dx.result).to_dict()}
    if fmt:
        out["export"] = _export_shell(result, ns.export, fmt)
    if ns.json:
        _emit(out)
    else:
        print(f"volume          {significant(out['volume'], 4)} units³  ({out['voxels']:,} voxels of edge "
              f"{out['voxel_size']:g})")
        if ns.bracket:
            print(f"certified       {significant(out['volume_inner'], 4)} <= V <= {significant(out['volume_outer'], 4)}"
                  "  (continuous workspace)")
        if out["voxels"]:
            # the measures that do not change with h lead (kinematics.measures, "Stable measures")
            frag = f" ({100 * out['fragment_volume_fraction']:.2f} % of the volume)" if out["fragments"] else ""
            print(f"pieces          {out['pieces']}  (components of >= {100 * out['piece_fraction']:g} % of the "
                  "volume; stable in h)")
            print(f"stable_genus    {out['stable_genus']}  (tunnels or windows wider than "
                  f"{2 * out['feature_radius']:.3g}; stable in h)")
            print(f"fragments       {out['fragments']}{frag}  (specks of thin sheets; their number grows as h "
                  "shrinks, their volume does not)")
            why = "" if out["boundary_complete"] else f"  ({out['completeness_reason']})"
            print(f"boundary        {'complete' if out['boundary_complete'] else 'incomplete'}{why}")
            print(f"hollowness      {significant(out['hollowness'], 3)}  (underside cavity ratio)")
            print(f"voids           {out['voids']}  (enclosed cavities; void ratio "
                  f"{significant(out['void_ratio'], 3)})")
            print(f"voxel-level     components {out['components']}, genus {out['genus']}, boundary_closed "
                  f"{out['boundary_closed']}  (raw voxel counts: they change with h)")
        b = out.get("bounds")
        if b:
            print("bounds          " + ", ".join(f"{ax} [{significant(lo, 4)}, {significant(hi, 4)}]"
                                                 for ax, lo, hi in zip("xyz", b["min"], b["max"])))
        if ns.diagnostics:
            print(f"chains          {(out.get('chain_binding') or {}).get('summary', '-')}")
            print(f"limits          {out['limit_binding']['summary']}")
        print(f"compute_seconds {out['compute_seconds']:.3f}")
        _print_total_and_dexterity(out)
        if fmt:
            print(f"exported        {ns.export} ({out['export']['faces']} faces)")
    return 0


def _orientation_general(ns: argparse.Namespace, mech: Any) -> int:
    """``paraspace orientation --mechanism`` for a general mechanism: the scans along the lines of its
    symmetry order and TI_1, TI_2 (kinematics/mechanism_orientation.py), the paper path's output shape."""
    from paraspace.kinematics.mechanism_orientation import mechanism_orientation_workspace
    from paraspace.kinematics.mechanism_workspace import warm_up_general
    from paraspace.kinematics.orientation import OrientationSettings
    from paraspace.kinematics.settings import ORIENTATION

    z0 = float(ORIENTATION["z0"].parse(ns.z0))
    settings = OrientationSettings(z0=z0, position_delta=ns.position_delta, **_scan(ns))
    length_step = _length_step(ns)
    warm_up_general()
    with progress_scope("orientation") as progress:
        result = mechanism_orientation_workspace(mech, settings, length_step, progress)
    out = result.to_dict()
    if ns.json:
        _emit(out)
    else:
        print(f"mechanism {mech.name}: symmetry order {result.order} about z; lines z, x and y' = the "
              f"horizontal line at {result.azimuth:g} deg from x (kinematics/mechanism_orientation.py (S2))")
        print(f"TI_1 = {out['TI_1']:.6g}   TI_2 = {out['TI_2']:.6g}   (z0 = {z0:g})")
        if out["saturation_note"]:
            print(f"note: {out['saturation_note']}")
        for name, val in out.get("deltas", {}).items():
            print(f"  {name:<8} {val:.6g}")
    return 0


def cmd_orientation(ns: argparse.Namespace) -> int:
    from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace
    from paraspace.kinematics.workspace import warm_up

    mech, design = _mechanism(ns, {"--at": "at"})
    if design is None:
        return _orientation_general(ns, mech)
    if mech is not None:
        _length_step(ns)  # validated; the paper path samples no second prismatic joint
    if ns.at is not None:
        given = [flag for flag, name in SCAN_FLAGS.items() if getattr(ns, f"scan_{name}") is not None]
        if given:
            raise ParameterError(given[0].lstrip("-"), getattr(ns, f"scan_{SCAN_FLAGS[given[0]]}"),
                                 "not with --at (the tilt-and-torsion report has its own scan: --azimuth-step)")
        return _tilt_torsion(ns, design)
    from paraspace.kinematics.settings import ORIENTATION

    z0 = float(ORIENTATION["z0"].parse(ns.z0))
    settings = OrientationSettings(z0=z0, joints=joints_of(ns), position_delta=ns.position_delta, **_scan(ns))
    warm_up()
    with progress_scope("orientation") as progress:
        result = orientation_workspace(design, settings, progress)
    out = {"design": design.to_dict(), **result.to_dict()}
    if mech is not None:
        out["mechanism"], out["engine"] = mech.to_dict(), "paper"
    if ns.json:
        _emit(out)
    else:
        print(f"TI_1 = {out['TI_1']:.6g}   TI_2 = {out['TI_2']:.6g}   (z0 = {z0:g})")
        if out["saturation_note"]:
            print(f"note: {out['saturation_note']}")
        for name, val in out.get("deltas", {}).items():
            print(f"  {name:<8} {val:.6g}")
    return 0


def _tilt_torsion(ns: argparse.Namespace, design: Design) -> int:
    """``paraspace orientation --at x,y,z``: the tilt-and-torsion report at one position."""
    from paraspace.kinematics.tilt_torsion import TiltTorsionSettings, tilt_torsion_at
    from paraspace.kinematics.workspace import warm_up

    at = _floats("at", ns.at, 3)
    settings = TiltTorsionSettings(azimuth_step=_float_arg("azimuth_step", ns.azimuth_step, "(0, 90] degrees"))
    warm_up()
    joints = joints_of(ns)
    report = tilt_torsion_at(design, at, settings, joints)
    out = {"design": design.to_dict(), "joints": joints.to_dict(), **report.to_dict()}
    if ns.json:
        _emit(out)
    elif not report.reachable:
        print(f"position {at} is not reachable at the zero orientation")
    else:
        az, mt = out["azimuths"], out["max_tilt"]
        k = int(min(range(len(mt)), key=lambda i: mt[i]))
        print(f"tilt (zero torsion): {out['min_max_tilt']:.4g} deg in every direction "
              f"(smallest at azimuth {az[k]:g}), up to {out['max_max_tilt']:.4g} deg")
        sat = " (scan limit)" if any(out["torsion_saturated"]) else ""
        print(f"torsion (zero tilt): {out['torsion_range'][0]:.4g} .. {out['torsion_range'][1]:.4g} deg{sat}")
    return 0


def _task_of(ns: argparse.Namespace) -> Any:
    """The task of ``--box`` / ``--cylinder`` / ``--sphere`` / ``--points`` (exactly one)."""
    from paraspace.kinematics.task import MAX_CSV_BYTES, Region, read_pose_csv

    given = [s for s in ("box", "cylinder", "sphere", "points") if getattr(ns, s, None) is not None]
    if len(given) != 1:
        raise ParameterError("task", ",".join(given) or None,
                             "exactly one of --box CX,CY,CZ,LX,LY,LZ, --cylinder CX,CY,CZ,R,H, --sphere CX,CY,CZ,R "
                             "or --points FILE.csv")
    kind = given[0]
    if kind == "points":
        path = ns.points
        if not os.path.isfile(path):
            raise ParameterError("points", path, "an existing CSV file with the header x,y,z,psi,theta,phi[,t]")
        size = os.path.getsize(path)
        if size > MAX_CSV_BYTES:
            raise ParameterError("points", f"{size:,} bytes", f"at most {MAX_CSV_BYTES:,} bytes (at most "
                                 f"{MAX_CSV_BYTES // 100:,} poses)")
        with open(path, "rb") as fh:
            return read_pose_csv(fh.read())
    return Region.parse(kind, _floats(kind, getattr(ns, kind)))


def _task_orientations(ns: argparse.Namespace) -> Any:
    from paraspace.kinematics.task import OrientationSet

    o = _floats("orientation", ns.orientation, 3) if ns.orientation else [0.0, 0.0, 0.0]
    return OrientationSet(tilt=ns.tilt, torsion=ns.torsion, fixed=(o[0], o[1], o[2]), step=ns.angle_step)


def _task_settings(ns: argparse.Namespace) -> Any:
    from paraspace.kinematics.task import TaskSettings

    return TaskSettings(voxel=ns.voxel, eta_step=ns.eta_step, margin_range=ns.margin_range,
                        carriage_margin=ns.carriage_margin, joints=joints_of(ns))


def _study_task(ns: argparse.Namespace, joints: Any) -> Any:
    """The ``TaskSpec`` of a study's task flags (``sweep``, ``optimize``), or ``None`` when none is given."""
    if not any(getattr(ns, k, None) is not None for k in ("box", "cylinder", "sphere", "points")):
        return None
    from paraspace.kinematics.task import OrientationSet, TaskSettings, TaskSpec

    return TaskSpec(_task_of(ns), OrientationSet(tilt=ns.tilt, torsion=ns.torsion, step=ns.task_angle_step),
                    TaskSettings(voxel=_voxel(ns), margin_range=ns.margin_range, joints=joints))


def _add_study_task_flags(p: argparse.ArgumentParser, title: str) -> None:
    """The task flags of a study (``sweep``, ``optimize``): the region or pose list, its orientation set
    and sampling (the task's cells are the study's voxels)."""
    from paraspace.kinematics.settings import TASK, TOTAL_ORIENTATION

    _add_task_flags(p, title)
    for name in ("tilt", "torsion"):
        spec = TOTAL_ORIENTATION[name]
        p.add_argument(f"--{name}", metavar="DEG", help=f"the task region's {spec.label} (optimize: also the "
                                                        f"orientation set of total_orientation_volume); valid range "
                                                        f"{spec.range_text()}")
    p.add_argument("--task-angle-step", dest="task_angle_step", default=TASK["angle_step"].default, metavar="DEG",
                   help=f"the task's {TASK['angle_step'].label}; valid range {TASK['angle_step'].range_text()}")
    p.add_argument("--margin-range", dest="margin_range", default=TASK["margin_range"].default, metavar="V",
                   help=f"the task's {TASK['margin_range'].label}; valid range {TASK['margin_range'].range_text()}")


def task_csv(out: dict[str, Any]) -> str:
    """A pose list's answer one pose per row (index, t, reachable, leg slack, the 12 actuator values), or a
    region's answer as one row of its scalars."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    if out["kind"] == "poses":
        names = out["actuator_names"]
        w.writerow(["index", "t", "reachable", "leg_slack", *names])
        for r in out["poses"]:
            w.writerow([r["index"], r.get("t", ""), int(r["reachable"]), repr(r["leg_slack"]), *map(repr, r["q"])])
    else:
        keys = ["fraction", "contained", "certified", "margin", "margin_saturated", "sample_points",
                "reachable_points", "orientation_samples", "seconds"]
        w.writerow(keys + ["binding"])
        w.writerow([out[k] for k in keys] + [out["binding"]["message"]])
    return buf.getvalue()


def cmd_task(ns: argparse.Namespace) -> int:
    """``paraspace task``: does the design hold a region or follow a pose list, by what margin."""
    from paraspace.kinematics.task import evaluate_task
    from paraspace.kinematics.workspace import warm_up

    mech, design = _mechanism(ns, {})
    task = _task_of(ns)
    oset = _task_orientations(ns)
    settings = _task_settings(ns)
    if ns.points is not None and (ns.tilt is not None or ns.torsion is not None or ns.orientation):
        raise ParameterError("tilt", ns.tilt if ns.tilt is not None else ns.torsion,
                             "not with --points (each pose carries its orientation)")
    progress, done = progress_line("task")
    try:
        if design is None:  # a general mechanism (kinematics/mechanism_task.py)
            from paraspace.kinematics.mechanism_task import evaluate_mechanism_task
            from paraspace.kinematics.mechanism_workspace import warm_up_general

            warm_up_general()
            res = evaluate_mechanism_task(mech, task, oset, settings, _length_step(ns), progress)
        else:
            warm_up()
            res = evaluate_task(design, task, oset, settings, progress)
    finally:
        done()
    from paraspace.kinematics.serialize import jsonable

    out = jsonable(res.to_dict())
    if ns.csv:
        write_atomic(ns.csv, task_csv(out))
    if ns.json:
        _emit(out)
        return 0
    what = (f"{out['count']} poses" if out["kind"] == "poses" else
            f"{out['region']['shape']} of {out['sample_points']} sample points x {out['orientation_samples']} "
            f"orientations")
    print(f"task            {what}")
    print(f"fraction        {out['fraction']:.4g}  (contained: {'yes' if out['contained'] else 'no'})")
    print(f"certified       {out['certified']}")
    sat = " (at least: no unreachable point within margin_range)" if out.get("margin_saturated") else ""
    print(f"margin          {out['margin']:.4g}{sat}")
    print(f"binding         {out['binding']['message']}")
    if out["kind"] == "poses" and design is None:
        if out["unreachable"]:
            print(f"unreachable     {', '.join(map(str, out['unreachable'][:20]))}"
                  + (" ..." if len(out["unreachable"]) > 20 else ""))
    elif out["kind"] == "poses":
        car = out["carriage"]
        print(f"carriage travel d {car['travel_d']:.4g}, eta {car['travel_eta']:.4g} deg"
              + (f"; max speed d {car['max_speed_d']:.4g}/s, eta {car['max_speed_eta']:.4g} deg/s"
                 if "max_speed_d" in car else ""))
        jumps = sorted({j["index"] for j in out["discontinuities"]})
        print(f"discontinuities {', '.join(map(str, jumps)) if jumps else 'none'}")
        if out["unreachable"]:
            print(f"unreachable     {', '.join(map(str, out['unreachable'][:20]))}"
                  + (" ..." if len(out["unreachable"]) > 20 else ""))
        for a in out["actuators"]:
            print(f"  {a['name']:<7} {a['min']:9.3f} .. {a['max']:9.3f}  of [{a['stroke'][0]:g}, {a['stroke'][1]:g}]"
                  f"  ({100 * a['used_fraction']:.0f} % used)")
    print(f"seconds         {out['seconds']:.2f}")
    return 0


def _add_task_parser(sub: Any) -> None:
    from paraspace.kinematics.settings import TASK, TOTAL_ORIENTATION

    t = sub.add_parser("task", help="does the design hold a region (with an orientation set) or follow a pose list")
    add_design_flags(t)
    _add_task_flags(t, "the task (exactly one)")
    o = t.add_argument_group("orientation set of a region (default: the home orientation)")
    for name in ("tilt", "torsion"):
        spec = TOTAL_ORIENTATION[name]
        o.add_argument(f"--{name}", metavar="DEG", help=f"{spec.label}; valid range {spec.range_text()}")
    o.add_argument("--orientation", metavar="PSI,THETA,PHI", help="one fixed orientation instead (eq. (2), degrees)")
    from paraspace.kinematics.settings import WORKSPACE

    for name in ("voxel", "angle_step", "eta_step", "margin_range", "carriage_margin"):
        spec = WORKSPACE[name] if name in ("voxel", "eta_step") else TASK[name]
        t.add_argument(f"--{name.replace('_', '-')}", dest=name, default=spec.default, metavar="V",
                       help=f"{spec.label}; valid range {spec.range_text()} (default {spec.default:g})")
    t.add_argument("--json", action="store_true", help="one JSON object: fraction, contained, certified, margin, "
                                                      "worst, binding (and poses, discontinuities for a pose list)")
    t.add_argument("--csv", metavar="OUT", help="write the answer as CSV (a pose list: one row per pose)")
    add_joint_flags(t)
    add_mechanism_flags(t)
    t.set_defaults(func=cmd_task)


def cmd_paper(ns: argparse.Namespace) -> int:
    """``paraspace paper``: every checkable claim of the paper with its verdict under each assumption;
    ``--fit``: the bounded fit of the unstated assumptions toward V, TI_1 and TI_2."""
    from paraspace.kinematics.paper import ASSUMPTION_KEYS, fit_assumptions, paper_comparison
    from paraspace.kinematics.settings import ORIENTATION
    from paraspace.kinematics.workspace import warm_up

    voxel = _voxel(ns)
    scan = _scan(ns)
    keys = None
    if ns.assumptions is not None:
        keys = tuple(k.strip() for k in ns.assumptions.split(",") if k.strip())
        bad = [k for k in keys if k not in ASSUMPTION_KEYS]
        if bad or not keys:
            raise ParameterError("assumptions", ns.assumptions,
                                 "comma-separated names of " + ", ".join(ASSUMPTION_KEYS))
    if ns.fit and "angle_range" in scan:
        raise ParameterError("angle-range", scan["angle_range"], "not with --fit (the fit scans its own ranges)")
    warm_up()
    with progress_scope("paper") as progress:
        if ns.fit:
            steps = {"angle_step": scan.get("angle_step", 2.0), "position_step": scan.get("position_step", 4.0)}
            out = fit_assumptions(voxel, progress=progress, **steps)
        else:
            steps = {"angle_step": scan.get("angle_step", 1.0), "position_step": scan.get("position_step", 2.0)}
            out = paper_comparison(voxel, progress, assumptions=keys, **steps,
                                   angle_range=scan.get("angle_range", ORIENTATION["angle_range"].default))
    if ns.json:
        _emit(out)
        return 0
    if ns.fit:
        print(out["summary"])
        print(f"TI_2 / TI_1 over all {out['models']} models: {out['ti_ratio_range'][0]:.2f} .. "
              f"{out['ti_ratio_range'][1]:.2f} (paper 1.74)")
        print(f"{'arc range':<10} {'cones':<11} {'scan':>5} {'z floor':>7} {'V':>9} {'TI_1':>8} {'TI_2':>8}  residuals")
        for r in out["top"]:
            res = ", ".join(f"{k} {100 * v:+.0f}%" for k, v in r["residuals"].items())
            print(f"{r['eta_range']:<10} {r['cones'] or 'none':<11} {r['angle_range']:>5g} {r['z_floor']:>7g} "
                  f"{r['volume']:>9.3g} {r['TI_1']:>8.4g} {r['TI_2']:>8.4g}  {res}")
        return 0
    cols = [a["key"] for a in out["assumptions"]]
    print(f"The paper's claims beside ours (h = {out['voxel']:g}; scan ±{out['scan']['angle_range']:g}°, steps "
          f"{out['scan']['angle_step']:g}° / {out['scan']['position_step']:g})")
    for a in out["assumptions"]:
        print(f"  column {a['key']:<15} {a['label']}")
    short = {"holds": "holds", "fails": "FAILS"}
    print(f"{'claim':<19} " + " ".join(f"{c[:9]:<9}" for c in cols) + " value (paper's model) / quote")
    for r in out["claims"]:
        marks = " ".join(f"{short.get(r['by_assumption'][c]['verdict'], 'n/t'):<9}" for c in cols)
        print(f"{r['id']:<19} {marks} {r['value']}")
        print(f"{'':<19} {' ' * (10 * len(cols))}\"{r['quote']}\"")
    print("verdict counts: " + "; ".join(f"{c}: {n['holds']} hold, {n['fails']} fail, {n['not testable']} n/t"
                                         for c, n in out["counts"].items()))
    for key, rv in out["reported_vs_ours"].items():
        verdict = (f"holds under {rv['closest']}" if abs(rv["closest_gap"]) <= out["words"]["reported"]
                   else "fails under every column")
        print(f"{key}: paper {rv['paper']:.6g}: {verdict}; smallest gap {100 * rv['closest_gap']:+.0f} % "
              f"(column {rv['closest']}, the paper's design)")
    print("tuned on the paper's nine designs: " + " | ".join(out["tuned"]))
    print(out["summary"])
    return 0


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
    for flag, dest in {**_DESIGN_FLAGS, **_JOINT_FLAGS, **_SWEEP_PAPER_ONLY}.items():
        if _given(ns, flag, dest):
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
    length_step = _length_step(ns)
    values = _floats("values", ns.values)
    values2 = None if ns.values2 is None else _floats("values2", ns.values2)
    settings = WorkspaceSettings(voxel=_voxel(ns))
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
        _emit(rows)
    else:
        sys.stdout.write(rows_to_csv(rows))
    if failed:
        sys.stderr.write(f"paraspace: error: {len(failed)} of {len(rows)} points failed "
                         f"(first: {failed[0].get('error', '?')})\n")
        return 1
    return 0


def _backend_workers(ns: argparse.Namespace, auto: bool = True) -> int | None:
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
    settings = WorkspaceSettings(voxel=_voxel(ns), joints=joints_of(ns))
    for field in ("param", "param2"):
        name = getattr(ns, field)
        if name is not None and name not in PARAMS:
            raise ParameterError(field, name, "one of " + ", ".join(PARAMS))
    values = _floats("values", ns.values)
    if (ns.param2 is None) != (ns.values2 is None):
        raise ParameterError("param2", ns.param2, "given together with --values2")
    orientation = _sweep_orientation(ns)
    task = _study_task(ns, settings.joints)
    if ns.plot:
        from paraspace.app.figures import export_format

        try:
            export_format(ns.plot)
        except ValueError as err:
            raise ParameterError("plot", ns.plot, str(err)) from None
    workers = _backend_workers(ns, auto=task is None)
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
            values2 = _floats("values2", ns.values2)
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
        _emit(rows)
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
            given = [flag for flag, name in SCAN_FLAGS.items() if getattr(ns, f"scan_{name}") is not None]
            if given:
                raise ParameterError(given[0].lstrip("-"), getattr(ns, f"scan_{SCAN_FLAGS[given[0]]}"),
                                     "only with --measure TI_1/TI_2 or --z0 (the orientation maps)")
            return None
        return OrientationSettings(joints=joints_of(ns), **_scan(ns))
    return OrientationSettings(z0=float(ORIENTATION["z0"].parse(ns.z0)), joints=joints_of(ns), **_scan(ns))


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


def cmd_ik(ns: argparse.Namespace) -> int:
    from paraspace.kinematics.pose import Pose
    from paraspace.kinematics.redundancy import inverse_kinematics, resolve_redundancy

    mech, design = _mechanism(ns, {"--carriage": "carriage"})
    if design is None:
        return _ik_general(ns, mech)
    joints = joints_of(ns)
    pose = Pose.from_array(_floats("pose", ns.pose, 6))
    if ns.carriage:
        c = _floats("carriage", ns.carriage, 6)
        res = inverse_kinematics(design, pose, c[:3], c[3:], joints)
    else:
        res = resolve_redundancy(design, pose, joints)
    out = {"design": design.to_dict(), "pose": pose.to_dict(), **res.to_dict()}
    if ns.json:
        _emit(out)
    else:
        print(res.message)
        for ch in res.chains:
            print(f"chain {ch.chain + 1}: d = {fixed(ch.d, 3, 8)}  eta = {fixed(ch.eta, 3, 8)} deg  lengths = "
                  f"{fixed(ch.lengths[0], 3, 8)} {fixed(ch.lengths[1], 3, 8)}  ({', '.join(ch.leg_status)})")
        print(f"condition number of J: {significant(out['condition_number'], 4)}")
        if res.cone_angles is not None:
            print(f"largest joint angles: U {res.cone_angles[:, :, 0].max():.2f} deg, "
                  f"S {res.cone_angles[:, :, 1].max():.2f} deg")
        if res.min_leg_distance is not None:
            print(f"closest two legs: {res.min_leg_distance:.2f} apart (axes)")
    return 0 if res.feasible or not ns.strict else 1


def _ik_general(ns: argparse.Namespace, mech: Any) -> int:
    """``paraspace ik --mechanism`` for a general mechanism: per chain the carriage values of largest
    smallest length margin (kinematics/mechanism_workspace.py, ``mechanism_ik``)."""
    from paraspace.kinematics.mechanism_jacobian import mechanism_jacobians
    from paraspace.kinematics.mechanism_workspace import mechanism_ik
    from paraspace.kinematics.pose import Pose

    pose = Pose.from_array(_floats("pose", ns.pose, 6))
    angles = (pose.psi, pose.theta, pose.phi)
    chains = mechanism_ik(mech, pose.position, angles, length_step=_length_step(ns))
    feasible = all(c.feasible for c in chains)
    cond = mechanism_jacobians(mech, pose.position, angles, [c.q for c in chains]).condition_number
    out = {"mechanism": mech.to_dict(), "pose": pose.to_dict(), "feasible": feasible,
           "chains": [c.to_dict() for c in chains], "condition_number": cond}
    if ns.json:
        _emit(out)
    else:
        print("reachable: every chain puts its legs in range" if feasible else
              "unreachable: chain(s) " + ", ".join(str(c.chain + 1) for c in chains if not c.feasible)
              + " cannot put every leg in range")
        for c in chains:
            kinds = [j.type[0] for j in mech.chains[c.chain].carriage]
            q = "  ".join(f"{k}={fixed(v, 3, 8)}" for k, v in zip(kinds, c.q)) or "(fixed base)"
            print(f"chain {c.chain + 1}: {q}  lengths = {' '.join(fixed(x, 3, 8) for x in c.lengths)}  "
                  f"margin {fixed(c.margin, 3, 8)}")
        print(f"condition number of J: {significant(cond, 4)}")
    return 0 if feasible or not ns.strict else 1


def cmd_serve(ns: argparse.Namespace) -> int:
    from paraspace.app.serve import serve

    for field in ("port", "api_port"):
        v = getattr(ns, field)
        if not 0 <= v <= 65535:
            raise ParameterError(field.replace("_", "-"), v, "[0, 65535]")
    public_url = None
    if ns.public_url:
        from paraspace.app.serve import check_public_url

        public_url = check_public_url(ns.public_url)
    from paraspace.app.hostcheck import parse_allowed_hosts

    serve(host=ns.host, port=ns.port, api_port=ns.api_port, block=True, public_url=public_url,
          trusted_proxy=ns.trusted_proxy, allowed_hosts=parse_allowed_hosts(ns.allowed_host))
    return 0


# ----- optimize (issue 11) -------------------------------------------------------------------


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
    spec = _study_task(ns, joints)
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
        workspace=WorkspaceSettings(voxel=_voxel(ns), joints=joints),
        orientation=OrientationSettings(joints=joints, **_scan(ns)),
        population=int(OPTIMIZE["population"].parse(ns.population)),
        generations=int(OPTIMIZE["generations"].parse(ns.generations)),
        seed=int(OPTIMIZE["seed"].parse(ns.seed)), step=OPTIMIZE["step"].parse(ns.step), algorithm=ns.algorithm)


def _optimize_preset(ns: argparse.Namespace) -> tuple[str | None, dict[str, Any], float, list[str]]:
    """``optimize --mechanism PRESET [--param NAME=VALUE]... [--length-step L]``: ``(preset, its fixed
    values, length_step, the names --params and --bounds may use)``; ``(None, {}, 1, PARAMS)`` without
    ``--mechanism``. A file is refused (the optimiser varies a preset's parameters); so are the design
    flags, and the joint flags with a general preset (by :func:`_mechanism`)."""
    from paraspace.kinematics.presets import PRESETS

    from .mechanism_cli import _param_values

    if getattr(ns, "mechanism", None) is not None and ns.mechanism not in PRESETS:
        raise ParameterError("--mechanism", ns.mechanism, f"a preset ({', '.join(PRESETS)}): the optimiser varies "
                                                          "a preset's parameters, not a description file's")
    _mechanism(ns, {})  # refuses the flags a preset replaces (and validates --param)
    if ns.mechanism is None:
        return None, {}, 1.0, list(PARAMS)
    known = [q.name for q in PRESETS[ns.mechanism].params if q.numeric]
    return ns.mechanism, _param_values(ns.param), _length_step(ns), known


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
        result = optimize(settings, scheduler=ns.scheduler, workers=_backend_workers(ns), progress=progress).to_dict()
    from paraspace.app.optimize_plots import front_csv, front_png

    if ns.csv:
        write_atomic(ns.csv, front_csv(result))
    if ns.plot:
        front_png(result, ns.plot)
    if ns.json:
        _emit(result)
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


def _add_optimize_parser(sub: Any) -> None:
    from paraspace.kinematics.optimize import ALGORITHMS, DEFAULT_PARAMS, MEASURES

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
    _add_scan_flags(z)
    add_joint_flags(z)
    _add_study_task_flags(z, "the task of task_fraction, task_margin and --constraint contains_task")
    add_mechanism_flags(z)
    z.set_defaults(func=cmd_optimize)


def _add_task_flags(p: argparse.ArgumentParser, title: str) -> None:
    """``--box | --cylinder | --sphere | --points`` (``task`` and ``optimize``)."""
    from paraspace.kinematics.settings import TASK

    g = p.add_argument_group(title)
    size = TASK["size"].range_text()
    g.add_argument("--box", metavar="CX,CY,CZ,LX,LY,LZ", help=f"a box: centre and edges (edges {size})")
    g.add_argument("--cylinder", metavar="CX,CY,CZ,R,H", help=f"a cylinder with a vertical axis (R, H {size})")
    g.add_argument("--sphere", metavar="CX,CY,CZ,R", help=f"a sphere (R {size})")
    g.add_argument("--points", metavar="FILE.csv",
                   help="a pose list: header x,y,z,psi,theta,phi[,t], degrees and seconds; at most "
                        f"{int(TASK['max_poses'].hi):,} poses")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="paraspace",
                description="Workspace explorer of the 3-(arc-P, P, 2-(UPS)) redundant parallel mechanism")
    p.add_argument("--version", action="version", version=f"paraspace {paraspace.__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    w = sub.add_parser("workspace", help="constant-orientation position workspace and its measures")
    add_design_flags(w)
    w.add_argument("--voxel", default=2.0, help="voxel edge h (default 2)")
    w.add_argument("--json", action="store_true", help="one JSON object on stdout")
    w.add_argument("--export", metavar="FILE", help="write the marching-cubes shell (.stl .ply .obj .glb)")
    w.add_argument("--method", default="blocks", metavar="blocks|dense",
                   help="engine: coarse-to-fine blocks (default) or every voxel (dense, the oracle); same voxels")
    w.add_argument("--bracket-refine", dest="bracket_refine", default=2, metavar="N",
                   help="halvings of the bracket's boundary cubes, 0-3 (default 2; each about halves the gap "
                        "and costs about 4x the previous one)")
    w.add_argument("--bracket", action="store_true",
                   help="also certify volume_inner <= V <= volume_outer for the continuous workspace")
    w.add_argument("--diagnostics", action="store_true",
                   help="which chain and which leg limit bind (evaluates every chain everywhere; slower)")
    w.add_argument("--tilt", metavar="DEG",
                   help="total-orientation workspace: every tilt up to DEG (all azimuths), [0, 90]")
    w.add_argument("--torsion", metavar="DEG",
                   help="total-orientation workspace: every torsion in [-DEG, DEG], [0, 180]")
    w.add_argument("--angle-step", dest="angle_step", default=5.0, metavar="DEG",
                   help="largest spacing of the total-orientation samples (default 5 degrees)")
    w.add_argument("--dexterity", action="store_true",
                   help="1/kappa of eq. (26) over the workspace: gci and well_conditioned_volume")
    w.add_argument("--kappa-min", dest="kappa_min", metavar="X",
                   help="threshold on 1/kappa of the well-conditioned workspace, (0, 1] (default 0.005)")
    w.add_argument("--dexterity-mode", dest="dexterity_mode", default="resolved", metavar="resolved|best",
                   help="carriage pose of 1/kappa: the redundancy resolution's (default) or the best sampled")
    from paraspace.kinematics.settings import DEXTERITY, DEXTERITY_SEARCHES

    searches = list(DEXTERITY_SEARCHES)
    w.add_argument("--dexterity-search", dest="dexterity_search", metavar="|".join(searches),
                   help="how the resolved carriage poses are found: "
                        + "; ".join(f"{k}: {v}" for k, v in DEXTERITY_SEARCHES.items()) + f" (default {searches[0]})")
    mt = DEXTERITY["margin_tolerance"]
    w.add_argument("--margin-tolerance", dest="margin_tolerance", metavar="V",
                   help=f"the neighbour search's {mt.label}, checked on a sample; valid range {mt.range_text()} "
                        f"(default {mt.default:g})")
    add_joint_flags(w)
    add_mechanism_flags(w)
    w.set_defaults(func=cmd_workspace)

    o = sub.add_parser("orientation", help="orientation workspace along the symmetry lines, TI_1 and TI_2")
    add_design_flags(o)
    o.add_argument("--z0", default=130.0, help="height of the x and y' lines (default 130)")
    o.add_argument("--at", metavar="x,y,z",
                   help="tilt-and-torsion report at this position instead: maximal tilt per azimuth, torsion range")
    o.add_argument("--azimuth-step", dest="azimuth_step", default=5.0, metavar="DEG",
                   help="azimuth spacing of the tilt-and-torsion report (default 5)")
    o.add_argument("--json", action="store_true")
    o.add_argument("--position-delta", dest="position_delta", default="per_region",
                   choices=("per_region", "line", "phi"),
                   help="eq. (28)'s position Δ: each region's own (default), the union of a line's regions, "
                        "or the literal reading: one Δ per line taken from the φ region")
    _add_scan_flags(o)
    add_joint_flags(o)
    add_mechanism_flags(o)
    o.set_defaults(func=cmd_orientation)

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
    _add_scan_flags(s)
    add_joint_flags(s)
    _add_study_task_flags(s, "a task: each point also gets task_fraction, task_margin, contains_task")
    s.set_defaults(func=cmd_sweep)

    _add_optimize_parser(sub)
    _add_task_parser(sub)

    pp = sub.add_parser("paper", help="every checkable claim of the paper with its verdict under each assumption")
    pp.add_argument("--voxel", default=4.0, help="voxel edge h of every workspace (default 4)")
    pp.add_argument("--json", action="store_true")
    pp.add_argument("--assumptions", metavar="K[,K]",
                    help="only these columns (paper, from_zero, cones30_home, cones45_normal, scan180, scan_coarse, "
                         "legs10; default all)")
    pp.add_argument("--fit", action="store_true",
                    help="fit the unstated assumptions (arc range, cones, scan range, z floor) to V, TI_1, TI_2")
    _add_scan_flags(pp)
    pp.set_defaults(func=cmd_paper)

    k = sub.add_parser("ik", help="inverse kinematics with redundancy resolution")
    add_design_flags(k)
    k.add_argument("--pose", required=True, help="x,y,z,psi,theta,phi (degrees)")
    k.add_argument("--carriage", help="hand-set d1,d2,d3,eta1,eta2,eta3 instead of the resolution")
    k.add_argument("--json", action="store_true")
    k.add_argument("--strict", action="store_true", help="exit 1 when the pose is unreachable")
    add_joint_flags(k)
    add_mechanism_flags(k)
    k.set_defaults(func=cmd_ik)

    v = sub.add_parser("serve", help="run the browser explorer and the REST API")
    v.add_argument("--host", default="127.0.0.1",
                   help="interface to bind (default 127.0.0.1: this machine only; 0.0.0.0: every interface, "
                        "e.g. in a container)")
    v.add_argument("--allowed-host", dest="allowed_host", metavar="NAME[,NAME]",
                   help="host names a request may carry in its Host header besides localhost, 127.0.0.1, ::1, "
                        "the bound address and --public-url's host ('*': any; protects against DNS rebinding)")
    v.add_argument("--port", type=int, default=8080, help="explorer port (default 8080)")
    v.add_argument("--api-port", dest="api_port", type=int, default=8081, help="REST API port (default 8081)")
    v.add_argument("--public-url", dest="public_url", metavar="URL",
                   help="the explorer's URL as users reach it (behind a proxy); links are built from it, "
                        "never from a request's Host header")
    v.add_argument("--trusted-proxy", dest="trusted_proxy", metavar="IP[,IP]",
                   help="believe X-Forwarded-For only from these proxy addresses (default: never)")
    v.set_defaults(func=cmd_serve)

    from .mechanism_cli import add_mechanism_parser
    from .report_cli import add_report_parser
    add_mechanism_parser(sub)
    add_report_parser(sub)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    ns = parser.parse_args(argv)
    ns.argv = list(sys.argv[1:] if argv is None else argv)
    try:
        return int(ns.func(ns))
    except ParameterError as err:
        sys.stderr.write(f"paraspace: error: {err}\n")
        return 2
    except BrokenPipeError:  # e.g. `paraspace orientation | head` (before OSError, its base class)
        sys.stderr.close()
        return 0
    except OSError as err:  # a file we were asked to write or read (--export, --csv, --plot, ...)
        where = f" {err.filename!r}" if getattr(err, "filename", None) else ""
        sys.stderr.write(f"paraspace: error: cannot use the file{where}: {err.strerror or err}\n")
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
