"""An independent interval oracle for tests/test_bracket.py (run as a subprocess: importing codac
changes the floating-point rounding mode of the process that imports it).

Reads ``{"design": {...}, "cubes": [[[x0, x1], [y0, y1], [z0, z1]], ...]}`` on stdin and prints one
verdict per cube: ``"in"`` when for every chain an arc sample and a rail value keep both legs in
``[l_min, l_max]`` over the whole cube (codac's interval evaluation of the leg lengths), ``"out"``
when for some chain a bisection of the carriage box (arc angle x rail) proves that no carriage pose
serves any point of the cube, ``"?"`` otherwise. Only the geometry of the paper (eqs. (3)-(5), (11))
is re-derived here; nothing of the engine is used.
"""

from __future__ import annotations

import json
import math
import sys

import codac
import numpy as np


def legs(d: dict, chain: int) -> list:
    gamma = 2.0 * math.pi * chain / 3.0
    v = codac.VectorVar(5)  # x, y, z, varpi, rho
    out = []
    for j, sign in enumerate((1.0, -1.0)):
        # platform point (eq. (4)): Z(gamma) [sqrt(3) a/2, sign a/2, 0]
        px, py = math.sqrt(3.0) * d["a"] / 2.0, sign * d["a"] / 2.0
        ux, uy = math.cos(gamma) * px - math.sin(gamma) * py, math.sin(gamma) * px + math.cos(gamma) * py
        lat = sign * d["b"] / 2.0
        dx = v[4] * codac.cos(v[3]) - lat * codac.sin(v[3])
        dy = v[4] * codac.sin(v[3]) + lat * codac.cos(v[3])
        expr = codac.sqrt(codac.sqr(v[0] + ux - dx) + codac.sqr(v[1] + uy - dy) + codac.sqr(v[2]))
        out.append(codac.AnalyticFunction([v], expr))
    return out


def chain_verdict(fs, cube, varpi, rho, lmin, lmax, depth=9) -> str:
    for w in np.linspace(varpi[0], varpi[1], 7):
        for r in np.linspace(rho[0], rho[1], 5):
            box = codac.IntervalVector([*cube, [w, w], [r, r]])
            if all(lmin <= f.eval(box).lb() and f.eval(box).ub() <= lmax for f in fs):
                return "in"
    stack = [(varpi, rho, 0)]
    while stack:
        (w0, w1), (r0, r1), k = stack.pop()
        box = codac.IntervalVector([*cube, [w0, w1], [r0, r1]])
        if any(f.eval(box).ub() < lmin or f.eval(box).lb() > lmax for f in fs):
            continue
        if k >= depth:
            return "?"
        if (w1 - w0) * 150.0 > (r1 - r0):
            m = 0.5 * (w0 + w1)
            stack += [((w0, m), (r0, r1), k + 1), ((m, w1), (r0, r1), k + 1)]
        else:
            m = 0.5 * (r0 + r1)
            stack += [((w0, w1), (r0, m), k + 1), ((w0, w1), (m, r1), k + 1)]
    return "out"


def main() -> None:
    job = json.load(sys.stdin)
    d = job["design"]
    eta = (-0.5 * d["eta_s"], 0.5 * d["eta_s"]) if d["eta_range"] == "centered" else (0.0, d["eta_s"])
    rho = (d["r"] - d["d_s"], d["r"])
    lmin, lmax = d["l_min"], d["l_min"] + d["l_s"]
    fs = [legs(d, i) for i in range(3)]
    verdicts = []
    for cube in job["cubes"]:
        vs = []
        for i in range(3):
            g = 2.0 * math.pi * i / 3.0
            v = chain_verdict(fs[i], cube, (g + math.radians(eta[0]), g + math.radians(eta[1])), rho, lmin, lmax)
            vs.append(v)
            if v == "out":
                break
        verdicts.append("out" if "out" in vs else ("in" if vs == ["in"] * 3 else "?"))
    json.dump(verdicts, sys.stdout)


if __name__ == "__main__":
    main()
