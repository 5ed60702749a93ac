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

This module holds the parser, ``workspace``, ``orientation``, ``paper``, ``ik`` and ``serve``; the
other commands have a module each (``sweep_cli``, ``optimize_cli``, ``task_cli``, ``report_cli``,
``mechanism_cli``), and the flags they share are read in ``cli_flags``.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

import paraspace
from paraspace.kinematics.design import Design, ParameterError

from .cli_flags import (
    SCAN_FLAGS,
    add_design_flags,
    add_joint_flags,
    add_scan_flags,
    bracket_refine_of,
    emit_json,
    float_of,
    floats_of,
    joints_of,
    length_step_of,
    mechanism_of,
    scan_of,
    voxel_of,
)
from .fileout import write_atomic
from .mechanism_cli import add_mechanism_flags
from .numfmt import fixed, significant
from .optimize_cli import add_optimize_parser
from .progressline import progress_scope
from .sweep_cli import add_sweep_parser
from .task_cli import add_task_parser


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, status 2
        self.exit(2, f"paraspace: error: {message}\n")


def _export_shell(result: Any, path: str, fmt: str) -> dict[str, Any]:
    """Write the marching-cubes shell of ``result`` to ``path`` whole (``--export``); its JSON entry."""
    from paraspace.kinematics.shell import export_shell, workspace_shell

    mesh = workspace_shell(result)
    write_atomic(path, export_shell(mesh, fmt))
    return {"file": path, "faces": int(len(mesh.faces)), "mesh_volume": float(mesh.volume)}


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


def _print_measures(out: dict, bracket: str | None) -> None:
    """The volume, its certified bracket (``bracket``: what it certifies; None: not asked), the
    measures and the bounds of a workspace's ``out`` (the JSON object ``--json`` prints), the same
    lines for the paper's mechanism and a general one."""
    print(f"volume          {significant(out['volume'], 4)} units³  ({out['voxels']:,} voxels of edge "
          f"{out['voxel_size']:g})")
    if bracket is not None:
        print(f"certified       {significant(out['volume_inner'], 4)} <= V <= {significant(out['volume_outer'], 4)}"
              f"  ({bracket})")
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


def _workspace_general(ns: argparse.Namespace, mech: Any) -> int:
    """``paraspace workspace --mechanism`` for a general mechanism: the position workspace, its measures
    and the shell (kinematics/mechanism_workspace.py)."""
    from paraspace.kinematics.measures import measure_workspace
    from paraspace.kinematics.mechanism_workspace import compute_mechanism_workspace, warm_up_general
    from paraspace.kinematics.workspace import WorkspaceSettings

    refine = bracket_refine_of(ns)
    settings = WorkspaceSettings(voxel=voxel_of(ns), method=ns.method, bracket=ns.bracket, bracket_refine=refine)
    length_step = length_step_of(ns)
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
        emit_json(out)
    else:
        print(f"mechanism       {mech.name}  (general engine; carriage samples per chain "
              f"{', '.join(str(n) for n in result.samples)})")
        _print_measures(out, "continuous workspace, general_bracket" if ns.bracket else None)
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
    from paraspace.kinematics.cuda_dense import check_backend
    from paraspace.kinematics.measures import measure_workspace
    from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace, warm_up

    mech, design = mechanism_of(ns, _WORKSPACE_PAPER_ONLY)
    if design is None:
        if ns.backend != "cpu":
            raise ParameterError("backend", ns.backend, f"cpu for {mech.name!r} (the cuda backend runs the paper's "
                                                        "mechanism)")
        return _workspace_general(ns, mech)
    if mech is not None:
        length_step_of(ns)  # validated; the paper's engine solves d exactly and samples no other prismatic joint
    refine = bracket_refine_of(ns)
    settings = WorkspaceSettings(voxel=voxel_of(ns), diagnostics=ns.diagnostics, method=ns.method, bracket=ns.bracket,
                                 bracket_refine=refine,
                                 joints=joints_of(ns))
    total, dexterity = _total_and_dexterity(ns)
    fmt = _export_format(ns)
    check_backend(ns.backend, settings.joints.has_cones, settings.joints.min_distance > 0.0)
    warm_up()
    with progress_scope("workspace") as progress:
        result = compute_workspace(design, settings, progress, backend=ns.backend)
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
        emit_json(out)
    else:
        _print_measures(out, "continuous workspace" if ns.bracket else None)
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
    settings = OrientationSettings(z0=z0, position_delta=ns.position_delta, **scan_of(ns))
    length_step = length_step_of(ns)
    warm_up_general()
    with progress_scope("orientation") as progress:
        result = mechanism_orientation_workspace(mech, settings, length_step, progress)
    out = result.to_dict()
    if ns.json:
        emit_json(out)
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

    mech, design = mechanism_of(ns, {"--at": "at"})
    if design is None:
        return _orientation_general(ns, mech)
    if mech is not None:
        length_step_of(ns)  # validated; the paper path samples no second prismatic joint
    if ns.at is not None:
        given = [flag for flag, name in SCAN_FLAGS.items() if getattr(ns, f"scan_{name}") is not None]
        if given:
            raise ParameterError(given[0].lstrip("-"), getattr(ns, f"scan_{SCAN_FLAGS[given[0]]}"),
                                 "not with --at (the tilt-and-torsion report has its own scan: --azimuth-step)")
        return _tilt_torsion(ns, design)
    from paraspace.kinematics.settings import ORIENTATION

    z0 = float(ORIENTATION["z0"].parse(ns.z0))
    settings = OrientationSettings(z0=z0, joints=joints_of(ns), position_delta=ns.position_delta, **scan_of(ns))
    warm_up()
    with progress_scope("orientation") as progress:
        result = orientation_workspace(design, settings, progress)
    out = {"design": design.to_dict(), **result.to_dict()}
    if mech is not None:
        out["mechanism"], out["engine"] = mech.to_dict(), "paper"
    if ns.json:
        emit_json(out)
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

    at = floats_of("at", ns.at, 3)
    settings = TiltTorsionSettings(azimuth_step=float_of("azimuth_step", ns.azimuth_step, "(0, 90] degrees"))
    warm_up()
    joints = joints_of(ns)
    report = tilt_torsion_at(design, at, settings, joints)
    out = {"design": design.to_dict(), "joints": joints.to_dict(), **report.to_dict()}
    if ns.json:
        emit_json(out)
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


