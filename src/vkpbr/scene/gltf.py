# glTF 2.0 (.gltf / .glb) -> vkpbr Scene. pygltflib parses the JSON into its dataclasses; this
# module resolves buffers (GLB BIN chunk, data: URIs, external .bin), decodes accessors with
# NumPy (every component type, normalized, byteStride, sparse), flattens the node hierarchy
# into world matrices and maps materials, samplers, cameras and KHR_lights_punctual lights.
#
# Robustness: every offset and count is checked against the real byte lengths before NumPy
# touches memory, so a corrupt file raises SceneError instead of reading garbage or allocating
# gigabytes. Non-finite positions: triangles touching them are dropped with a warning (see
# geometry.drop_nonfinite). Reference: the glTF 2.0 specification (Khronos), sections 3.6-3.9.

from __future__ import annotations

import base64
import binascii
import json
import struct
import warnings
from pathlib import Path
from urllib.parse import unquote

import numpy as np
import pygltflib

from vkpbr.errors import SceneError
from vkpbr.scene.geometry import (
    drop_nonfinite,
    ensure_normals,
    fan_triangles,
    normalize_mesh_arrays,
    strip_triangles,
)
from vkpbr.scene.gltf_scene import (
    build_materials,
    build_nodes_cameras_lights,
    check_index,
    get,
    load_images,
)
from vkpbr.scene.types import Mesh, Scene

__all__ = ["load_gltf", "SUPPORTED_EXTENSIONS"]

SUPPORTED_EXTENSIONS = frozenset(
    {
        "KHR_texture_transform",
        "KHR_lights_punctual",
        "KHR_materials_emissive_strength",
        "KHR_mesh_quantization",  # integer attributes: handled by the generic accessor decoder
    }
)
_DTYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
_NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_MODES = {0: "POINTS", 1: "LINES", 2: "LINE_LOOP", 3: "LINE_STRIP"}
# An accessor without a bufferView is zero-filled (sparse-only). Its size is not bounded by any
# byte in the file, so cap it: 64 MiB beyond whatever the file itself holds.
_ZERO_FILL_SLACK = 64 << 20


