# A small glTF writer for tests of the loader's extensions (issue 18): several buffers (a GLB
# BIN chunk, data-URI buffers, placeholder buffers without a uri), bufferViews with extension
# objects, accessors of any component type with padded strides. No pygltflib: the JSON is
# written as the specification shows it, so the loader is checked against the spec's layout.

from __future__ import annotations

import base64
import json
import struct
from pathlib import Path

import numpy as np

CTYPE = {np.dtype("i1"): 5120, np.dtype("u1"): 5121, np.dtype("i2"): 5122,
         np.dtype("u2"): 5123, np.dtype("u4"): 5125, np.dtype("f4"): 5126}  # fmt: skip
ATYPE = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}


def padded_rows(arr: np.ndarray) -> tuple[bytes, int]:
    """(bytes, byteStride): rows of `arr` padded to 4-byte multiples, as glTF requires for
    vertex attributes (a VEC3 of bytes takes 4)."""
    arr = np.ascontiguousarray(arr)
    row = arr.dtype.itemsize * arr.shape[1]
    stride = row + (-row % 4)
    out = np.zeros((len(arr), stride), np.uint8)
    out[:, :row] = arr.view(np.uint8).reshape(len(arr), row)
    return out.tobytes(), stride


class GltfFile:
    """A glTF document under construction; buffer 0 is the GLB BIN chunk (or a data URI)."""

    def __init__(self) -> None:
        self.buffers: list[bytearray | None] = [bytearray()]  # None: a placeholder, no data
        self.buffer_ext: dict[int, dict] = {}
        self.placeholder_lengths: dict[int, int] = {}
        self.doc: dict = {"asset": {"version": "2.0"}, "bufferViews": [], "accessors": [],
                          "meshes": [], "nodes": [], "scenes": [{"nodes": []}]}  # fmt: skip

    def add_buffer(self, data: bytes | None = None, length: int = 0, **ext: object) -> int:
        self.buffers.append(None if data is None else bytearray(data))
        i = len(self.buffers) - 1
        if data is None:
            self.placeholder_lengths[i] = length
        if ext:
            self.buffer_ext[i] = ext
        return i

    def append(self, buffer: int, data: bytes) -> int:
        """Append to a data buffer, 4-byte aligned; returns the byte offset."""
        buf = self.buffers[buffer]
        assert buf is not None
        buf += b"\0" * (-len(buf) % 4)
        offset = len(buf)
        buf += data
        return offset

    def view(self, data: bytes, stride: int | None = None, buffer: int = 0,
             **extensions: object) -> int:
        if self.buffers[buffer] is None:  # a placeholder: only the declared range
            offset = self.placeholder_lengths[buffer]
            self.placeholder_lengths[buffer] += len(data) + (-len(data) % 4)
        else:
            offset = self.append(buffer, data)
        v: dict = {"buffer": buffer, "byteOffset": offset, "byteLength": len(data)}
        if stride:
            v["byteStride"] = stride
        if extensions:
            v["extensions"] = extensions
        self.doc["bufferViews"].append(v)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, arr: np.ndarray | None, view: int | None = None, *,
                 ctype: int | None = None, ncomp: int | None = None, count: int | None = None,
                 padded: bool = True, **extra: object) -> int:
        """An accessor of `arr` (its dtype and width), in a new view unless `view` is given;
        arr None (with ctype, ncomp, count): an accessor without data (Draco)."""
        if arr is not None:
            arr = np.asarray(arr)
            arr = arr.reshape(len(arr), -1)
            ctype, ncomp, count = CTYPE[arr.dtype], arr.shape[1], len(arr)
            if view is None:
                data, stride = padded_rows(arr) if padded else (arr.tobytes(), 0)
                view = self.view(data, stride if stride != arr.dtype.itemsize * ncomp else None)
        acc = {"componentType": ctype, "count": count, "type": ATYPE[ncomp], **extra}
        if view is not None:
            acc["bufferView"] = view
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def mesh(self, attributes: dict, indices: int | None = None, **prim: object) -> int:
        p = {"attributes": attributes, **prim}
        if indices is not None:
            p["indices"] = indices
        self.doc["meshes"].append({"primitives": [p]})
        return len(self.doc["meshes"]) - 1

    def node(self, root: bool = True, **fields: object) -> int:
        self.doc["nodes"].append(fields)
        if root:
            self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)
        return len(self.doc["nodes"]) - 1

    def used(self, name: str, required: bool = False) -> None:
        self.doc.setdefault("extensionsUsed", []).append(name)
        if required:
            self.doc.setdefault("extensionsRequired", []).append(name)

    def save(self, path: Path) -> Path:
        """A .glb (buffer 0 in the BIN chunk) or a .gltf (every buffer a data URI)."""
        doc = json.loads(json.dumps(self.doc))
        doc["buffers"] = []
        for i, buf in enumerate(self.buffers):
            entry: dict = {"byteLength": self.placeholder_lengths[i] if buf is None else len(buf)}
            if buf is not None and (i or path.suffix != ".glb"):
                entry["uri"] = ("data:application/octet-stream;base64,"
                                + base64.b64encode(bytes(buf)).decode())
            if i in self.buffer_ext:
                entry["extensions"] = self.buffer_ext[i]
            doc["buffers"].append(entry)
        text = json.dumps(doc).encode()
        if path.suffix != ".glb":
            path.write_bytes(text)
            return path
        text += b" " * (-len(text) % 4)
        data = bytes(self.buffers[0] or b"")
        data += b"\0" * (-len(data) % 4)
        body = struct.pack("<II", len(text), 0x4E4F534A) + text
        body += struct.pack("<II", len(data), 0x004E4942) + data
        path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)
        return path


