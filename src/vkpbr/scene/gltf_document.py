# The glTF document layer: parse the JSON (and the GLB container), resolve buffers (GLB BIN
# chunk, data: URIs, external .bin files), decode accessors with NumPy (every component type,
# normalized, byteStride, sparse), and the small typed accessors of JSON fields that the rest of
# the glTF importer shares (gltf_meshes, gltf_materials, gltf_nodes build on this module; it
# imports none of them).
#
# Robustness: every offset and count is checked against the real byte lengths before NumPy
# touches memory, so a corrupt file raises SceneError instead of reading garbage or allocating
# gigabytes. Reference: the glTF 2.0 specification (Khronos), sections 3.6 (buffers,
# accessors), 3.11 (normalized), 4.4 (GLB).

from __future__ import annotations

import base64
import binascii
import struct
import warnings
from pathlib import Path
from urllib.parse import unquote

import numpy as np
import pygltflib

from vkpbr.errors import JsonError, SceneError
from vkpbr.json_input import decode_json
from vkpbr.scene.gltf_codecs import decode_meshopt, missing_codec
from vkpbr.scene.material_table import EXTENSIONS as MATERIAL_EXTENSIONS
from vkpbr.scene.resources import ResourcePolicy, read_error, read_resource

__all__ = ["SUPPORTED_EXTENSIONS", "GltfDocument", "check_index", "ext", "floats", "get", "scalar",
           "to_float"]

SUPPORTED_EXTENSIONS = frozenset(
    {
        "KHR_texture_transform",
        "KHR_lights_punctual",
        "KHR_materials_emissive_strength",
        "KHR_mesh_quantization",  # integer attributes: handled by the generic accessor decoder
        "KHR_animation_pointer",  # animated properties (gltf_animation, docs/animation.md)
    }
) | frozenset(
    {
        # The loading blockers (issue 18); the codecs need their optional packages
        # (gltf_codecs.CODEC_PACKAGES), which extensionsRequired checks for.
        "EXT_meshopt_compression",  # bufferViews, decoded in buffer_view()
        "KHR_draco_mesh_compression",  # primitives, decoded in gltf_meshes
        "KHR_texture_basisu",  # texture sources (_pick_texture_sources), KTX2 in textures.py
        "EXT_texture_webp",  # texture sources, decoded by Pillow
        "EXT_mesh_gpu_instancing",  # Node.instances (gltf_nodes)
    }
) | frozenset(
    MATERIAL_EXTENSIONS  # the material layers (material_table.py)
)
_DTYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
_NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
# An accessor without a bufferView is zero-filled (sparse-only). Its size is not bounded by any
# byte in the file, so cap it: 64 MiB beyond whatever the file itself holds.
_ZERO_FILL_SLACK = 64 << 20


def get(obj: object, key: str, default: object = None) -> object:
    """Field of a pygltflib object or of a plain dict (pygltflib keeps some parts as dicts)."""
    value = obj.get(key) if isinstance(obj, dict) else getattr(obj, key, None)
    return default if value is None else value


