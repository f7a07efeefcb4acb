# The compressed-geometry extensions at the data level (issue 18): EXT_meshopt_compression
# through meshoptimizer (every mode; the OCTAHEDRAL, QUATERNION and EXPONENTIAL filters, whose
# encoders are written here in NumPy from the extension's Appendix B; fallback buffers) and
# KHR_draco_mesh_compression through DracoPy (round trip within the quantisation's stated
# precision), EXT_mesh_gpu_instancing (instance matrices against an independent Rodrigues
# evaluation), texture sources of KHR_texture_basisu / EXT_texture_webp, and the clean errors
# of corrupt payloads and mismatched counts. Codec tests skip when their package is absent.

from __future__ import annotations

import io
import math
import struct
from pathlib import Path

import gltf_files
import numpy as np
import pytest
from gltf_files import GltfFile, grid_mesh
from PIL import Image as PILImage

from vkpbr.errors import SceneError
from vkpbr.scene import gltf_codecs
from vkpbr.scene.gltf import load_gltf
from vkpbr.scene.loader import load_scene
from vkpbr.scene.textures import decode_images
from vkpbr.scene.types import Image, expand_instances


def _need(module: str):  # noqa: ANN202
    extra = {"DracoPy": "codecs", "meshoptimizer": "bake", "opengl_basisu": "codecs"}[module]
    return pytest.importorskip(module, reason=f"{module} is not installed (extra: {extra})")


def _without(monkeypatch: pytest.MonkeyPatch, extension: str) -> None:
    """Make the loader believe the codec package of `extension` is not installed."""
    monkeypatch.setitem(gltf_codecs._MODULES, gltf_codecs.CODEC_PACKAGES[extension][0], None)


def _plain(g: dict, path: Path) -> Path:
    """The grid as an uncompressed glTF (the reference the compressed files must match)."""
    f = GltfFile()
    attrs = {k: f.accessor(g[k]) for k in ("POSITION", "NORMAL", "TANGENT", "TEXCOORD_0")}
    f.node(mesh=f.mesh(attrs, f.accessor(g["indices"])))
    return f.save(path)


# -- EXT_meshopt_compression: NumPy encoders of the Appendix B filters --------------------------


def oct_encode(n: np.ndarray, bits: int, stride: int) -> np.ndarray:
    """Unit vectors -> (N, 4) octahedral codes of `bits` bits in int8 (stride 4) / int16."""
    one = (1 << (bits - 1)) - 1
    p = n[:, :2] / np.abs(n).sum(1, keepdims=True)
    neg = n[:, 2] < 0
    folded = (1 - np.abs(p[:, ::-1])) * np.where(p >= 0, 1.0, -1.0)
    p = np.where(neg[:, None], folded, p)
    out = np.zeros((len(n), 4), np.int8 if stride == 4 else np.int16)
    out[:, :2] = np.rint(p * one)
    out[:, 2] = one
    return out


def quat_encode(q: np.ndarray, bits: int) -> np.ndarray:
    """Unit quaternions (x, y, z, w) -> (N, 4) int16 max-component codes of `bits` bits."""
    one = (1 << (bits - 1)) - 1
    big = np.argmax(np.abs(q), axis=1)
    q = q * np.where(q[np.arange(len(q)), big] < 0, -1.0, 1.0)[:, None]
    out = np.zeros((len(q), 4), np.int16)
    for j in range(3):
        comp = q[np.arange(len(q)), (big + 1 + j) % 4]
        out[:, j] = np.rint(comp * math.sqrt(2) * one)
    out[:, 3] = (one & ~3) | big
    return out


def exp_encode(v: np.ndarray, mantissa_bits: int) -> np.ndarray:
    """float32 values -> uint32 exponential codes (signed 8-bit e, signed 24-bit m)."""
    _, ex = np.frexp(v.astype(np.float64))
    e = np.where(v == 0, 0, ex - mantissa_bits).astype(np.int64)
    m = np.clip(np.rint(v / np.exp2(e.astype(np.float64))), -(1 << 23), (1 << 23) - 1)
    m = m.astype(np.int64)
    return (((e & 0xFF) << 24) | (m & 0xFFFFFF)).astype(np.uint32)