def grid_mesh(n: int = 6, seed: int = 0) -> dict[str, np.ndarray]:
    """A bumpy (n x n)-vertex height field in [-1, 1]^2 facing +Z: positions, unit normals,
    unit tangents with w = +-1, texcoords in [0, 1], uint32 indices."""
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    x, y = u * 2 - 1, v * 2 - 1
    z = 0.15 * np.sin(3 * x) * np.cos(2 * y) + 0.02 * rng.standard_normal(x.shape)
    pos = np.stack([x, y, z], -1).reshape(-1, 3).astype(np.float32)
    nrm = rng.standard_normal((n * n, 3)) * 0.3 + [0, 0, 1]
    nrm = (nrm / np.linalg.norm(nrm, axis=1, keepdims=True)).astype(np.float32)
    tan = np.cross(nrm, [0, 1, 0])
    tan /= np.linalg.norm(tan, axis=1, keepdims=True)
    w = np.where(rng.random(n * n) < 0.5, -1.0, 1.0)
    tangents = np.concatenate([tan, w[:, None]], 1).astype(np.float32)
    uv = np.stack([u, 1 - v], -1).reshape(-1, 2).astype(np.float32)
    quads = [(r * n + c, r * n + c + 1, (r + 1) * n + c + 1, (r + 1) * n + c)
             for r in range(n - 1) for c in range(n - 1)]
    idx = np.array([[a, b, c, a, c, d] for a, b, c, d in quads], np.uint32).reshape(-1)
    return {"POSITION": pos, "NORMAL": nrm, "TANGENT": tangents, "TEXCOORD_0": uv,
            "indices": idx}


def ktx2_bytes(pixels: np.ndarray, uastc: bool = True, mipmaps: bool = False) -> bytes:
    """RGBA8 pixels -> a Basis Universal KTX2 (UASTC at its best quality, or ETC1S), sRGB,
    with its full mip chain when `mipmaps` (as gltf-transform and toktx write them), through
    alktx2 (basis_universal's encoder; the `test` extra). ImportError without it."""
    import alktx2

    h, w = pixels.shape[:2]
    return alktx2.encode_raw_rgba_to_ktx2(np.ascontiguousarray(pixels, np.uint8).tobytes(), w, h,
                                          True, codec="uastc" if uastc else "etc1s",
                                          quality=255, srgb=True, mipmaps=mipmaps)
