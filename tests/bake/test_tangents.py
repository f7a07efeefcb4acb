# Tests of tgen tangent generation: agreement with a reference glTF's TANGENTs, the sign
# convention, and NaN-free output for degenerate input.
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vkpbr.bake.tangents import any_perpendicular, generate_tangents, orthonormal_tangent

MIRROR = "NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf"  # under the `assets` folder


def _read_primitive(path: Path) -> dict[str, np.ndarray]:
    """The first primitive's attributes, read directly with pygltflib (tightly packed)."""
    pygltflib = pytest.importorskip("pygltflib")
    gltf = pygltflib.GLTF2().load(str(path))
    blob = (path.parent / gltf.buffers[0].uri).read_bytes()
    comps = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
    types = {5126: np.float32, 5123: np.uint16, 5125: np.uint32}

    def accessor(i: int) -> np.ndarray:
        a = gltf.accessors[i]
        view = gltf.bufferViews[a.bufferView]
        k, dt = comps[a.type], types[a.componentType]
        assert not view.byteStride or view.byteStride == k * np.dtype(dt).itemsize
        off = (view.byteOffset or 0) + (a.byteOffset or 0)
        return np.frombuffer(blob, dt, a.count * k, off).reshape(a.count, k).squeeze()

    prim = gltf.meshes[0].primitives[0]
    attrs = prim.attributes
    return {"positions": accessor(attrs.POSITION), "normals": accessor(attrs.NORMAL),
            "tangents": accessor(attrs.TANGENT), "texcoords": accessor(attrs.TEXCOORD_0),
            "indices": accessor(prim.indices).astype(np.uint32)}


def test_matches_supplied_tangents_including_mirrored_half(assets: Path) -> None:
    m = _read_primitive(assets / MIRROR)
    t = generate_tangents(m["positions"], m["normals"], m["texcoords"], m["indices"])
    ref = m["tangents"]
    cos = np.einsum("ij,ij->i", t[:, :3], ref[:, :3]) / np.linalg.norm(ref[:, :3], axis=1)
    angle = np.degrees(np.arccos(np.clip(cos, -1, 1)))
    assert np.mean(angle < 10.0) >= 0.95
    assert (ref[:, 3] < 0).any(), "the asset must contain mirrored vertices"
    np.testing.assert_array_equal(t[:, 3], ref[:, 3])


def _quad(u_sign: float = 1.0) -> tuple[np.ndarray, ...]:
    p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], np.float32)
    n = np.tile(np.float32([0, 0, 1]), (4, 1))
    # glTF UVs: v grows downwards in the image, i.e. against +y here.
    uv = np.array([[0, 1], [u_sign, 1], [0, 0], [u_sign, 0]], np.float32)
    idx = np.array([0, 1, 2, 2, 1, 3], np.uint32)
    return p, n, uv, idx


def test_axis_aligned_quad_sign_convention() -> None:
    p, n, uv, idx = _quad()
    t = generate_tangents(p, n, uv, idx)
    np.testing.assert_allclose(t, np.tile([1, 0, 0, 1], (4, 1)), atol=1e-6)
    b = t[:, 3:] * np.cross(n, t[:, :3])  # glTF: bitangent toward decreasing v = +y here
    np.testing.assert_allclose(b, np.tile([0, 1, 0], (4, 1)), atol=1e-6)


def test_mirrored_uvs_give_negative_handedness() -> None:
    p, n, uv, idx = _quad(u_sign=-1.0)
    t = generate_tangents(p, n, uv, idx)
    np.testing.assert_allclose(t, np.tile([-1, 0, 0, -1], (4, 1)), atol=1e-6)


def _assert_valid(t: np.ndarray, n: np.ndarray) -> None:
    assert np.isfinite(t).all()
    np.testing.assert_allclose(np.linalg.norm(t[:, :3], axis=1), 1.0, atol=1e-5)
    nn = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    ok = np.linalg.norm(n, axis=1) > 1e-8
    assert np.abs(np.einsum("ij,ij->i", t[ok, :3], nn[ok])).max() < 1e-5
    assert set(np.unique(t[:, 3])) <= {-1.0, 1.0}


def test_degenerate_input_never_nan() -> None:
    rng = np.random.default_rng(3)
    p = rng.normal(size=(8, 3)).astype(np.float32)
    p[3] = p[4] = p[5]  # a zero-area triangle
    p[6, 0] = np.nan
    n = rng.normal(size=(8, 3)).astype(np.float32)
    n[7] = 0.0  # no normal at all
    uv = np.zeros((8, 2), np.float32)  # all UVs equal: det = 0 everywhere
    idx = np.array([0, 1, 2, 3, 4, 5, 5, 6, 7, 0, 0, 0], np.uint32)
    for texcoords in (uv, None):
        _assert_valid(generate_tangents(p, n, texcoords, idx), n)
    _assert_valid(generate_tangents(p, n, uv, np.zeros(0, np.uint32)), n)


def test_tangent_parallel_to_normal_gets_a_perpendicular() -> None:
    n = np.array([[0, 0, 1], [1, 0, 0], [0, 0, -1], [0, -0.0, -1.0]], np.float64)
    t = orthonormal_tangent(n, n.copy())
    assert np.isfinite(t).all()
    np.testing.assert_allclose(np.einsum("ij,ij->i", t, n), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(any_perpendicular(n), axis=1), 1.0)