class Meshopt:
    """Writes bufferViews as EXT_meshopt_compression: the compressed bytes in buffer 0, the
    parent bufferView in a fallback buffer (a placeholder without data, or real data)."""

    def __init__(self, f: GltfFile, placeholder: bool = True) -> None:
        self.f = f
        self.placeholder = placeholder
        self.fallback = (f.add_buffer(None, fallback=True) if placeholder
                         else f.add_buffer(b""))  # fmt: skip
        f.used("EXT_meshopt_compression", required=placeholder)

    def view(self, raw: bytes, count: int, stride: int, mode: str, filt: str = "NONE",
             compressed: bytes | None = None, parent_stride: bool = True) -> int:
        mo = _need("meshoptimizer")
        if compressed is None:
            if mode == "ATTRIBUTES":
                compressed = mo.encode_vertex_buffer(
                    np.frombuffer(raw, np.uint8).reshape(count, stride), count, stride)
            elif mode == "TRIANGLES":
                compressed = mo.encode_index_buffer(
                    np.frombuffer(raw, "<u2" if stride == 2 else "<u4"), count)
            else:
                compressed = mo.encode_index_sequence(
                    np.frombuffer(raw, "<u2" if stride == 2 else "<u4"), count)
        offset = self.f.append(0, bytes(compressed))
        info = {"buffer": 0, "byteOffset": offset, "byteLength": len(compressed),
                "byteStride": stride, "count": count, "mode": mode}
        if filt != "NONE":
            info["filter"] = filt
        data = raw if not self.placeholder else bytes(len(raw))  # placeholder: length only
        return self.f.view(data, stride if parent_stride and mode == "ATTRIBUTES" else None,
                           buffer=self.fallback, EXT_meshopt_compression=info)


def _meshopt_grid(g: dict, path: Path, placeholder: bool = True, index_mode: str = "TRIANGLES",
                  index_dtype: type = np.uint16) -> Path:
    f = GltfFile()
    m = Meshopt(f, placeholder)
    attrs = {}
    for key in ("POSITION", "NORMAL", "TANGENT", "TEXCOORD_0"):
        arr = np.ascontiguousarray(g[key])
        view = m.view(arr.tobytes(), len(arr), arr.shape[1] * 4, "ATTRIBUTES")
        attrs[key] = f.accessor(None, view, ctype=5126, ncomp=arr.shape[1], count=len(arr))
    idx = g["indices"].astype(index_dtype)
    iview = m.view(idx.tobytes(), len(idx), idx.itemsize, index_mode)
    ind = f.accessor(None, iview, ctype=5123 if index_dtype == np.uint16 else 5125, ncomp=1,
                     count=len(idx))
    f.node(mesh=f.mesh(attrs, ind))
    return f.save(path)


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
@pytest.mark.parametrize(("index_mode", "index_dtype"),
                         [("TRIANGLES", np.uint16), ("TRIANGLES", np.uint32),
                          ("INDICES", np.uint16), ("INDICES", np.uint32)])  # fmt: skip
def test_meshopt_lossless_modes(tmp_path: Path, suffix: str, index_mode: str,
                                index_dtype: type) -> None:
    """Without filters the codec is lossless: the mesh equals the uncompressed file's (the
    TRIANGLES codec may rotate a triangle's corners, keeping its winding: compared rotated so
    that each starts at its smallest index)."""
    _need("meshoptimizer")
    g = grid_mesh(7)
    want = load_gltf(_plain(g, tmp_path / "plain.glb")).meshes[0]
    got = load_gltf(_meshopt_grid(g, tmp_path / f"m{suffix}", True, index_mode,
                                  index_dtype)).meshes[0]
    for name in ("positions", "normals", "tangents", "texcoords"):
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)
    np.testing.assert_array_equal(_canonical(got.indices), _canonical(want.indices))
    if index_mode == "INDICES":  # the sequence codec keeps the exact order
        np.testing.assert_array_equal(got.indices, want.indices)


def _canonical(indices: np.ndarray) -> np.ndarray:
    """Triangles rotated to start at their smallest corner (winding kept)."""
    tri = indices.reshape(-1, 3)
    k = np.argmin(tri, axis=1)
    return np.stack([tri[np.arange(len(tri)), (k + j) % 3] for j in range(3)], 1)


