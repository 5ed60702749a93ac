"""The README's optimisation figure and the paper design's distance from the front.

Runs the README command's optimisation (volume vs -footprint over a, d_s, eta_s, l_s, Table I's
ranges, h = 4, population 16 x 12 generations, seed 1), writes docs/optimize_front.png with the
paper's default design (Table I / Fig. 3) as a star, and prints (all at h = 4):
  * the default design's volume and footprint (evaluate_design, the same unit of work);
  * the largest front volume at a footprint <= the default's, and the ratio to the default's;
  * the smallest front footprint at a volume >= the default's.

Usage: python benchmarks/optimize_readme_figure.py [--out docs/optimize_front.png] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))  # measure this checkout

from paraspace.app.optimize_plots import front_png
from paraspace.kinematics.design import Design
from paraspace.kinematics.optimize import OptimizeSettings, measures_of, optimize
from paraspace.kinematics.sweep import evaluate_design
from paraspace.kinematics.workspace import WorkspaceSettings, warm_up


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="docs/optimize_front.png")
    ap.add_argument("--json", help="also write the result JSON here")
    ns = ap.parse_args()
    warm_up()
    ws = WorkspaceSettings(voxel=4.0)
    s = OptimizeSettings(objectives="volume,-footprint", workspace=ws, population=16, generations=12, seed=1)
    res = optimize(s).to_dict()
    if ns.json:
        with open(ns.json, "w") as fh:
            json.dump(res, fh)
    paper = measures_of(evaluate_design(Design(), ws))
    v0, f0 = paper["volume"], paper["footprint"]
    front_png(res, ns.out, highlight={"label": "paper's design (Fig. 3)", "measures": paper})
    print(f"front: {len(res['front'])} designs, {res['evaluations']} evaluations, {res['seconds']:.1f} s, "
          f"hypervolume per generation {[round(h, 4) for h in res['hypervolume']]}")
    print(f"paper's design: volume {v0:.4g}, footprint {f0:g}")
    cheaper = [e for e in res["front"] if e["measures"]["footprint"] <= f0]
    if cheaper:
        best = max(cheaper, key=lambda e: e["measures"]["volume"])
        print(f"largest front volume at footprint <= {f0:g}: {best['measures']['volume']:.4g} "
              f"(x{best['measures']['volume'] / v0:.2f}) at "
              + ", ".join(f"{p}={best['design'][p]:g}" for p in s.params)
              + f", footprint {best['measures']['footprint']:g}")
    bigger = [e for e in res["front"] if e["measures"]["volume"] >= v0]
    if bigger:
        best = min(bigger, key=lambda e: e["measures"]["footprint"])
        print(f"smallest front footprint at volume >= {v0:.4g}: {best['measures']['footprint']:g} "
              f"({best['measures']['footprint'] - f0:+g}) at "
              + ", ".join(f"{p}={best['design'][p]:g}" for p in s.params)
              + f", volume {best['measures']['volume']:.4g}")


if __name__ == "__main__":
    main()
