"""3-D scene of one browser: the mechanism at the current pose and the workspace shell.

:class:`MechanismScene` draws the base (circle, arc rails with their stroke, radial rails), the
three carriages, the six legs colored by state (inside / at a limit / out of range), the U and S
joints, and the platform with its frame. Static parts are rebuilt when the design changes; a pose
change only moves nodes (a few array assignments inside ``client.atomic()``).

:class:`ShellScene` shows the marching-cubes shell of the workspace (colored by z, translucent,
optionally cut by a horizontal plane). The platform plate is green when the pose lies in the
workspace and red otherwise, with a label above it; legs outside their stroke carry a label naming
their state; the x, y, z axes are drawn from the origin with labelled tips. Labels are screen
overlays: the translucent shell and the drag gizmo never hide them.
The shell is sent as a GLB with quantised attributes (:func:`app.explorer.wire_glb.quantised_glb`:
int16 positions, int8 normals, uint8 vertex colours, uint16 indices, and its material with alpha).

Coordinates are the paper's base frame ``O-xyz`` (z up), in the paper's dimensionless lengths.
"""

from __future__ import annotations

import json
import struct
from collections.abc import Callable
from typing import Any

import numpy as np
import trimesh
import viser
import viser.transforms as vtf

from paraspace.kinematics.design import Design
from paraspace.kinematics.geometry import GAMMA, base_points, carriage_rails, platform_points_local
from paraspace.kinematics.pose import Pose

from .wire_glb import quantised_glb

#: Leg colors by state (:func:`kinematics.inverse.leg_states`).
LEG_COLORS: dict[str, tuple[int, int, int]] = {
    "inside": (70, 130, 200),
    "at_limit": (245, 160, 20),
    "too_short": (215, 40, 40),
    "too_long": (215, 40, 40),
}
LEG_STATE_TEXT: dict[str, str] = {
    "inside": "inside", "at_limit": "at a limit", "too_short": "too short", "too_long": "too long",
}
RAIL_COLOR = (90, 90, 100)
ARC_COLOR = (40, 160, 90)
CARRIAGE_COLOR = (120, 120, 135)
PLATFORM_COLOR = (190, 190, 205)
REACHABLE_COLOR = (30, 180, 60)
UNREACHABLE_COLOR = (220, 30, 30)

_UNIT_CYLINDER = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=16)
_UNIT_BOX = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
_UNIT_SPHERE = trimesh.creation.icosphere(subdivisions=1, radius=1.0)