def test_meshopt_fallback_buffer_without_package(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """A loader without meshoptimizer reads the fallback bufferViews (real data); a file whose
    fallback is a placeholder is a clear error naming the package."""
    _need("meshoptimizer")
    g = grid_mesh(5)
    want = load_gltf(_plain(g, tmp_path / "plain.glb")).meshes[0]
    with_fallback = _meshopt_grid(g, tmp_path / "fb.gltf", placeholder=False)
    placeholder = _meshopt_grid(g, tmp_path / "ph.gltf", placeholder=True)
    np.testing.assert_array_equal(load_gltf(with_fallback).meshes[0].positions, want.positions)
    _without(monkeypatch, "EXT_meshopt_compression")
    got = load_gltf(with_fallback).meshes[0]
    np.testing.assert_array_equal(got.positions, want.positions)
    np.testing.assert_array_equal(_canonical(got.indices), _canonical(want.indices))
    with pytest.raises(SceneError, match=r"ph\.gltf.*requires EXT_meshopt_compression.*"
                                         r"meshoptimizer"):
        load_gltf(placeholder)
    doc_not_required = GltfFile()
    m = Meshopt(doc_not_required, placeholder=True)
    doc_not_required.doc.pop("extensionsRequired")
    pos = g["POSITION"]
    view = m.view(pos.tobytes(), len(pos), 12, "ATTRIBUTES", compressed=b"\xa0" + bytes(40))
    doc_not_required.node(mesh=doc_not_required.mesh({"POSITION": doc_not_required.accessor(
        None, view, ctype=5126, ncomp=3, count=len(pos))}))
    with pytest.raises(SceneError, match="without a fallback.*meshoptimizer"):
        load_gltf(doc_not_required.save(tmp_path / "nr.gltf"))


@pytest.mark.parametrize(("bits", "stride"), [(8, 4), (6, 4), (12, 8), (16, 8)])
def test_meshopt_octahedral_normals(tmp_path: Path, bits: int, stride: int) -> None:
    """NORMAL as normalized byte/short through the OCTAHEDRAL filter: within the precision of
    K-bit octahedral codes (a code step is 1 / (2^(K-1) - 1) of the octahedron's half-width:
    the angle error stays under 4 steps, plus the output's own rounding), and exactly what
    Appendix B's decode formula gives, to the 1-unit rounding the extension allows."""
    _need("meshoptimizer")
    g = grid_mesh(6, seed=3)
    n = g["NORMAL"].astype(np.float64)
    codes = oct_encode(n, bits, stride)
    f = GltfFile()
    m = Meshopt(f)
    view = m.view(codes.tobytes(), len(codes), stride, "ATTRIBUTES", "OCTAHEDRAL")
    ctype = 5120 if stride == 4 else 5122
    nrm = f.accessor(None, view, ctype=ctype, ncomp=3, count=len(codes), normalized=True)
    f.node(mesh=f.mesh({"POSITION": f.accessor(g["POSITION"]), "NORMAL": nrm},
                       f.accessor(g["indices"])))
    got = load_gltf(f.save(tmp_path / "oct.glb")).meshes[0].normals.astype(np.float64)
    # Appendix B, in NumPy
    one = codes[:, 2].astype(np.float64)
    x, y = codes[:, 0] / one, codes[:, 1] / one
    z = 1 - np.abs(x) - np.abs(y)
    t = np.minimum(z, 0)
    x, y = x - np.copysign(t, x), y - np.copysign(t, y)
    v = np.stack([x, y, z], 1)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    top = 127 if stride == 4 else 32767
    np.testing.assert_allclose(got, np.rint(v * top) / top, atol=1.01 / top)
    angle = _angle(got, n)
    assert angle.max() < 4 / ((1 << (bits - 1)) - 1) + 2 / top
    assert angle.max() > 0  # the codes did lose precision: the filter ran


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle between rows, by atan2 (arccos of a dot product near 1 is noise-dominated)."""
    a, b = a.astype(np.float64), b.astype(np.float64)
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), (a * b).sum(1))


def test_meshopt_exponential_positions(tmp_path: Path) -> None:
    _need("meshoptimizer")
    g = grid_mesh(6)
    p = g["POSITION"] * np.float32(37.5)
    codes = exp_encode(p.reshape(-1), 15).reshape(p.shape)
    f = GltfFile()
    m = Meshopt(f)
    view = m.view(codes.tobytes(), len(codes), 12, "ATTRIBUTES", "EXPONENTIAL")
    f.node(mesh=f.mesh({"POSITION": f.accessor(None, view, ctype=5126, ncomp=3, count=len(p)),
                        "NORMAL": f.accessor(g["NORMAL"])}, f.accessor(g["indices"])))
    got = load_gltf(f.save(tmp_path / "exp.gltf")).meshes[0].positions
    e = (codes.view(np.int32) >> 24).astype(np.float64)
    mant = ((codes.view(np.int32) << 8) >> 8).astype(np.float64)
    np.testing.assert_array_equal(got, (np.exp2(e) * mant).astype(np.float32))  # Appendix B
    np.testing.assert_allclose(got, p, rtol=2.0 ** -15, atol=1e-30)


def _axis_angle_quats(k: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(k, 4) unit quaternions (x, y, z, w) and their rotation matrices by Rodrigues' formula
    (an evaluation independent of the loader's quaternion -> matrix)."""
    rng = np.random.default_rng(seed)
    axis = rng.standard_normal((k, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    theta = rng.uniform(-math.pi, math.pi, k)
    q = np.concatenate([axis * np.sin(theta / 2)[:, None], np.cos(theta / 2)[:, None]], 1)
    mats = []
    for a, th in zip(axis, theta, strict=True):
        kx = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
        mats.append(np.eye(3) + math.sin(th) * kx + (1 - math.cos(th)) * kx @ kx)
    return q, np.array(mats)


def _instanced_file(k: int, seed: int, rotation: str = "float") -> tuple[GltfFile, np.ndarray]:
    """A triangle mesh (two primitives) on a node with translation (2, 0, 0) and k instances;
    returns the file and the expected (k, 4, 4) instance matrices T * R * S."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(-5, 5, (k, 3)).astype(np.float32)
    s = rng.uniform(0.5, 2, (k, 3)).astype(np.float32)
    q, rot = _axis_angle_quats(k, seed)
    want = np.zeros((k, 4, 4))
    want[:, :3, :3] = rot * s[:, None, :]
    want[:, :3, 3] = t
    want[:, 3, 3] = 1
    f = GltfFile()
    f.used("EXT_mesh_gpu_instancing", required=True)
    g = grid_mesh(3)
    prim = {"attributes": {"POSITION": f.accessor(g["POSITION"])},
            "indices": f.accessor(g["indices"])}
    f.doc["meshes"].append({"primitives": [prim, dict(prim)]})
    attrs = {"TRANSLATION": f.accessor(t), "SCALE": f.accessor(s)}
    if rotation == "float":
        attrs["ROTATION"] = f.accessor(q.astype(np.float32))
    elif rotation == "short":
        attrs["ROTATION"] = f.accessor(np.rint(q * 32767).astype(np.int16), normalized=True)
    else:  # meshopt QUATERNION filter, 12-bit codes
        f.used("KHR_mesh_quantization")
        view = Meshopt(f).view(quat_encode(q, 12).tobytes(), k, 8, "ATTRIBUTES", "QUATERNION")
        attrs["ROTATION"] = f.accessor(None, view, ctype=5122, ncomp=4, count=k, normalized=True)
    f.node(mesh=0, translation=[2.0, 0.0, 0.0],
           extensions={"EXT_mesh_gpu_instancing": {"attributes": attrs}})
    return f, want


@pytest.mark.parametrize(("rotation", "atol"), [("float", 1e-5), ("short", 2e-4),
                                                ("meshopt", 3e-3)])  # fmt: skip
def test_gpu_instancing_matrices(tmp_path: Path, rotation: str, atol: float) -> None:
    if rotation == "meshopt":
        _need("meshoptimizer")
    k = 9
    f, want = _instanced_file(k, 11, rotation)
    scene = load_gltf(f.save(tmp_path / "inst.glb"))
    assert len(scene.meshes) == 2  # the mesh is stored once, not per instance
    assert len(scene.nodes) == 2
    for node in scene.nodes:
        assert node.instances.shape == (k, 4, 4)
        assert node.instances.dtype == np.float32
        np.testing.assert_allclose(node.instances, want, atol=atol * 2)  # S up to 2
        world = node.instance_matrices()
        np.testing.assert_allclose(world[:, :3, 3], want[:, :3, 3] + [2, 0, 0], atol=atol * 5)
    one = scene.meshes[0].triangle_count
    assert scene.triangle_count == 2 * k * one
    expanded = expand_instances(scene.nodes)
    assert len(expanded) == 2 * k
    assert all(n.instances is None for n in expanded)
    # bounds: every instance's vertices, transformed independently
    pts = []
    for node in scene.nodes:
        p = scene.meshes[node.mesh].positions.astype(np.float64)
        for m in want:
            pts.append(p @ m[:3, :3].T + m[:3, 3] + [2, 0, 0])
    pts = np.concatenate(pts)
    lo, hi = scene.bounds()
    assert np.all(lo <= pts.min(0) + 1e-3)
    assert np.all(hi >= pts.max(0) - 1e-3)


def test_gpu_instancing_bad_counts(tmp_path: Path) -> None:
    f, _ = _instanced_file(4, 1)
    attrs = f.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]
    attrs["SCALE"] = f.accessor(np.ones((3, 3), np.float32))
    with pytest.raises(SceneError, match=r"bad\.glb.*EXT_mesh_gpu_instancing.*counts differ"):
        load_gltf(f.save(tmp_path / "bad.glb"))
    attrs["SCALE"] = f.accessor(np.ones((4, 2), np.float32))
    with pytest.raises(SceneError, match="SCALE: 2 components"):
        load_gltf(f.save(tmp_path / "bad.glb"))


# -- KHR_draco_mesh_compression ----------------------------------------------------------------

DRACO_TYPES = {0: "POSITION", 1: "NORMAL", 3: "TEXCOORD_0"}  # Draco GeometryAttribute::Type


def _draco_file(g: dict, path: Path, bits: tuple[int, int, int] = (14, 10, 12),
                preserve_order: bool = True, fallback: bool = False,
                payload: bytes | None = None) -> tuple[Path, bytes]:
    """The grid as a KHR_draco_mesh_compression glTF (position, normal, texcoord bits)."""
    draco = _need("DracoPy")
    if payload is None:
        payload = draco.encode(g["POSITION"], g["indices"].reshape(-1, 3),
                               quantization_bits=bits[0], normal_quantization_bits=bits[1],
                               tex_coord_quantization_bits=bits[2],
                               normals=g["NORMAL"].astype(np.float64),
                               tex_coord=g["TEXCOORD_0"].astype(np.float64),
                               preserve_order=preserve_order,
                               compression_level=7)
        decoded = draco.decode(payload)
        ids = {DRACO_TYPES[a["attribute_type"]]: a["unique_id"] for a in decoded.attributes}
        n = len(decoded.points)
    else:
        ids, n = {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, len(g["POSITION"])
    f = GltfFile()
    f.used("KHR_draco_mesh_compression", required=not fallback)
    view = f.view(bytes(payload))
    attrs = {}
    for key, width in (("POSITION", 3), ("NORMAL", 3), ("TEXCOORD_0", 2)):
        if fallback:
            attrs[key] = f.accessor(g[key])
        else:
            attrs[key] = f.accessor(None, ctype=5126, ncomp=width, count=n)
    ind = (f.accessor(g["indices"]) if fallback
           else f.accessor(None, ctype=5125, ncomp=1, count=len(g["indices"])))  # fmt: skip
    f.node(mesh=f.mesh(attrs, ind, extensions={"KHR_draco_mesh_compression": {
        "bufferView": view, "attributes": ids}}))
    return f.save(path), payload


def test_draco_round_trip_within_quantisation(tmp_path: Path) -> None:
    """Decoded attributes equal the originals within Draco's stated precision: positions and
    texcoords to half a quantisation step of their range (plus float rounding), normals
    (octahedral, `bits` bits) to an angle of 4 code steps, as for meshopt's filter."""
    g = grid_mesh(8, seed=5)
    bits = (14, 10, 12)
    path, _ = _draco_file(g, tmp_path / "d.glb", bits)
    mesh = load_gltf(path).meshes[0]
    np.testing.assert_array_equal(mesh.indices, g["indices"])  # preserve_order
    prange = float(np.ptp(g["POSITION"], axis=0).max())
    np.testing.assert_allclose(mesh.positions, g["POSITION"],
                               atol=0.5 * prange / (2 ** bits[0] - 1) * 1.01 + 1e-6)
    urange = float(np.ptp(g["TEXCOORD_0"], axis=0).max())
    np.testing.assert_allclose(mesh.texcoords, g["TEXCOORD_0"],
                               atol=0.5 * urange / (2 ** bits[2] - 1) * 1.01 + 1e-6)
    assert _angle(mesh.normals, g["NORMAL"]).max() < 4 / ((1 << (bits[1] - 1)) - 1)
    # ...and the errors are not zero: the data did go through the quantiser
    assert np.abs(mesh.positions - g["POSITION"]).max() > 0


def test_draco_fallback_without_package(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    g = grid_mesh(5)
    with_fallback, _ = _draco_file(g, tmp_path / "fb.glb", fallback=True)
    required, _ = _draco_file(g, tmp_path / "req.glb")
    _without(monkeypatch, "KHR_draco_mesh_compression")
    got = load_gltf(with_fallback).meshes[0]
    np.testing.assert_array_equal(got.positions, g["POSITION"])  # the uncompressed data
    np.testing.assert_array_equal(got.indices, g["indices"])
    with pytest.raises(SceneError, match=r"req\.glb.*KHR_draco_mesh_compression.*DracoPy"):
        load_gltf(required)


def _edit_draco(path: Path, edit) -> Path:  # noqa: ANN001
    """Rewrite the JSON of a .glb written by _draco_file (the BIN chunk kept)."""
    import json
    import struct

    raw = path.read_bytes()
    (jlen,) = struct.unpack_from("<I", raw, 12)
    doc = json.loads(raw[20:20 + jlen])
    edit(doc)
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    rest = raw[20 + jlen:]
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + rest
    out = path.with_name("edited.glb")
    out.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)
    return out


@pytest.mark.parametrize(("edit", "match"), [
    (lambda d: d["accessors"][0].update(count=5), "POSITION accessor count 5"),
    (lambda d: d["accessors"][3].update(count=9), "indices accessor count 9"),
    (lambda d: d["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"][
        "attributes"].update(NORMAL=17), "attribute id 17"),
    (lambda d: d["meshes"][0]["primitives"][0].update(mode=5), "mode 5"),
    (lambda d: d["bufferViews"][0].update(byteLength=40), "corrupt KHR_draco_mesh_compression"),
])  # fmt: skip
def test_draco_bad_input(tmp_path: Path, edit, match: str) -> None:  # noqa: ANN001
    path, _ = _draco_file(grid_mesh(4), tmp_path / "d.glb")
    bad = _edit_draco(path, edit)
    with pytest.raises(SceneError, match=match) as info:
        load_scene(bad)
    assert "edited.glb" in str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("payload", [b"", b"DRACO\x02\x02\x01\x01\x00\x00" + bytes(30),
                                     bytes(range(256)) * 4])  # fmt: skip
def test_draco_corrupt_payloads(tmp_path: Path, payload: bytes) -> None:
    _need("DracoPy")
    path, _ = _draco_file(grid_mesh(4), tmp_path / "c.glb", payload=payload)
    with pytest.raises(SceneError, match=r"c\.glb.*corrupt KHR_draco_mesh_compression"):
        load_scene(path)


# -- EXT_meshopt_compression: bad input -------------------------------------------------------


@pytest.mark.parametrize(("change", "match"), [
    ({"count": 999}, "count 999 x byteStride 12"),
    ({"byteStride": 6, "count": 72}, "multiple of 4"),
    ({"mode": "SPIRAL"}, "unknown EXT_meshopt_compression mode"),
    ({"filter": "WAVELET"}, "unknown EXT_meshopt_compression filter"),
    ({"filter": "QUATERNION"}, "QUATERNION filter needs byteStride 8"),
    ({"byteLength": 7}, "corrupt EXT_meshopt_compression"),
    ({"byteLength": 10 ** 9}, "exceed their buffer"),
    ({"count": -1}, "count -1 is invalid"),
])  # fmt: skip
def test_meshopt_bad_input(tmp_path: Path, change: dict, match: str) -> None:
    _need("meshoptimizer")
    g = grid_mesh(6)
    path = _meshopt_grid(g, tmp_path / "m.gltf")
    import json

    doc = json.loads(path.read_text())
    doc["bufferViews"][0]["extensions"]["EXT_meshopt_compression"].update(change)
    path.write_text(json.dumps(doc))
    with pytest.raises(SceneError, match=match) as info:
        load_scene(path)
    assert "m.gltf" in str(info.value)


def test_meshopt_random_payloads_are_clean_errors(tmp_path: Path) -> None:
    """Corrupt compressed bytes (random, truncated, bit-flipped) never crash the decoder."""
    _need("meshoptimizer")
    import json

    g = grid_mesh(6)
    path = _meshopt_grid(g, tmp_path / "m.gltf")
    good = json.loads(path.read_text())
    rng = np.random.default_rng(0)
    for trial in range(40):
        doc = json.loads(json.dumps(good))
        info = doc["bufferViews"][trial % 5]["extensions"]["EXT_meshopt_compression"]
        import base64

        uri = doc["buffers"][0]["uri"]
        head, b64 = uri.split(",", 1)
        data = bytearray(base64.b64decode(b64))
        lo, n = info["byteOffset"], info["byteLength"]
        kind = trial % 3
        if kind == 0:
            data[lo:lo + n] = rng.integers(0, 256, n, np.uint8).tobytes()
        elif kind == 1:
            info["byteLength"] = int(rng.integers(0, n))
        else:
            k = lo + int(rng.integers(0, n))
            data[k] ^= 1 << int(rng.integers(0, 8))
        doc["buffers"][0]["uri"] = head + "," + base64.b64encode(bytes(data)).decode()
        path.write_text(json.dumps(doc))
        try:
            load_scene(path)  # a bit flip may still decode: then it must load
        except SceneError as exc:
            assert "m.gltf" in str(exc)


# -- texture sources: EXT_texture_webp, KHR_texture_basisu --------------------------------------


def _png(color: tuple[int, ...], fmt: str = "PNG", **kw: object) -> bytes:
    buf = io.BytesIO()
    PILImage.new("RGBA", (8, 4), color).save(buf, fmt, **kw)
    return buf.getvalue()


def _textured(tmp_path: Path, exts: dict, images: list[bytes], source: int | None = 0,
              required: tuple[str, ...] = ()) -> Path:
    f = GltfFile()
    for name in exts:
        f.used(name, required=name in required)
    f.doc["images"] = [{"bufferView": f.view(data), "mimeType": mime}
                       for data, mime in images]  # type: ignore[misc]
    tex: dict = {"extensions": exts}
    if source is not None:
        tex["source"] = source
    f.doc["textures"] = [tex]
    f.doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
    g = grid_mesh(3)
    f.node(mesh=f.mesh({"POSITION": f.accessor(g["POSITION"]),
                        "TEXCOORD_0": f.accessor(g["TEXCOORD_0"])}, f.accessor(g["indices"]),
                       material=0))
    return f.save(tmp_path / "tex.glb")


def test_webp_source_preferred_and_decoded(tmp_path: Path) -> None:
    rng = np.random.default_rng(2)
    pixels = rng.integers(0, 256, (4, 8, 4), np.uint8)
    buf = io.BytesIO()
    PILImage.fromarray(pixels, "RGBA").save(buf, "WEBP", lossless=True, exact=True)
    images = [(_png((255, 0, 0, 255)), "image/png"), (buf.getvalue(), "image/webp")]
    scene = load_gltf(_textured(tmp_path, {"EXT_texture_webp": {"source": 1}}, images))
    ref = scene.materials[0].base_color_texture
    assert ref.image == 1
    np.testing.assert_array_equal(decode_images(scene)[1], pixels)  # lossless WebP, exact
    # without a core source at all (the extension required)
    scene = load_gltf(_textured(tmp_path, {"EXT_texture_webp": {"source": 1}}, images,
                                source=None, required=("EXT_texture_webp",)))
    assert scene.materials[0].base_color_texture.image == 1


def test_basisu_without_decoder_keeps_fallback(tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    if "KHR_texture_basisu" not in gltf_codecs.CODEC_PACKAGES:
        pytest.skip("no KTX2 decoder is wired in this build")
    _without(monkeypatch, "KHR_texture_basisu")
    images = [(_png((0, 255, 0, 255)), "image/png"), (b"\xabKTX 20\xbb\r\n\x1a\n", "image/ktx2")]
    scene = load_gltf(_textured(tmp_path, {"KHR_texture_basisu": {"source": 1}}, images))
    assert scene.materials[0].base_color_texture.image == 0
    with pytest.raises(SceneError, match="requires KHR_texture_basisu"):
        load_gltf(_textured(tmp_path, {"KHR_texture_basisu": {"source": 1}}, images,
                            required=("KHR_texture_basisu",)))


def test_unhonourable_required_extension_is_named(tmp_path: Path) -> None:
    path = _textured(tmp_path, {"EXT_lights_image_based": {}},
                     [(_png((1, 2, 3, 255)), "image/png")], required=("EXT_lights_image_based",))
    with pytest.raises(SceneError, match=r"tex\.glb.*unsupported extension.*EXT_lights_image_based"):
        load_scene(path)


def ktx2_bytes(pixels: np.ndarray, uastc: bool = True, mipmaps: bool = False) -> bytes:
    """RGBA8 pixels -> a Basis Universal KTX2 (gltf_files.ktx2_bytes), the decoder and the
    encoder both needed (skipped, naming the extra, without either)."""
    _need("opengl_basisu")
    pytest.importorskip("alktx2", reason="alktx2 is not installed (extra: test)")
    return gltf_files.ktx2_bytes(pixels, uastc, mipmaps)


def smooth_pixels(w: int = 32, h: int = 16) -> np.ndarray:
    y, x = np.mgrid[0:h, 0:w]
    px = np.stack([x * 255 / (w - 1), y * 255 / (h - 1), 128 + 60 * np.sin(x / 3.0),
                   np.full_like(x, 255)], -1)
    return np.rint(px).astype(np.uint8)


def test_basisu_source_transcoded(tmp_path: Path) -> None:
    """KHR_texture_basisu picks the KTX2 image over the PNG fallback; UASTC transcodes to
    RGBA8 within its precision (smooth content: mean error under 2, max under 16 levels)."""
    px = smooth_pixels()
    images = [(_png((255, 0, 0, 255)), "image/png"), (ktx2_bytes(px), "image/ktx2")]
    scene = load_gltf(_textured(tmp_path, {"KHR_texture_basisu": {"source": 1}}, images))
    assert scene.materials[0].base_color_texture.image == 1
    got = decode_images(scene)[1].astype(np.int64)
    assert got.shape == px.shape
    err = np.abs(got - px)
    assert err.mean() < 2.0
    assert err.max() < 16
    assert decode_images(scene.images, max_size=8)[1].shape == (4, 8, 4)


def test_corrupt_ktx2_is_the_missing_texture_fallback(tmp_path: Path,
                                                      caplog: pytest.LogCaptureFixture) -> None:
    good = ktx2_bytes(smooth_pixels(8, 8), mipmaps=True)
    for bad in (good[:70], good[:12] + bytes(68), good[:-20], good[:100] + bytes(len(good) - 100)):
        images = [(_png((1, 2, 3, 255)), "image/png"), (bad, "image/ktx2")]
        scene = load_gltf(_textured(tmp_path, {"KHR_texture_basisu": {"source": 1}}, images))
        for blocks in (None, "bc7"):  # as a GPU with BC7 decodes them too
            levels: dict[int, list[np.ndarray]] = {}
            caplog.clear()
            with caplog.at_level("WARNING"):
                out = decode_images(scene, blocks=blocks, block_levels=levels)
            assert out[1] is None  # the renderer binds its default in its place
            assert levels == {}
            assert "cannot be decoded" in caplog.text


def test_ktx2_with_mips_is_also_bc7_blocks() -> None:
    """decode_images(blocks="bc7"): a KTX2 holding its mip chain gets every level as BC7 blocks
    (16 bytes a 4x4 block, odd sizes rounded up); one without mips, or downscaled, gets none
    (the GPU cannot make mips of blocks). What the blocks look like is the GPU test's
    (tests/gpu/test_gltf_codec_renders.py: sampled, they render as the PNG)."""
    px = smooth_pixels(40, 20)  # not multiples of 4 below level 0
    images = [Image("mips", data=ktx2_bytes(px, mipmaps=True)), Image("one", data=ktx2_bytes(px))]
    levels: dict[int, list[np.ndarray]] = {}
    out = decode_images(images, blocks="bc7", block_levels=levels)
    assert [o.shape for o in out] == [(20, 40, 4)] * 2
    assert list(levels) == [0]
    w, h = 40, 20
    shapes = [(-(-max(h >> k, 1) // 4), -(-max(w >> k, 1) // 4), 16) for k in range(6)]
    assert [lv.shape for lv in levels[0]] == shapes
    assert all(lv.dtype == np.uint8 and lv.any() for lv in levels[0])
    small: dict[int, list[np.ndarray]] = {}
    assert decode_images(images, max_size=16, blocks="bc7", block_levels=small)[0].shape == (8, 16, 4)
    assert small == {}


def plain_ktx2(pixels: np.ndarray, vk_format: int = 43, scheme: int = 0) -> bytes:
    """An uncompressed KTX2 (KTX 2.0 spec 3.1: the 80-byte header, one level's index entry,
    then the texels), built by hand: what a tool writes for raw RGBA8 (vkFormat 43 = SRGB)."""
    h, w = pixels.shape[:2]
    data = np.ascontiguousarray(pixels, np.uint8).tobytes()
    header = gltf_codecs.KTX2_MAGIC + struct.pack("<9I", vk_format, 1, w, h, 0, 0, 1, 1, scheme)
    index = struct.pack("<4I2Q", 0, 0, 0, 0, 0, 0)
    level = struct.pack("<3Q", 104, len(data), len(data))
    return header + index + level + data


def test_etc1s_and_plain_rgba8_ktx2() -> None:
    """ETC1S (the lossier Basis codec: smooth content within 12 levels on average) and an
    uncompressed RGBA8 KTX2 (exact) decode; other raw formats and supercompressed raw texels
    are one clear error each."""
    px = smooth_pixels()
    etc1s = gltf_codecs.decode_ktx2(ktx2_bytes(px, uastc=False)).astype(np.int64)
    assert etc1s.shape == px.shape and np.abs(etc1s - px).mean() < 12
    assert np.array_equal(gltf_codecs.decode_ktx2(plain_ktx2(px)), px)
    assert np.array_equal(gltf_codecs.decode_ktx2(plain_ktx2(px, vk_format=37)), px)
    for bad, match in ((plain_ktx2(px, vk_format=109), "vkFormat 109"),
                       (plain_ktx2(px, scheme=2), "supercompression 2"),
                       (plain_ktx2(px)[:-10], "shorter than its header")):
        with pytest.raises(ValueError, match=match):
            gltf_codecs.decode_ktx2(bad)
