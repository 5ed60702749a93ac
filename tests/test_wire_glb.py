"""The shell's GLB on the wire (app.explorer.wire_glb): decoded by a small, independent glTF reader
written from the glTF 2.0 specification (accessors, byte strides, normalised integers, the node's
translation and scale), then checked as a mesh against the mesh it encodes: positions within half
the quantisation step ``E / 65534`` (``E`` the largest extent), the same faces, the same colours
(within 1/255), closed where the input was, and the enclosed volume kept."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest
import trimesh

from paraspace.app.explorer.wire_glb import quantised_glb
from paraspace.kinematics.design import Design
from paraspace.kinematics.display_mesh import display_shell, edges_closed
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

# glTF 2.0, 3.6.2.2 (component types) and 3.11 (normalised integers: signed max(c / (2^(b-1) - 1), -1),
# unsigned c / (2^b - 1))
_TYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def read_glb(glb: bytes) -> tuple[dict, bytes]:
    """The JSON document and the BIN chunk of a GLB (glTF 2.0, 4.4)."""
    magic, version, length = struct.unpack_from("<4sII", glb, 0)
    assert magic == b"glTF" and version == 2 and length == len(glb)
    json_len, json_type = struct.unpack_from("<I4s", glb, 12)
    assert json_type == b"JSON" and json_len % 4 == 0
    doc = json.loads(glb[20:20 + json_len])
    bin_len, bin_type = struct.unpack_from("<I4s", glb, 20 + json_len)
    assert bin_type == b"BIN\0" and bin_len % 4 == 0 and 28 + json_len + bin_len == len(glb)
    return doc, glb[28 + json_len:28 + json_len + bin_len]


def read_accessor(doc: dict, binary: bytes, index: int) -> np.ndarray:
    """Accessor ``index`` as float64 (normalised integers mapped to [-1, 1] / [0, 1]) or as integers."""
    acc = doc["accessors"][index]
    dtype = np.dtype(_TYPES[acc["componentType"]])
    width, count = _WIDTH[acc["type"]], acc["count"]
    if "bufferView" not in acc:  # glTF: initialised with zeros
        return np.zeros((count, width))
    view = doc["bufferViews"][acc["bufferView"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    stride = view.get("byteStride", dtype.itemsize * width)
    rows = [np.frombuffer(binary, dtype=dtype, count=width, offset=start + i * stride) for i in range(count)]
    raw = np.array(rows).reshape(count, width)
    if not acc.get("normalized", False):
        return raw
    if np.issubdtype(dtype, np.signedinteger):
        return np.maximum(raw / float(np.iinfo(dtype).max), -1.0)
    return raw / float(np.iinfo(dtype).max)


def decode(glb: bytes) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, dict]:
    """(vertices in the scene's frame, faces, RGBA colours in [0, 1] or None, the document)."""
    doc, binary = read_glb(glb)
    (node_index,) = doc["scenes"][doc["scene"]]["nodes"]
    node = doc["nodes"][node_index]
    assert "rotation" not in node and "matrix" not in node
    (prim,) = doc["meshes"][node["mesh"]]["primitives"]
    assert prim.get("mode", 4) == 4  # triangles
    local = read_accessor(doc, binary, prim["attributes"]["POSITION"])
    vertices = np.asarray(node.get("translation", [0, 0, 0])) + local * np.asarray(node.get("scale", [1, 1, 1]))
    faces = read_accessor(doc, binary, prim["indices"]).reshape(-1, 3).astype(np.int64)
    colours = (read_accessor(doc, binary, prim["attributes"]["COLOR_0"])
               if "COLOR_0" in prim["attributes"] else None)
    return vertices, faces, colours, doc


def check_alignment(doc: dict) -> None:
    """glTF 2.0, 3.6.2.4: vertex attribute elements aligned to 4 bytes, offsets to the component size."""
    for acc in doc["accessors"]:
        if "bufferView" not in acc:
            continue
        view = doc["bufferViews"][acc["bufferView"]]
        size = np.dtype(_TYPES[acc["componentType"]]).itemsize
        assert (view.get("byteOffset", 0) + acc.get("byteOffset", 0)) % size == 0
        if view.get("target") == 34962:  # ARRAY_BUFFER: vertex attributes
            assert view.get("byteOffset", 0) % 4 == 0 and view.get("byteStride", 4) % 4 == 0
            assert view.get("byteStride", size * _WIDTH[acc["type"]]) >= size * _WIDTH[acc["type"]]


@pytest.fixture(scope="module")
def shell() -> trimesh.Trimesh:
    return display_shell(compute_workspace(Design(), WorkspaceSettings(voxel=6.0)))


def test_the_display_shell_decodes_to_itself_within_the_quantisation_step(shell):
    glb = quantised_glb(shell, 0.55)
    v, f, c, doc = decode(glb)
    check_alignment(doc)
    assert "KHR_mesh_quantization" in doc["extensionsRequired"]
    v0 = np.asarray(shell.vertices)
    extent = float(np.ptp(v0, axis=0).max())
    step = extent / 65534  # normalised int16 over [-32767, 32767]
    assert np.abs(v - v0).max() <= 0.5 * step * (1 + 1e-9)
    assert np.array_equal(f, np.asarray(shell.faces))
    assert c is not None and np.abs(c - np.asarray(shell.visual.vertex_colors) / 255.0).max() <= 1 / 255
    # a mesh: closed as the input was, the same volume up to the step (|V' - V| <= area * sqrt(3) step / 2)
    assert edges_closed(np.asarray(shell.faces)) and edges_closed(f)
    decoded = trimesh.Trimesh(vertices=v, faces=f, process=False)
    assert decoded.is_watertight and decoded.is_winding_consistent and decoded.volume > 0
    assert abs(decoded.volume - shell.volume) <= shell.area * np.sqrt(3) * 0.5 * step
    # smaller than trimesh's float32 GLB of the same mesh, by more than a third
    assert len(glb) < 0.66 * len(shell.export(file_type="glb", include_normals=True))


def test_indices_uint16_up_to_65535_vertices_then_uint32_normals_declared_material_alpha():
    for subdivisions, expect in ((3, 5123), (7, 5125)):  # 642 and 163 842 vertices
        mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=80.0)
        mesh.vertices = mesh.vertices * [1.0, 0.5, 0.25] + [10.0, -20.0, 300.0]  # unequal extents, off-centre
        rgba = np.column_stack([np.arange(len(mesh.vertices)) % 256, np.full(len(mesh.vertices), 7),
                                np.linspace(0, 255, len(mesh.vertices)).round(), np.full(len(mesh.vertices), 255)])
        mesh.visual.vertex_colors = rgba.astype(np.uint8)
        for opacity, mode in ((1.0, "OPAQUE"), (0.3, "BLEND")):
            v, f, c, doc = decode(quantised_glb(mesh, opacity))
            (prim,) = doc["meshes"][0]["primitives"]
            assert doc["accessors"][prim["indices"]]["componentType"] == expect
            normal = doc["accessors"][prim["attributes"]["NORMAL"]]  # declared, filled by the viewer
            assert "bufferView" not in normal and normal["componentType"] == 5126
            assert normal["count"] == len(mesh.vertices)
            (mat,) = doc["materials"]
            assert mat["alphaMode"] == mode and mat["pbrMetallicRoughness"]["baseColorFactor"][3] == opacity
            step = float(np.ptp(mesh.vertices, axis=0).max()) / 65534
            assert np.abs(v - mesh.vertices).max() <= 0.5 * step * (1 + 1e-9)
            assert np.array_equal(f, mesh.faces) and edges_closed(f)
            assert np.abs(c * 255 - rgba).max() <= 1


def test_a_mesh_without_colours_and_an_empty_mesh():
    box = trimesh.creation.box(extents=(4.0, 2.0, 1.0))
    v, f, c, _ = decode(quantised_glb(box))
    assert c is None and np.array_equal(f, box.faces)
    assert np.abs(v - box.vertices).max() <= 0.5 * 4.0 / 65534 * (1 + 1e-9)
    with pytest.raises(ValueError, match="without faces"):
        quantised_glb(trimesh.Trimesh())
