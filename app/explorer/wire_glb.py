r"""The shell on the wire: a GLB with quantised attributes (glTF ``KHR_mesh_quantization``).

Definition. For a triangle mesh with vertices ``v`` (N, 3, millimetres), RGBA8 vertex colours
``c`` and faces ``f`` (F, 3), let ``lo, hi`` be the per-axis bounds, ``t = (lo + hi) / 2`` and
``s = max_k (hi_k - lo_k) / 2`` (one scale for all axes, so that normals computed from the stored
positions point the same way as the millimetre mesh's). The GLB stores

    POSITION  q = round((v - t) / s * 32767)   int16, normalised   (decoded q / 32767)
    NORMAL    (declared, no data)              float32             (zeros; see below)
    COLOR_0   c                                uint8, normalised   (core glTF)
    indices   f                                uint16 when N <= 65535, else uint32

and the node's ``scale = (s, s, s)`` and ``translation = t`` restore millimetres:
``v' = t + s q / 32767``. With the largest extent ``E = 2 s`` the position step is
``E / 65534`` and ``|v' - v| <= E / 131068`` per coordinate (the tests allow ``E / 65534``, which
also covers the float32 of the node transform). Colours and faces are exact and vertices stay
shared (never split), so a closed mesh stays closed: no cracks.

Normals are not sent, only declared: viser 1.1.1's client recomputes every GLB mesh's vertex
normals after loading it (``geometry.computeVertexNormals()`` on each mesh, in the GLB component of
its bundled client), so the float normals that trimesh wrote were overwritten unused. The NORMAL
accessor is float32 with no buffer view, which glTF defines as zeros and three.js's GLTFLoader
allocates as a zero Float32Array; the client then fills it with the area-weighted vertex normals of
the decoded positions, as it did before (up to the position step). It must be declared: without a
NORMAL attribute the loader switches the material to flat shading (a faceted shell), and int8
normals do not survive the recomputation (it accumulates into the attribute it finds, and an int8
attribute rounds the small sums to zero: a black shell). Positions are padded to 8-byte elements
(byte stride 8), as glTF requires of vertex attributes (4-byte alignment).

One single-sided PBR material with alpha ``opacity`` (``alphaMode: BLEND`` below 1) is written
with the mesh, as :func:`app.explorer.scene.glb_with_material` patches into trimesh's float GLB.
Per vertex the GLB holds 12 bytes instead of 28, per face 6 instead of 12 (while N <= 65535).
"""

from __future__ import annotations

import json
import struct
from typing import Any

import numpy as np

__all__ = ["quantised_glb", "POSITION_STEPS"]

#: Positions map onto the normalised int16 range [-32767, 32767]: 65 534 steps over the largest extent.
POSITION_STEPS = 65_534
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963
_UBYTE, _SHORT, _USHORT, _UINT, _FLOAT = 5121, 5122, 5123, 5125, 5126


def quantised_glb(mesh: Any, opacity: float = 1.0) -> bytes:
    """The GLB of ``mesh`` (a ``trimesh.Trimesh`` with faces) as defined in the module docstring.

    Vertex colours are the mesh's ``visual.vertex_colors`` when it has them (else none are written).

    Raises:
        ValueError: a mesh without faces.
    """
    v = np.asarray(mesh.vertices, dtype=np.float64)
    f = np.asarray(mesh.faces, dtype=np.int64)
    if len(f) == 0 or len(v) == 0:
        raise ValueError("a mesh without faces has no GLB")
    n_v = len(v)
    lo, hi = v.min(axis=0), v.max(axis=0)
    t = (lo + hi) / 2.0
    s = float((hi - lo).max()) / 2.0 or 1.0
    q = np.zeros((n_v, 4), dtype=np.int16)  # 4th component: padding to 8 bytes
    q[:, :3] = np.clip(np.rint((v - t) / s * 32767.0), -32767, 32767)
    colours = None
    if getattr(mesh.visual, "kind", None) == "vertex":
        colours = np.ascontiguousarray(np.asarray(mesh.visual.vertex_colors, dtype=np.uint8)[:, :4])
    idx = f.astype(np.uint16 if n_v <= 65535 else np.uint32).ravel()

    chunks: list[bytes] = []
    views: list[dict] = []
    offset = 0

    def view(data: bytes, target: int, stride: int | None = None) -> int:
        nonlocal offset
        entry = {"buffer": 0, "byteOffset": offset, "byteLength": len(data), "target": target}
        if stride is not None:
            entry["byteStride"] = stride
        views.append(entry)
        pad = (4 - len(data) % 4) % 4
        chunks.append(data + b"\0" * pad)
        offset += len(data) + pad
        return len(views) - 1

    accessors: list[dict] = [
        {"bufferView": view(idx.tobytes(), _ELEMENT_ARRAY_BUFFER), "componentType":
         _USHORT if idx.dtype == np.uint16 else _UINT, "count": int(idx.size), "type": "SCALAR",
         "min": [int(idx.min())], "max": [int(idx.max())]},
        {"bufferView": view(q.tobytes(), _ARRAY_BUFFER, 8), "componentType": _SHORT, "normalized": True,
         "count": n_v, "type": "VEC3", "min": q[:, :3].min(axis=0).tolist(), "max": q[:, :3].max(axis=0).tolist()},
        {"componentType": _FLOAT, "count": n_v, "type": "VEC3"},  # no buffer view: zeros, filled by the client
    ]
    attributes = {"POSITION": 1, "NORMAL": 2}
    if colours is not None:
        accessors.append({"bufferView": view(colours.tobytes(), _ARRAY_BUFFER), "componentType": _UBYTE,
                          "normalized": True, "count": n_v, "type": "VEC4"})
        attributes["COLOR_0"] = 3
    doc = {
        "asset": {"version": "2.0", "generator": "paraspace"},
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "translation": t.tolist(), "scale": [s, s, s]}],
        "meshes": [{"primitives": [{"attributes": attributes, "indices": 0, "mode": 4, "material": 0}]}],
        "materials": [{
            "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, float(opacity)],
                                     "metallicFactor": 0.0, "roughnessFactor": 0.85},
            "alphaMode": "BLEND" if opacity < 0.999 else "OPAQUE",
            "doubleSided": False,
        }],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": offset}],
    }
    body = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    body += b" " * ((4 - len(body) % 4) % 4)
    binary = b"".join(chunks)
    total = 12 + 8 + len(body) + 8 + len(binary)
    return (struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(body), b"JSON") + body
            + struct.pack("<I4s", len(binary), b"BIN\0") + binary)
