"""The workspace's boundary as a mesh file (STL, PLY, OBJ or GLB) for CAD or a 3-D viewer.

    python examples/04_export_shell.py
"""

from __future__ import annotations

import pathlib

import paraspace as ps


def main(out: str = "workspace.stl", voxel: float = 4.0, max_faces: int = 50_000) -> pathlib.Path:
    result = ps.compute_workspace(ps.Design(), ps.WorkspaceSettings(voxel=voxel))
    mesh = ps.workspace_shell(result, max_faces=max_faces)  # closed, outward-oriented
    path = pathlib.Path(out)
    path.write_bytes(ps.export_shell(mesh, path.suffix.lstrip(".")))
    print(f"{path}: {len(mesh.faces)} faces, mesh volume {mesh.volume:.6g} "
          f"(voxel volume {result.volume:.6g}) units^3")
    return path


if __name__ == "__main__":
    main()
