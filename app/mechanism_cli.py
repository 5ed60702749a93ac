"""``paraspace mechanism``: show a validated mechanism description, or write a preset's file.

::

    paraspace mechanism show paper                          # the paper's mechanism as TOML
    paraspace mechanism show gough-stewart --param base_half_angle=8 --json
    paraspace mechanism show my-hexapod.toml                # validate a file; errors name the field
    paraspace mechanism export 6-pups --param lift=40 -o 6-pups.toml

``--param NAME=VALUE`` (repeatable) sets a preset's parameter; ``paraspace mechanism presets``
lists the presets with their parameters, defaults and ranges.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
from typing import Any

from paraspace.kinematics.design import ParameterError
from paraspace.kinematics.mechanism import MAX_TEXT_BYTES, Mechanism, dumps_mechanism, loads_mechanism
from paraspace.kinematics.presets import PRESETS, preset

from .fileout import write_atomic

__all__ = ["add_mechanism_flags", "add_mechanism_parser", "resolve_mechanism"]


def _param_values(pairs: list[str] | None) -> dict[str, Any]:
    values: dict[str, Any] = {}
    for pair in pairs or []:
        name, sep, text = pair.partition("=")
        if not sep or not name:
            raise ParameterError("--param", pair, "NAME=VALUE, e.g. --param lift=40")
        try:
            values[name.strip()] = float(text)
        except ValueError:
            values[name.strip()] = text.strip()  # e.g. eta_range=from-zero
    return values


def resolve_mechanism(source: str, params: list[str] | None = None) -> Mechanism:
    """A preset name (with ``NAME=VALUE`` parameters) or the path of a TOML/JSON description."""
    if source in PRESETS:
        return preset(source, _param_values(params))
    if params:
        raise ParameterError("--param", params[0], f"only with a preset ({', '.join(PRESETS)}), not a file")
    path = pathlib.Path(source)
    if not path.is_file():
        raise ParameterError("mechanism", source, f"one of the presets {', '.join(PRESETS)} or an existing file")
    if path.stat().st_size > MAX_TEXT_BYTES:
        raise ParameterError("mechanism", f"{path.stat().st_size:,} bytes",
                             f"a description of at most {MAX_TEXT_BYTES:,} bytes")
    return loads_mechanism(path.read_bytes())


def add_mechanism_flags(p: argparse.ArgumentParser) -> None:
    """``--mechanism FILE|PRESET``, ``--param NAME=VALUE`` (repeatable) and ``--length-step L`` on a command."""
    g = p.add_argument_group("mechanism (instead of the design flags; see 'paraspace mechanism presets')")
    g.add_argument("--mechanism", metavar="FILE|PRESET",
                   help=f"a preset ({', '.join(PRESETS)}) or a TOML/JSON description file; 'paper' (and a file "
                        "equal to it) runs the paper's engine with every option, any other mechanism the general "
                        "engine (position workspace, measures, shell, IK)")
    g.add_argument("--param", action="append", metavar="NAME=VALUE", help="a preset's parameter (repeatable)")
    g.add_argument("--length-step", dest="length_step", metavar="L",
                   help="spacing of a sampled (second) prismatic joint's values, [0.01, 100] (default 1)")


def cmd_mechanism(ns: argparse.Namespace) -> int:
    if ns.action == "presets":
        for p in PRESETS.values():
            print(f"{p.name}: {p.description}")
            for q in p.params:
                unit = " " + q.unit if q.unit else ""
                rng = "" if not q.numeric else (f" in [{q.lo:g}, {q.hi:g}]{unit} (studies: {q.study_range[0]:g} "
                                                f"to {q.study_range[1]:g})")
                print(f"    {q.name} = {q.default}{rng}: {q.description}")
        return 0
    if ns.source is None:
        raise ParameterError("mechanism", None, f"a preset ({', '.join(PRESETS)}) or a description file")
    if ns.action == "export" and ns.source not in PRESETS:
        raise ParameterError("mechanism", ns.source, f"one of the presets {', '.join(PRESETS)}")
    mech = resolve_mechanism(ns.source, ns.param)
    text = json.dumps(mech.to_dict(), indent=2) + "\n" if ns.json else dumps_mechanism(mech)
    if ns.action == "export" and ns.output:
        write_atomic(ns.output, text)
        sys.stderr.write(f"wrote {ns.output}\n")
    else:
        sys.stdout.write(text)
    return 0


def add_mechanism_parser(sub: Any) -> None:
    """Register ``paraspace mechanism`` on the CLI's sub-command parsers."""
    m = sub.add_parser("mechanism", help="show a mechanism description (preset or file), or write a preset's file")
    m.add_argument("action", choices=("show", "export", "presets"),
                   help="show: validate and print; export: write a preset's file; presets: list them")
    m.add_argument("source", nargs="?", help=f"a preset ({', '.join(PRESETS)}) or a TOML/JSON file")
    m.add_argument("--param", action="append", metavar="NAME=VALUE", help="a preset's parameter (repeatable)")
    m.add_argument("--json", action="store_true", help="JSON instead of TOML")
    m.add_argument("-o", "--output", metavar="FILE", help="with export: the file to write (default: stdout)")
    m.set_defaults(func=cmd_mechanism)