def segment_transforms(p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rotation (wxyz), midpoint and length that map the unit +Z cylinder onto segments ``p -> q``.

    Args:
        p, q: segment end points, shape (N, 3).
    Returns:
        ``(wxyz (N, 4), centers (N, 3), lengths (N,))``.
    """
    p = np.asarray(p, float).reshape(-1, 3)
    q = np.asarray(q, float).reshape(-1, 3)
    d = q - p
    length = np.linalg.norm(d, axis=1)
    u = d / np.maximum(length, 1e-12)[:, None]
    ax = np.cross(np.array([0.0, 0.0, 1.0]), u)
    s = np.linalg.norm(ax, axis=1)
    ang = np.arctan2(s, u[:, 2])
    ax = np.where(s[:, None] > 1e-9, ax / np.maximum(s, 1e-12)[:, None], np.array([1.0, 0.0, 0.0]))
    wxyz = vtf.SO3.exp(ax * ang[:, None]).wxyz
    return np.asarray(wxyz), (p + q) / 2.0, length


def rotation_wxyz(rot: np.ndarray) -> np.ndarray:
    """Quaternion (w, x, y, z) of a rotation matrix."""
    return np.asarray(vtf.SO3.from_matrix(np.asarray(rot, float)).wxyz)


def _polyline_segments(points: np.ndarray) -> np.ndarray:
    """(N, 3) polyline -> (N-1, 2, 3) segments."""
    return np.stack([points[:-1], points[1:]], axis=1)


def _carriage_frames(design: Design, d: np.ndarray, eta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centre (3, 3) and heading wxyz (3, 4) of each carriage at radius ``r - d_i``, angle ``varpi_i``."""
    varpi = np.radians(np.asarray(eta, float)) + GAMMA
    rho = design.r - np.asarray(d, float)
    centers = np.stack([rho * np.cos(varpi), rho * np.sin(varpi), np.zeros(3)], axis=1)
    wxyz = np.stack([vtf.SO3.from_z_radians(float(v)).wxyz for v in varpi])
    return centers, wxyz


class MechanismScene:
    """The mechanism of one client's scene (see the module docstring).

    Nodes are created once; a design change only assigns new geometry to them (no node is
    removed and re-added), a pose change only moves them.

    Args:
        scene: the client's :class:`viser.SceneApi` (``client.scene``).
        design, pose: what to draw first.
        d, eta: carriage values (3,), eta in degrees.
        leg_status: 3x2 leg states.
    """

    def __init__(self, scene: viser.SceneApi, design: Design, pose: Pose, d: np.ndarray, eta: np.ndarray,
                 leg_status: list[list[str]]) -> None:
        self.scene = scene
        self.design = design
        sc = scene
        g = self._geometry(design)
        self.grid = sc.add_grid("/mechanism/grid", width=g["grid"], height=g["grid"], cell_size=g["cell"],
                                section_size=design.r, plane="xy", cell_color=(215, 215, 215),
                                section_color=(170, 170, 170), fade_distance=40.0 * design.r, shadow_opacity=0.0)
        self.base_circle = sc.add_line_segments("/mechanism/base_circle", g["circle"], RAIL_COLOR,
                                                thickness=0.4 * g["thick"])
        self.arc_rails = sc.add_line_segments("/mechanism/arc_rails", g["arcs"], ARC_COLOR, thickness=2.0 * g["thick"])
        self.labels = [sc.add_label(f"/mechanism/chain_label_{i + 1}", f"chain {i + 1}", position=g["labels"][i],
                                    font_size_mode="screen", font_screen_scale=0.8) for i in range(3)]
        # the scale: what one grid cell measures, at the grid's near corner
        self.scale_label = sc.add_label("/mechanism/grid_scale", grid_scale_text(design), position=g["scale_at"],
                                        font_size_mode="screen", font_screen_scale=0.7)
        B, D = self._joint_points(design, pose, d, eta)
        wxyz, ctr, length = segment_transforms(D, B)
        lr, jr = g["leg_radius"], g["joint_radius"]
        self.legs = sc.add_batched_meshes_simple(
            "/mechanism/legs", _UNIT_CYLINDER.vertices, _UNIT_CYLINDER.faces, wxyz, ctr,
            batched_scales=np.c_[np.full(6, lr), np.full(6, lr), length],
            batched_colors=self._leg_colors(leg_status), lod="off", cast_shadow=False, receive_shadow=False,
            material="toon3")  # flat bands: a leg's state colour stays readable, never shaded to near-black
        self.joints = sc.add_batched_meshes_simple(
            "/mechanism/joints", _UNIT_SPHERE.vertices, _UNIT_SPHERE.faces,
            np.tile([1.0, 0.0, 0.0, 0.0], (12, 1)), np.vstack([D, B]),
            batched_scales=np.full(12, jr), batched_colors=np.array([(60, 60, 70)] * 6 + [(200, 80, 40)] * 6),
            lod="off", cast_shadow=False, receive_shadow=False)
        centers, cw = _carriage_frames(design, d, eta)
        self.carriages = sc.add_batched_meshes_simple(
            "/mechanism/carriages", _UNIT_BOX.vertices, _UNIT_BOX.faces, cw, centers,
            batched_scales=g["carriage_scale"], batched_colors=CARRIAGE_COLOR, lod="off",
            cast_shadow=False, receive_shadow=False)
        self.radials = sc.add_line_segments("/mechanism/radial_rails", self._radial_segments(design, eta),
                                            RAIL_COLOR, thickness=g["radial_thick"])
        self.platform = sc.add_frame("/platform", show_axes=True, axes_length=0.6 * design.a,
                                     axes_radius=0.03 * design.a, origin_radius=0.05 * design.a,
                                     position=pose.position, wxyz=rotation_wxyz(pose.rotation))
        verts, faces = g["plate"]
        self.platform_mesh = sc.add_mesh_simple("/platform/plate", verts, faces, color=PLATFORM_COLOR,
                                                opacity=0.85, side="double", cast_shadow=False,
                                                receive_shadow=False)
        # labels are drawn over the 3-D scene: never hidden by the translucent shell or the gizmo
        self.pose_label = sc.add_label("/platform/pose_label", "P", position=(0.0, 0.0, 0.9 * design.a),
                                       font_size_mode="screen", font_screen_scale=0.9)
        # one label per chain whose legs leave their stroke, at the top end of its first such leg
        self.leg_labels = [sc.add_label(f"/mechanism/leg_label_{k}", "", position=(0.0, 0.0, 0.0), visible=False,
                                        font_size_mode="screen", font_screen_scale=0.75) for k in range(3)]
        self._leg_top = B
        self._leg_status = leg_status
        self._show_leg_labels()
        ax_len = 1.35 * design.r
        self.axes = sc.add_line_segments(
            "/mechanism/axes", np.array([[[0, 0, 0], [ax_len, 0, 0]], [[0, 0, 0], [0, ax_len, 0]],
                                         [[0, 0, 0], [0, 0, ax_len]]], float),
            np.array([[[200, 40, 40]] * 2, [[40, 150, 40]] * 2, [[40, 70, 200]] * 2], np.uint8), thickness=2.0)
        self.axis_labels = [sc.add_label(f"/mechanism/axis_{n}", n, position=tuple(1.08 * ax_len * e),
                                         font_size_mode="screen", font_screen_scale=0.9)
                            for n, e in (("x", np.array([1.0, 0, 0])), ("y", np.array([0, 1.0, 0])),
                                         ("z", np.array([0, 0, 1.0])))]

    @staticmethod
    def _geometry(design: Design) -> dict[str, Any]:
        """Everything the design fixes: base circle, arc rails, grid, sizes, the platform plate."""
        t = np.linspace(0.0, 2.0 * np.pi, 121)
        circle = np.stack([design.r * np.cos(t), design.r * np.sin(t), np.zeros_like(t)], axis=1)
        rails = carriage_rails(design, samples=49)
        lr = max(1.0, 0.03 * design.a)
        jr = 1.8 * lr
        # platform polygon in the platform frame (fan from the centre through the six joints)
        u = platform_points_local(design).reshape(6, 3)
        ring = u[np.argsort(np.arctan2(u[:, 1], u[:, 0]))]
        verts = np.vstack([np.zeros((1, 3)), ring])
        faces = np.array([[0, 1 + k, 1 + (k + 1) % 6] for k in range(6)])
        return {
            "circle": _polyline_segments(circle),
            "arcs": np.concatenate([_polyline_segments(a) for a in rails["arcs"]]),
            "thick": max(0.6, 0.012 * design.r),
            "radial_thick": max(0.8, 0.02 * design.r),
            "grid": 4.0 * design.r,
            "cell": design.r / 5.0,
            "scale_at": (1.7 * design.r, -0.5 * design.r, 0.0),
            "labels": [1.12 * design.r * np.array([np.cos(GAMMA[i]), np.sin(GAMMA[i]), 0.0]) for i in range(3)],
            "leg_radius": lr,
            "joint_radius": jr,
            "carriage_scale": np.tile([0.12 * design.r, design.b + 4.0 * jr, 2.0 * jr], (3, 1)),
            "plate": (verts, faces),
        }

    @staticmethod
    def _joint_points(design: Design, pose: Pose, d: np.ndarray, eta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Platform joints ``B`` and base joints ``D``, each (6, 3) in chain-major order."""
        u = platform_points_local(design)
        B = (pose.position + u @ pose.rotation.T).reshape(6, 3)
        D = base_points(design, d, eta).reshape(6, 3)
        return B, D

    @staticmethod
    def _leg_colors(leg_status: list[list[str]]) -> np.ndarray:
        return np.array([LEG_COLORS.get(s, (128, 128, 128)) for row in leg_status for s in row], dtype=np.uint8)

    @staticmethod
    def _radial_segments(design: Design, eta: np.ndarray) -> np.ndarray:
        varpi = np.radians(np.asarray(eta, float)) + GAMMA
        lo, hi = design.rho_limits
        seg = np.zeros((3, 2, 3))
        for i in range(3):
            c, s = np.cos(varpi[i]), np.sin(varpi[i])
            seg[i, 0, :2] = hi * c, hi * s
            seg[i, 1, :2] = lo * c, lo * s
        return seg

    # ----- updates ----------------------------------------------------------------------------
    def set_design(self, design: Design, pose: Pose, d: np.ndarray, eta: np.ndarray,
                   leg_status: list[list[str]]) -> None:
        """Give every node the geometry of ``design`` (in place), then draw the pose."""
        g = self._geometry(design)
        self.grid.width = self.grid.height = g["grid"]
        self.grid.cell_size = g["cell"]
        self.grid.section_size = design.r
        self.grid.fade_distance = 40.0 * design.r
        self.base_circle.points = g["circle"]
        self.base_circle.thickness = 0.4 * g["thick"]
        self.arc_rails.points = g["arcs"]
        self.arc_rails.thickness = 2.0 * g["thick"]
        for label, pos in zip(self.labels, g["labels"]):
            label.position = pos
        self.scale_label.text = grid_scale_text(design)
        self.scale_label.position = g["scale_at"]
        self.joints.batched_scales = np.full(12, g["joint_radius"])
        self.carriages.batched_scales = g["carriage_scale"]
        self.radials.thickness = g["radial_thick"]
        self.platform.axes_length = 0.6 * design.a
        self.platform.axes_radius = 0.03 * design.a
        self.platform.origin_radius = 0.05 * design.a
        self.platform_mesh.vertices = g["plate"][0]
        self.pose_label.position = (0.0, 0.0, 0.9 * design.a)
        ax_len = 1.35 * design.r
        self.axes.points = np.array([[[0, 0, 0], [ax_len, 0, 0]], [[0, 0, 0], [0, ax_len, 0]],
                                     [[0, 0, 0], [0, 0, ax_len]]], float)
        for lab, e in zip(self.axis_labels, np.eye(3)):
            lab.position = tuple(1.08 * ax_len * e)
        self.design = design
        self.update_pose(pose, d, eta, leg_status)

    def update_pose(self, pose: Pose, d: np.ndarray, eta: np.ndarray, leg_status: list[list[str]]) -> None:
        """Move legs, joints, carriages, radial rails and the platform (no re-creation)."""
        design = self.design
        B, D = self._joint_points(design, pose, d, eta)
        wxyz, ctr, length = segment_transforms(D, B)
        lr = max(1.0, 0.03 * design.a)
        self.legs.batched_wxyzs = wxyz
        self.legs.batched_positions = ctr
        self.legs.batched_scales = np.c_[np.full(6, lr), np.full(6, lr), length]
        self.legs.batched_colors = self._leg_colors(leg_status)
        self.joints.batched_positions = np.vstack([D, B])
        centers, cw = _carriage_frames(design, d, eta)
        self.carriages.batched_positions = centers
        self.carriages.batched_wxyzs = cw
        self.radials.points = self._radial_segments(design, eta)
        self.platform.position = pose.position
        self.platform.wxyz = rotation_wxyz(pose.rotation)
        self._leg_top = B
        self._leg_status = leg_status
        self._show_leg_labels()

    def _show_leg_labels(self) -> None:
        """One label per chain with a leg that is not inside its stroke, at that leg's top end
        (:func:`chain_label_text`)."""
        for i, lab in enumerate(self.leg_labels):
            text = chain_label_text(i, self._leg_status[i])
            if text is None:
                lab.visible = False
                continue
            j = next(j for j in range(2) if self._leg_status[i][j] != "inside")
            lab.text = text
            lab.position = np.asarray(self._leg_top[2 * i + j], float)
            lab.visible = True

    def set_reachable(self, reachable: bool) -> None:
        """Colour the platform plate by whether the pose lies in the workspace and say so in a label
        above it (the label stays readable over the shell and the drag gizmo)."""
        self.platform_mesh.color = REACHABLE_COLOR if reachable else UNREACHABLE_COLOR
        self.pose_label.text = "P: in the workspace" if reachable else "P: outside the workspace"


# --------------------------------------------------------------------------------------------
# workspace shell


def grid_scale_text(design: Design) -> str:
    """The grid's scale in words: "grid: 20 units per cell, 100 per section" (cells r/5, sections r)."""
    return f"grid: {design.r / 5.0:g} units per cell, {design.r:g} per section"


def chain_label_text(chain: int, states: list[str]) -> str | None:
    """The label of chain ``chain`` (0-based) with leg states ``states`` (2), ``None`` when both
    legs are inside their stroke: "chain 2: legs 1, 2 too long", "chain 1: leg 2 at a limit",
    "chain 3: leg 1 too short, leg 2 at a limit"."""
    out = [(j, st) for j, st in enumerate(states) if st != "inside"]
    if not out:
        return None
    if len(out) == 2 and out[0][1] == out[1][1]:
        return f"chain {chain + 1}: legs 1, 2 {LEG_STATE_TEXT.get(out[0][1], out[0][1])}"
    return f"chain {chain + 1}: " + ", ".join(f"leg {j + 1} {LEG_STATE_TEXT.get(st, st)}" for j, st in out)


def remove_node(handle: Any | None) -> None:
    """Remove a scene node if there is one (quietly: its browser may have left)."""
    if handle is not None:
        try:
            handle.remove()
        except Exception:  # noqa: BLE001 - the client may be gone
            pass


def glb_with_material(glb: bytes, opacity: float) -> bytes:
    """Give every primitive of a GLB one double-sided material with alpha ``opacity``.

    trimesh writes vertex colors (``COLOR_0``) without a material, which three.js renders opaque;
    this rewrites the JSON chunk so the shell is translucent (``alphaMode: BLEND``) when
    ``opacity < 1``.
    """
    magic, version, _total = struct.unpack_from("<4sII", glb, 0)
    if magic != b"glTF":
        raise ValueError("not a GLB")
    json_len, json_type = struct.unpack_from("<I4s", glb, 12)
    doc = json.loads(glb[20:20 + json_len].decode("utf-8"))
    rest = glb[20 + json_len:]
    doc["materials"] = [{
        "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, float(opacity)],
                                 "metallicFactor": 0.0, "roughnessFactor": 0.85},
        "alphaMode": "BLEND" if opacity < 0.999 else "OPAQUE",
        "doubleSided": False,
    }]
    for mesh in doc.get("meshes", []):
        for prim in mesh.get("primitives", []):
            prim["material"] = 0
    body = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    body += b" " * ((4 - len(body) % 4) % 4)
    out = struct.pack("<4sII", magic, version, 12 + 8 + len(body) + len(rest))
    out += struct.pack("<I4s", len(body), json_type) + body + rest
    return out


def _z_color_lookup(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray] | None:
    """(sorted z, RGBA colors) of the mesh's vertices, when it has vertex colors."""
    if mesh.visual.kind != "vertex" or len(mesh.vertices) == 0:  # type: ignore[union-attr]
        return None
    z = mesh.vertices[:, 2]
    order = np.argsort(z, kind="stable")
    return z[order], np.asarray(mesh.visual.vertex_colors)[order]  # type: ignore[union-attr]


def cut_mesh(mesh: trimesh.Trimesh, z: float, keep: str) -> trimesh.Trimesh:
    """The part of ``mesh`` below (``keep="below"``) or above a horizontal plane at height ``z``.

    Faces are split exactly at the plane (no cap: looking into the cut shows the cavities). Colors
    of new vertices are interpolated in z (the shell's colors are a function of z).
    """
    from trimesh import intersections

    normal = np.array([0.0, 0.0, -1.0 if keep == "below" else 1.0])
    verts, faces, _ = intersections.slice_faces_plane(mesh.vertices, mesh.faces, normal, np.array([0.0, 0.0, z]))
    out = trimesh.Trimesh(vertices=verts, faces=faces, process=False)
    lut = _z_color_lookup(mesh)
    if lut is not None and len(verts):
        zs, cols = lut
        rgba = np.stack([np.interp(verts[:, 2], zs, cols[:, k].astype(float)) for k in range(4)], axis=1)
        out.visual.vertex_colors = np.round(rgba).astype(np.uint8)  # type: ignore[union-attr]
    return out


class ShellScene:
    """Workspace shell node and the pose marker of one client's scene."""

    NAME = "/workspace/shell"

    def __init__(self, scene: viser.SceneApi, is_closed: Callable[[], bool] = lambda: False) -> None:
        self.scene = scene
        self.is_closed = is_closed  # the browser left: an encoded shell is not sent
        self.handle: Any | None = None
        self.source: trimesh.Trimesh | None = None
        self.last_payload_bytes = 0
        self.last_faces = 0
        self.stale_label = scene.add_label("/workspace/stale_label", "", position=(0.0, 0.0, 0.0), visible=False,
                                           font_size_mode="screen", font_screen_scale=1.0)

    def show(self, mesh: trimesh.Trimesh | None, opacity: float, cut: bool, cut_z: float, keep: str) -> int:
        """Replace the shell (``None`` removes it); returns the GLB payload size in bytes."""
        self.source = mesh
        return self.refresh(opacity, cut, cut_z, keep)

    def refresh(self, opacity: float, cut: bool, cut_z: float, keep: str) -> int:
        """Re-send the current shell with new view settings (opacity, cut plane)."""
        mesh = self.source
        if mesh is None or len(mesh.faces) == 0:
            if self.handle is not None:
                try:
                    self.handle.remove()
                except Exception:  # noqa: BLE001
                    pass
                self.handle = None
            self.last_payload_bytes = 0
            self.last_faces = 0
            return 0
        shown = cut_mesh(mesh, cut_z, keep) if cut else mesh
        if len(shown.faces) == 0:
            glb = b""
        else:
            glb = quantised_glb(shown, opacity)
        if not glb:
            if self.handle is not None:
                self.handle.visible = False
            self.last_payload_bytes = 0
            self.last_faces = 0
            return 0
        if self.is_closed():  # checked after the encoding, which takes a while
            return 0
        self.handle = self.scene.add_glb(self.NAME, glb, cast_shadow=False, receive_shadow=False)
        self.last_payload_bytes = len(glb)
        self.last_faces = int(len(shown.faces))
        return len(glb)

    def set_stale(self, text: str | None) -> None:
        """Mark the shown shell as belonging to a previous design (``text`` over its top) or clear it."""
        mesh = self.source
        if not text or mesh is None or len(mesh.vertices) == 0:
            self.stale_label.visible = False
            return
        top = mesh.vertices[np.argmax(mesh.vertices[:, 2])]
        self.stale_label.text = text
        self.stale_label.position = (float(top[0]), float(top[1]), float(top[2]) + 10.0)
        self.stale_label.visible = True

    def z_range(self) -> tuple[float, float] | None:
        """The z range that the shell's colours span (``None`` without a shell)."""
        mesh = self.source
        if mesh is None or len(mesh.vertices) == 0:
            return None
        zr = mesh.metadata.get("paraspace", {}).get("color_range")
        if zr is not None:  # the reachable voxels' heights (workspace_job.voxel_z_range)
            return float(zr[0]), float(zr[1])
        return float(mesh.vertices[:, 2].min()), float(mesh.vertices[:, 2].max())