def cmd_paper(ns: argparse.Namespace) -> int:
    """``paraspace paper``: every checkable claim of the paper with its verdict under each assumption;
    ``--fit``: the bounded fit of the unstated assumptions toward V, TI_1 and TI_2."""
    from paraspace.kinematics.paper import ASSUMPTION_KEYS, fit_assumptions, paper_comparison
    from paraspace.kinematics.settings import ORIENTATION
    from paraspace.kinematics.workspace import warm_up

    voxel = voxel_of(ns)
    scan = scan_of(ns)
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
        emit_json(out)
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


def cmd_ik(ns: argparse.Namespace) -> int:
    from paraspace.kinematics.pose import Pose
    from paraspace.kinematics.redundancy import inverse_kinematics, resolve_redundancy

    mech, design = mechanism_of(ns, {"--carriage": "carriage"})
    if design is None:
        return _ik_general(ns, mech)
    joints = joints_of(ns)
    pose = Pose.from_array(floats_of("pose", ns.pose, 6))
    if ns.carriage:
        c = floats_of("carriage", ns.carriage, 6)
        res = inverse_kinematics(design, pose, c[:3], c[3:], joints)
    else:
        res = resolve_redundancy(design, pose, joints)
    out = {"design": design.to_dict(), "pose": pose.to_dict(), **res.to_dict()}
    if ns.json:
        emit_json(out)
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

    pose = Pose.from_array(floats_of("pose", ns.pose, 6))
    angles = (pose.psi, pose.theta, pose.phi)
    chains = mechanism_ik(mech, pose.position, angles, length_step=length_step_of(ns))
    feasible = all(c.feasible for c in chains)
    cond = mechanism_jacobians(mech, pose.position, angles, [c.q for c in chains]).condition_number
    out = {"mechanism": mech.to_dict(), "pose": pose.to_dict(), "feasible": feasible,
           "chains": [c.to_dict() for c in chains], "condition_number": cond}
    if ns.json:
        emit_json(out)
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
    from paraspace.kinematics.cuda_dense import BACKENDS

    w.add_argument("--backend", default=BACKENDS[0], metavar="|".join(BACKENDS),
                   help="where the voxels are decided: the CPU engines (default) or the dense test on an NVIDIA GPU "
                        "(needs CuPy: pip install 'paraspace[cuda]'; strokes only); same voxels")
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
    add_scan_flags(o)
    add_joint_flags(o)
    add_mechanism_flags(o)
    o.set_defaults(func=cmd_orientation)

    add_sweep_parser(sub)
    add_optimize_parser(sub)
    add_task_parser(sub)

    pp = sub.add_parser("paper", help="every checkable claim of the paper with its verdict under each assumption")
    pp.add_argument("--voxel", default=4.0, help="voxel edge h of every workspace (default 4)")
    pp.add_argument("--json", action="store_true")
    pp.add_argument("--assumptions", metavar="K[,K]",
                    help="only these columns (paper, from_zero, cones30_home, cones45_normal, scan180, scan_coarse, "
                         "legs10; default all)")
    pp.add_argument("--fit", action="store_true",
                    help="fit the unstated assumptions (arc range, cones, scan range, z floor) to V, TI_1, TI_2")
    add_scan_flags(pp)
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
