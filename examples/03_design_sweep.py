"""Workspace volume against one design parameter (the paper's Fig. 4).

Each point is a full workspace computation; results can be cached between runs with
``ps.ResultCache(directory=...)``.

    python examples/03_design_sweep.py
"""

from __future__ import annotations

import numpy as np

import paraspace as ps


def main(param: str = "d_s", voxel: float = 6.0, points: int = 5) -> list[dict]:
    spec = ps.PARAMS[param]  # the range of paper Table I
    values = [float(v) for v in np.linspace(spec.slider_min, spec.slider_max, points)]
    rows = ps.sweep_1d(ps.Design(), param, values, ps.WorkspaceSettings(voxel=voxel))
    print(f"{param:>8}  {'volume':>12}  voids  genus")
    for row in rows:
        print(f"{row['value']:8.3g}  {row['volume']:12.6g}  {row['voids']:5d}  {row['genus']:5d}")
    return rows


if __name__ == "__main__":
    main()
