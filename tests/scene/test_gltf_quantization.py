# KHR_mesh_quantization: every attribute type the extension allows (its table: POSITION and
# TEXCOORD as (u)byte/(u)short, normalized or not; NORMAL and TANGENT as normalized byte/short),
# in padded 4-byte strides as exporters write them, decoded against a NumPy evaluation of the
# glTF "normalized" rule; and node transforms that dequantise integer positions.

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from gltf_files import GltfFile, grid_mesh

from vkpbr.scene.gltf import load_gltf

SIGNED = {np.int8, np.int16}
# The KHR_mesh_quantization attribute table (float omitted: that is core glTF).
ALLOWED = {
    "POSITION": [(t, n) for t in (np.int8, np.uint8, np.int16, np.uint16) for n in (False, True)],
    "TEXCOORD_0": [(t, n) for t in (np.int8, np.uint8, np.int16, np.uint16) for n in (False, True)],
    "NORMAL": [(np.int8, True), (np.int16, True)],
    "TANGENT": [(np.int8, True), (np.int16, True)],
}
CASES = [(attr, t, n) for attr, combos in ALLOWED.items() for t, n in combos]
FIELD = {"POSITION": "positions", "TEXCOORD_0": "texcoords", "NORMAL": "normals",
         "TANGENT": "tangents"}  # fmt: skip


def quantize(values: np.ndarray, dtype: type, normalized: bool) -> np.ndarray:
    """Integer codes of `values` (in [-1, 1], or [0, 1] for unsigned types, when normalized;
    any magnitude otherwise), rounded as an encoder would."""
    info = np.iinfo(dtype)
    if normalized:
        return np.clip(np.rint(values * info.max), info.min, info.max).astype(dtype)
    return np.clip(np.rint(values), info.min, info.max).astype(dtype)


def expected(codes: np.ndarray, normalized: bool) -> np.ndarray:
    """glTF 2.0 spec 3.11: unsigned c / max; signed max(c / max, -1); non-normalized c."""
    c = codes.astype(np.float64)
    if not normalized:
        return c
    info = np.iinfo(codes.dtype)
    return np.maximum(c / info.max, -1.0) if codes.dtype.kind == "i" else c / info.max


@pytest.mark.parametrize(("attr", "dtype", "normalized"), CASES,
                         ids=[f"{a}-{np.dtype(t).name}-{'norm' if n else 'int'}"
                              for a, t, n in CASES])  # fmt: skip
def test_quantized_attribute(tmp_path: Path, attr: str, dtype: type, normalized: bool) -> None:
    g = grid_mesh()
    n = len(g["POSITION"])
    rng = np.random.default_rng(7)
    signed = dtype in SIGNED
    width = {"POSITION": 3, "TEXCOORD_0": 2, "NORMAL": 3, "TANGENT": 4}[attr]
    if normalized:
        source = g[attr] if attr in ("NORMAL", "TANGENT") else rng.uniform(-1 if signed else 0, 1, (n, width))
    else:
        info = np.iinfo(dtype)
        source = rng.integers(info.min, int(info.max) + 1, (n, width))
    codes = quantize(np.asarray(source, np.float64), dtype, normalized)
    codes[0] = np.iinfo(dtype).min  # the extremes: -128 / -32768 must clamp to -1
    codes[1] = np.iinfo(dtype).max
    f = GltfFile()
    f.used("KHR_mesh_quantization", required=True)
    # NORMAL given: without it, flat normals would unweld the vertices.
    attrs = {"POSITION": f.accessor(g["POSITION"]), "NORMAL": f.accessor(g["NORMAL"])}
    attrs[attr] = f.accessor(codes, normalized=normalized) if normalized else f.accessor(codes)
    f.node(mesh=f.mesh(attrs, f.accessor(g["indices"])))
    mesh = load_gltf(f.save(tmp_path / "q.glb")).meshes[0]
    got = getattr(mesh, FIELD[attr])
    assert got.dtype == np.float32
    assert got.shape == (n, width)
    np.testing.assert_allclose(got, expected(codes, normalized), rtol=1e-6, atol=1e-7)
    np.testing.assert_array_equal(mesh.indices, g["indices"])


@pytest.mark.parametrize("dtype", [np.int16, np.uint16, np.int8, np.uint8])
def test_node_transform_dequantises_positions(tmp_path: Path, dtype: type) -> None:
    """An exporter stores integer positions and moves the dequantisation (scale, offset) into
    the node: world positions equal the float originals within half a quantisation step."""
    g = grid_mesh()
    p = g["POSITION"].astype(np.float64)
    lo, hi = p.min(0), p.max(0)
    info = np.iinfo(dtype)
    step = (hi - lo) / (int(info.max) - int(info.min))
    codes = np.rint((p - lo) / step + info.min).astype(dtype)
    f = GltfFile()
    f.used("KHR_mesh_quantization", required=True)
    mesh = f.mesh({"POSITION": f.accessor(codes), "NORMAL": f.accessor(g["NORMAL"])},
                  f.accessor(g["indices"]))
    offset = lo - info.min * step
    parent = f.node(translation=[5.0, 0.0, 0.0], children=[])
    child = f.node(root=False, mesh=mesh, translation=offset.tolist(), scale=step.tolist())
    f.doc["nodes"][parent]["children"].append(child)
    scene = load_gltf(f.save(tmp_path / "t.gltf"))
    node = scene.nodes[0]
    local = scene.meshes[node.mesh].positions.astype(np.float64)
    world = local @ node.matrix[:3, :3].T.astype(np.float64) + node.matrix[:3, 3]
    np.testing.assert_allclose(world, p + [5, 0, 0], atol=float(step.max()) * 0.5 + 1e-5)
    lo_w, hi_w = scene.bounds()
    np.testing.assert_allclose(lo_w, lo + [5, 0, 0], atol=float(step.max()) + 1e-5)
    np.testing.assert_allclose(hi_w, hi + [5, 0, 0], atol=float(step.max()) + 1e-5)