def load_gltf(path: str | Path) -> Scene:
    """Load a .gltf or .glb file.

    Parameters
    ----------
    path : the file; external buffers and images resolve relative to its folder.

    Returns
    -------
    Scene whose meshes are glTF primitives (one Mesh per primitive), nodes the instances of
    the default scene with full world matrices, images left encoded (see textures.py).

    Raises
    ------
    SceneError : naming the file, for any malformed, truncated or unsupported input.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise SceneError(path, f"cannot read: {exc.strerror or exc}") from exc
    try:
        # Overflow/NaN from hostile values is handled explicitly (drop_nonfinite, range
        # checks), so numpy must not turn it into FloatingPointError under np.seterr(raise).
        with np.errstate(all="ignore"):
            return _Loader(path, raw).load()
    except SceneError:
        raise
    except (TypeError, ValueError, KeyError, IndexError, AttributeError, OverflowError,
            RecursionError, struct.error) as exc:  # fmt: skip
        # A value of the wrong JSON type that no explicit check anticipated is still the file's
        # fault; keep the promise that users only ever see SceneError.
        raise SceneError(path, f"malformed glTF ({type(exc).__name__}: {exc})") from exc


def _parse_glb(path: Path, raw: bytes) -> tuple[bytes, memoryview | None]:
    """Split a GLB container into its JSON text and optional BIN chunk (glTF spec 4.4)."""
    if len(raw) < 20:
        raise SceneError(path, "truncated GLB header")
    _magic, version, length = struct.unpack_from("<4sII", raw, 0)
    if version != 2:
        raise SceneError(path, f"GLB version {version} is not supported (need 2)")
    if length > len(raw):
        raise SceneError(path, f"truncated GLB: header says {length} bytes, file has {len(raw)}")
    chunks: list[tuple[int, memoryview]] = []
    offset = 12
    view = memoryview(raw)[:length]
    while offset + 8 <= length:
        size, kind = struct.unpack_from("<II", raw, offset)
        if offset + 8 + size > length:
            raise SceneError(path, f"truncated GLB chunk at byte {offset}")
        chunks.append((kind, view[offset + 8 : offset + 8 + size]))
        offset += 8 + size + (-size % 4)  # chunks are 4-byte aligned
    if not chunks or chunks[0][0] != 0x4E4F534A:
        raise SceneError(path, "GLB does not start with a JSON chunk")
    bin_chunk = next((c for k, c in chunks[1:] if k == 0x004E4942), None)
    return bytes(chunks[0][1]), bin_chunk


class _Loader:
    """State of one load: the parsed document, resolved buffers and decoded-accessor cache."""

    def __init__(self, path: Path, raw: bytes) -> None:
        self.path = path
        self.folder = path.parent
        self.file_size = len(raw)
        bin_chunk = None
        text = raw
        if raw[:4] == b"glTF":
            text, bin_chunk = _parse_glb(path, raw)
        self.bin_chunk = bin_chunk
        try:
            doc = json.loads(text.decode("utf-8-sig"))
        except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
            raise SceneError(path, f"malformed JSON: {exc}") from exc
        if not isinstance(doc, dict):
            raise SceneError(path, "top-level JSON value is not an object")
        version = str(get(get(doc, "asset", {}), "version", "2.0"))
        if not version.startswith("2"):
            raise SceneError(path, f"glTF version {version} is not supported (need 2.x)")
        required = doc.get("extensionsRequired") or []
        if not isinstance(required, list):
            raise SceneError(path, "extensionsRequired is not a list")
        unsupported = [str(e) for e in required if e not in SUPPORTED_EXTENSIONS]
        if unsupported:
            raise SceneError(path, f"requires unsupported extension(s): {', '.join(unsupported)}")
        with warnings.catch_warnings():
            # dataclasses_json warns about every optional field given as null: noise, not news.
            warnings.simplefilter("ignore")
            try:
                self.gltf = pygltflib.GLTF2.from_dict(doc)
            except (TypeError, ValueError, AttributeError, KeyError, OverflowError) as exc:
                # pygltflib coerces fields to their declared types; a JSON value of the wrong
                # kind (a list for a count, NaN for an index) fails here.
                raise SceneError(path, f"invalid glTF structure ({exc})") from exc
        self.doc = doc
        self.buffers: dict[int, memoryview] = {}
        self.accessors: dict[int, np.ndarray] = {}

    def load(self) -> Scene:
        """Build the Scene (meshes on demand, only for nodes of the displayed scene)."""
        scene = Scene(name=self.path.stem, source=self.path)
        scene.images = load_images(self)
        scene.materials = build_materials(self, len(scene.images))
        build_nodes_cameras_lights(self, scene)
        return scene

    # -- buffers ------------------------------------------------------------------------------

    def buffer(self, index: object) -> memoryview:
        """Bytes of buffer `index`, checked against its declared byteLength."""
        buffers = self.gltf.buffers or []
        i = check_index(self.path, index, len(buffers), "buffer")
        if i in self.buffers:
            return self.buffers[i]
        buf = buffers[i]
        uri = get(buf, "uri")
        if uri is None:
            if self.bin_chunk is None or i != 0:
                raise SceneError(self.path, f"buffer {i} has no uri and there is no GLB BIN chunk")
            data = self.bin_chunk
        else:
            data = memoryview(self.read_uri(str(uri), f"buffer {i}"))
        length = get(buf, "byteLength", 0)
        if not isinstance(length, int) or length < 0:
            raise SceneError(self.path, f"buffer {i}: bad byteLength {length!r}")
        if len(data) < length:
            raise SceneError(
                self.path, f"buffer {i} truncated: {len(data)} bytes, byteLength says {length}"
            )
        self.buffers[i] = data[:length]
        return self.buffers[i]

    def read_uri(self, uri: str, what: str) -> bytes:
        """Bytes of a data: URI or of a file relative to the glTF's folder."""
        if uri.startswith("data:"):
            try:
                header, payload = uri[5:].split(",", 1)
            except ValueError:
                raise SceneError(self.path, f"{what}: malformed data URI") from None
            try:
                if header.endswith(";base64"):
                    return base64.b64decode(payload, validate=False)
                return unquote(payload).encode("latin-1")
            except (binascii.Error, UnicodeEncodeError) as exc:
                raise SceneError(self.path, f"{what}: bad data URI ({exc})") from exc
        file = self.resolve_uri(uri)
        try:
            return file.read_bytes()
        except OSError as exc:
            raise SceneError(
                self.path, f"{what}: cannot read {file.name} ({exc.strerror})"
            ) from exc

    def resolve_uri(self, uri: str) -> Path:
        if "://" in uri:
            raise SceneError(self.path, f"remote URI {uri!r} is not supported")
        return self.folder / unquote(uri)

    def buffer_view(self, index: object) -> tuple[memoryview, int]:
        """(bytes, byteStride or 0) of bufferView `index`, bounds-checked against its buffer."""
        views = self.gltf.bufferViews or []
        i = check_index(self.path, index, len(views), "bufferView")
        view = views[i]
        data = self.buffer(get(view, "buffer"))
        offset, length = get(view, "byteOffset", 0), get(view, "byteLength", 0)
        stride = get(view, "byteStride", 0)
        for name, v in (("byteOffset", offset), ("byteLength", length), ("byteStride", stride)):
            if not isinstance(v, int) or v < 0:
                raise SceneError(self.path, f"bufferView {i}: bad {name} {v!r}")
        if offset + length > len(data):
            raise SceneError(
                self.path,
                f"bufferView {i} (bytes {offset}..{offset + length}) exceeds its buffer "
                f"({len(data)} bytes)",
            )
        return data[offset : offset + length], stride

    # -- accessors ----------------------------------------------------------------------------

    def accessor(self, index: object) -> tuple[np.ndarray, bool]:
        """Decode accessor `index` to a (count, ncomp) array of its own dtype.

        Returns the array and the accessor's `normalized` flag; cached because several
        primitives often share one accessor (Sponza shares 39).
        """
        accessors = self.gltf.accessors or []
        i = check_index(self.path, index, len(accessors), "accessor")
        acc = accessors[i]
        normalized = bool(get(acc, "normalized", False))
        if i in self.accessors:
            return self.accessors[i], normalized
        ctype, atype = get(acc, "componentType"), get(acc, "type")
        count, offset = get(acc, "count", 0), get(acc, "byteOffset", 0)
        if ctype not in _DTYPES or atype not in _NCOMP:
            raise SceneError(self.path, f"accessor {i}: bad componentType/type {ctype}/{atype}")
        if not isinstance(count, int) or count < 0 or not isinstance(offset, int) or offset < 0:
            raise SceneError(self.path, f"accessor {i}: bad count/byteOffset {count}/{offset}")
        dtype, ncomp = np.dtype(_DTYPES[ctype]), _NCOMP[atype]
        elem = dtype.itemsize * ncomp
        view_index = get(acc, "bufferView")
        if view_index is None:
            if count * elem > self.file_size + _ZERO_FILL_SLACK:
                raise SceneError(self.path, f"accessor {i}: count {count} is absurd")
            out = np.zeros((count, ncomp), dtype)
        else:
            data, stride = self.buffer_view(view_index)
            stride = stride or elem
            if stride < elem:
                raise SceneError(self.path, f"accessor {i}: byteStride {stride} < element {elem}")
            end = offset + (count - 1) * stride + elem if count else offset
            if end > len(data):
                raise SceneError(
                    self.path,
                    f"accessor {i} needs {end} bytes of bufferView {view_index}, "
                    f"which has {len(data)} (count {count} too large?)",
                )
            raw = np.frombuffer(data, np.uint8, count=end - offset, offset=offset)
            rows = np.lib.stride_tricks.as_strided(raw, (count, elem), (stride, 1))
            out = np.ascontiguousarray(rows).view(dtype).reshape(count, ncomp)
        sparse = get(acc, "sparse")
        if sparse is not None:
            out = self._apply_sparse(i, out, sparse)
        out.setflags(write=False)  # shared through the cache
        self.accessors[i] = out
        return out, normalized

    def _apply_sparse(self, i: int, out: np.ndarray, sparse: object) -> np.ndarray:
        """Overwrite the rows listed by a sparse accessor (glTF spec 3.6.2.3)."""
        n = get(sparse, "count", 0)
        if not isinstance(n, int) or not 0 <= n <= len(out):
            raise SceneError(self.path, f"accessor {i}: sparse count {n!r} out of range")
        idx_info, val_info = get(sparse, "indices", {}), get(sparse, "values", {})
        idx_type = get(idx_info, "componentType")
        if idx_type not in (5121, 5123, 5125):
            raise SceneError(self.path, f"accessor {i}: bad sparse index type {idx_type!r}")
        idx = self._tight(idx_info, np.dtype(_DTYPES[idx_type]), n, f"accessor {i} sparse indices")
        values = self._tight(val_info, out.dtype, n * out.shape[1], f"accessor {i} sparse values")
        if n and idx.max() >= len(out):
            raise SceneError(self.path, f"accessor {i}: sparse index {idx.max()} >= {len(out)}")
        out = out.copy()
        out[idx.astype(np.intp)] = values.reshape(n, out.shape[1])
        return out

    def _tight(self, info: object, dtype: np.dtype, count: int, what: str) -> np.ndarray:
        """`count` tightly packed values of `dtype` from info's bufferView + byteOffset."""
        data, _ = self.buffer_view(get(info, "bufferView"))
        offset = get(info, "byteOffset", 0)
        if not isinstance(offset, int) or offset < 0 or offset + count * dtype.itemsize > len(data):
            raise SceneError(self.path, f"{what} exceed their bufferView")
        return np.frombuffer(data, dtype, count=count, offset=offset)

    def attribute(self, index: object, ncomps: tuple[int, ...], what: str) -> np.ndarray:
        """A vertex attribute as float32 (count, ncomp), applying `normalized` scaling."""
        arr, normalized = self.accessor(index)
        if arr.shape[1] not in ncomps:
            raise SceneError(self.path, f"{what}: {arr.shape[1]} components, expected {ncomps}")
        if arr.dtype.kind == "f":
            return arr.astype(np.float32)
        out = arr.astype(np.float32)
        if normalized:
            info = np.iinfo(arr.dtype)
            # Signed: c / max, clamped at -1 (glTF spec 3.11 "normalized" table).
            out = np.maximum(out / np.float32(info.max), np.float32(-1.0))
        return out

    # -- meshes -------------------------------------------------------------------------------

    def primitive(self, mesh_index: int, prim_index: int, prim: object) -> Mesh:
        """One triangle primitive -> Mesh (indices resolved, flat normals if NORMAL is absent)."""
        name = f"{get(self.gltf.meshes[mesh_index], 'name', f'mesh {mesh_index}')}/{prim_index}"
        mode = get(prim, "mode", 4)
        if mode in _MODES:
            raise SceneError(
                self.path, f"mesh {name}: primitive mode {_MODES[mode]} is not triangles"
            )
        if mode not in (4, 5, 6):
            raise SceneError(self.path, f"mesh {name}: unknown primitive mode {mode!r}")
        attrs = get(prim, "attributes", {})
        attrs = attrs if isinstance(attrs, dict) else getattr(attrs, "__dict__", None)
        if not isinstance(attrs, dict):
            raise SceneError(self.path, f"mesh {name}: attributes is not an object")
        if attrs.get("POSITION") is None:
            raise SceneError(self.path, f"mesh {name}: primitive has no POSITION")
        positions = self.attribute(attrs["POSITION"], (3,), f"mesh {name} POSITION")
        n = len(positions)

        def optional(key: str, ncomps: tuple[int, ...]) -> np.ndarray | None:
            if attrs.get(key) is None:
                return None
            arr = self.attribute(attrs[key], ncomps, f"mesh {name} {key}")
            if len(arr) != n:
                raise SceneError(self.path, f"mesh {name}: {key} has {len(arr)} items, not {n}")
            return arr

        colors = optional("COLOR_0", (3, 4))
        if colors is not None and colors.shape[1] == 3:
            colors = np.concatenate([colors, np.ones((n, 1), np.float32)], axis=1)
        index_acc = get(prim, "indices")
        if index_acc is None:
            indices = np.arange(n, dtype=np.uint32)
        else:
            arr, _ = self.accessor(index_acc)
            if arr.dtype.kind != "u" or arr.shape[1] != 1:
                raise SceneError(self.path, f"mesh {name}: indices must be unsigned scalars")
            indices = arr.reshape(-1).astype(np.uint32)
            if len(indices) and int(indices.max()) >= n:
                raise SceneError(
                    self.path, f"mesh {name}: index {int(indices.max())} >= vertex count {n}"
                )
        if mode == 5:
            indices = strip_triangles(indices)
        elif mode == 6:
            indices = fan_triangles(indices)
        elif len(indices) % 3:
            raise SceneError(
                self.path, f"mesh {name}: {len(indices)} indices is not a multiple of 3"
            )
        material = get(prim, "material", -1)
        if material != -1:
            material = check_index(self.path, material, len(self.gltf.materials or []), "material")
        mesh = Mesh(
            name=name,
            positions=positions,
            indices=indices,
            normals=optional("NORMAL", (3,)),
            texcoords=optional("TEXCOORD_0", (2,)),
            texcoords1=optional("TEXCOORD_1", (2,)),
            tangents=optional("TANGENT", (4,)),
            colors=colors,
            material=material,
        )
        return normalize_mesh_arrays(ensure_normals(drop_nonfinite(mesh, self.path)))
