"""Workspace volume and shape of one design.

The constant-orientation position workspace of the paper's default design, on a voxel grid, and its
measures (volume, voids, genus, boundary). A finer voxel (``main(voxel=1.0)``) takes longer and is
closer to the continuous workspace.

    python examples/01_workspace_volume.py
"""

from __future__ import annotations

import paraspace as ps


def main(voxel: float = 4.0) -> ps.WorkspaceMeasures:
    design = ps.Design()  # the paper's dimensions; ps.Design(a=60.0) changes one of them
    result = ps.compute_workspace(design, ps.WorkspaceSettings(voxel=voxel))
    measures = ps.measure_workspace(result)
    print(f"design          {design}")
    print(f"voxels          {result.voxels} of {voxel:g}^3")
    print(f"volume          {result.volume:.6g} units^3 ({result.compute_seconds:.2f} s)")
    print(f"voids           {measures.voids}, genus {measures.genus}, "
          f"boundary {'closed' if measures.boundary_closed else 'open'}")
    return measures


if __name__ == "__main__":
    main()