def check_index(path: object, value: object, count: int, what: str) -> int:
    """`value` as an index into a list of `count` items, or SceneError."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < count:
        raise SceneError(path, f"{what} {value!r} out of range (0..{count - 1})")
    return value


def ext(obj: object, name: str) -> dict:
    """The `name` extension object of a glTF object, {} if absent or not an object."""
    exts = get(obj, "extensions", {})
    value = exts.get(name) if isinstance(exts, dict) else None
    return value if isinstance(value, dict) else {}


def floats(value: object, n: int, default: tuple[float, ...], what: str, path: object) -> tuple:
    """`n` finite floats from a JSON list, or SceneError."""
    if value is None:
        return default
    try:
        arr = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise SceneError(path, f"{what}: not a list of numbers") from exc
    if arr.shape != (n,) or not np.isfinite(arr).all():
        raise SceneError(path, f"{what}: expected {n} finite numbers, got {value!r}")
    return tuple(float(x) for x in arr)


def scalar(value: object, default: float, what: str, path: object) -> float:
    """One finite float (a JSON number), `default` when absent, or SceneError."""
    return floats(None if value is None else [value], 1, (default,), what, path)[0]


def to_float(arr: np.ndarray, normalized: bool) -> np.ndarray:
    """Integer or float values -> float32, `normalized` integers scaled to [0, 1] / [-1, 1].

    Non-normalized integers keep their values (KHR_mesh_quantization: the node transform or
    KHR_texture_transform dequantises them)."""
    out = arr.astype(np.float32)
    if normalized and arr.dtype.kind in "iu":
        info = np.iinfo(arr.dtype)
        # Signed: c / max, clamped at -1 (glTF spec 3.11 "normalized" table).
        out = np.maximum(out / np.float32(info.max), np.float32(-1.0))
    return out


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


def _pick_texture_sources(doc: dict, basisu: bool) -> None:
    """Point each texture's `source` at its KHR_texture_basisu or EXT_texture_webp image
    when the file gives one (in place, before pygltflib sees the JSON): the extension image is
    the one the exporter meant, `source` (PNG/JPEG, or absent) only its fallback. The rest of
    the importer then reads `source` alone. KTX2 is decoded in textures.py (only when `basisu`:
    its decoder is installed; otherwise the fallback stays), WebP by Pillow."""
    textures = doc.get("textures")
    if not isinstance(textures, list):
        return
    for tex in textures:
        exts = tex.get("extensions") if isinstance(tex, dict) else None
        if not isinstance(exts, dict):
            continue
        for name in ("KHR_texture_basisu", "EXT_texture_webp"):
            if name == "KHR_texture_basisu" and not basisu:
                continue
            info = exts.get(name)
            if isinstance(info, dict) and info.get("source") is not None:
                tex["source"] = info["source"]  # range-checked where it is used
                break


class GltfDocument:
    """One parsed glTF file: its JSON (`doc`, and pygltflib's `gltf` view of it), its buffers
    resolved and bounds-checked, and a cache of decoded accessors."""

    def __init__(self, path: Path, raw: bytes, policy: ResourcePolicy | None = None) -> None:
        self.path = path
        self.folder = path.parent
        self.policy = policy or ResourcePolicy(path)
        self.file_size = len(raw)
        bin_chunk = None
        text = raw
        if raw[:4] == b"glTF":
            text, bin_chunk = _parse_glb(path, raw)
        self.bin_chunk = bin_chunk
        try:
            doc = decode_json(text, path)
        except JsonError as exc:
            raise SceneError(path, f"malformed JSON: {exc.problem}") from None
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
        for name in required:
            if (package := missing_codec(name)) is not None:
                raise SceneError(path, f"requires {name}, which needs the {package} package")
        _pick_texture_sources(doc, basisu=missing_codec("KHR_texture_basisu") is None)
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
        self.decoded_views: dict[int, memoryview] = {}  # EXT_meshopt_compression
        self.accessors: dict[int, np.ndarray] = {}

    # -- buffers ------------------------------------------------------------------------------

    def buffer(self, index: object) -> memoryview:
        """Bytes of buffer `index`, checked against its declared byteLength."""
        buffers = self.gltf.buffers or []
        i = check_index(self.path, index, len(buffers), "buffer")
        if i in self.buffers:
            return self.buffers[i]
        buf = buffers[i]
        uri = get(buf, "uri")
        length = get(buf, "byteLength", 0)
        if isinstance(length, bool) or not isinstance(length, int) or length < 0:
            raise SceneError(self.path, f"buffer {i}: bad byteLength {length!r}")
        if uri is None:
            if ext(buf, "EXT_meshopt_compression").get("fallback") and (
                    self.bin_chunk is None or i != 0):
                # A placeholder: only compressed bufferViews may point at it (their data comes
                # from the extension's buffer), so reaching here is the file's fault.
                raise SceneError(self.path, f"buffer {i} is an EXT_meshopt_compression fallback "
                                            "without data, read by an uncompressed bufferView")
            if self.bin_chunk is None or i != 0:
                raise SceneError(self.path, f"buffer {i} has no uri and there is no GLB BIN chunk")
            data = self.bin_chunk
        elif str(uri).startswith("data:"):
            data = memoryview(self.read_uri(str(uri), f"buffer {i}"))
        else:
            # Only byteLength bytes: /dev/zero or a huge file named as a buffer costs nothing.
            file = self.resolve_uri(str(uri), f"buffer {i}")
            try:
                data = memoryview(read_resource(file, length))
            except OSError as exc:
                raise read_error(self.path, f"buffer {i}", str(uri), exc) from exc
        if len(data) < length:
            raise SceneError(
                self.path, f"buffer {i} truncated: {len(data)} bytes, byteLength says {length}"
            )
        self.buffers[i] = data[:length]
        return self.buffers[i]

    def read_uri(self, uri: str, what: str) -> bytes:
        """Bytes of a data: URI or of a file relative to the glTF's folder (path policy:
        vkpbr.scene.resources)."""
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
        file = self.resolve_uri(uri, what)
        try:
            return read_resource(file)
        except OSError as exc:
            raise read_error(self.path, what, uri, exc) from exc

    def resolve_uri(self, uri: str, what: str = "file") -> Path:
        """A relative URI -> the file it names, through the path policy (percent-decoded
        first, so %2e%2e/ is `..`). Raises ResourceRefused (a SceneError) when refused."""
        if "://" in uri or uri.lower().startswith("file:"):
            raise SceneError(self.path, f"remote URI {uri!r} is not supported")
        return self.policy.resolve(unquote(uri), what)

    def buffer_view(self, index: object) -> tuple[memoryview, int]:
        """(bytes, byteStride or 0) of bufferView `index`, bounds-checked against its buffer."""
        views = self.gltf.bufferViews or []
        i = check_index(self.path, index, len(views), "bufferView")
        view = views[i]
        offset, length = get(view, "byteOffset", 0), get(view, "byteLength", 0)
        stride = get(view, "byteStride", 0)
        for name, v in (("byteOffset", offset), ("byteLength", length), ("byteStride", stride)):
            if not isinstance(v, int) or v < 0:
                raise SceneError(self.path, f"bufferView {i}: bad {name} {v!r}")
        meshopt = ext(view, "EXT_meshopt_compression")
        if meshopt:
            package = missing_codec("EXT_meshopt_compression")
            if package is None:
                return self._meshopt_view(i, meshopt, length), stride
            buf = (self.gltf.buffers or [None])[check_index(
                self.path, get(view, "buffer"), len(self.gltf.buffers or []), "buffer")]
            if get(buf, "uri") is None and (self.bin_chunk is None or get(view, "buffer") != 0):
                raise SceneError(self.path, f"bufferView {i} is EXT_meshopt_compression data "
                                            f"without a fallback; it needs the {package} package")
        data = self.buffer(get(view, "buffer"))
        if offset + length > len(data):
            raise SceneError(
                self.path,
                f"bufferView {i} (bytes {offset}..{offset + length}) exceeds its buffer "
                f"({len(data)} bytes)",
            )
        return data[offset : offset + length], stride

    def _meshopt_view(self, i: int, info: dict, length: int) -> memoryview:
        """bufferView `i` decompressed from its EXT_meshopt_compression source (cached)."""
        if i not in self.decoded_views:
            what = f"bufferView {i}"
            offset, n = info.get("byteOffset", 0), info.get("byteLength")
            for name, v in (("byteOffset", offset), ("byteLength", n)):
                if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                    raise SceneError(self.path, f"{what}: EXT_meshopt_compression {name} {v!r}")
            source = self.buffer(info.get("buffer"))
            if offset + n > len(source):
                raise SceneError(self.path, f"{what}: EXT_meshopt_compression bytes {offset}.."
                                            f"{offset + n} exceed their buffer ({len(source)})")
            self.decoded_views[i] = decode_meshopt(self.path, what, source[offset:offset + n],
                                                   info, length)
        return self.decoded_views[i]

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
        return to_float(arr, normalized)

    # -- meshes -------------------------------------------------------------------------------
