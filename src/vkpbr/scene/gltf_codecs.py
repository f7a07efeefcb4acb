# The glTF compression codecs, each behind an optional package: EXT_meshopt_compression
# (bufferView-level, through the meshoptimizer package's decoder and filters) and
# KHR_draco_mesh_compression (primitive-level, through DracoPy). The packages are imported on
# first use, so that a scene without compressed data never pays for them and a machine without
# them still loads everything else. Every size is checked before a decoder allocates: a corrupt
# or hostile payload is a SceneError naming the file, never a crash or a gigabyte allocation.
# References: EXT_meshopt_compression (Khronos glTF extension registry, modes and Appendix B
# filters); KHR_draco_mesh_compression (ibid.). KHR_texture_basisu's KTX2 images are
# transcoded to RGBA8 through opengl_basisu (Binomial's basis_universal transcoder compiled
# into a wheel, arrays out; the KTX-Software binding pyktx needs a libktx install that neither
# pip nor the Debian archive provides) in decode_ktx2.

from __future__ import annotations

import importlib
from types import ModuleType

import numpy as np

from vkpbr.errors import SceneError
from vkpbr.scene.mips import mip_level_count

__all__ = ["CODEC_PACKAGES", "KTX2_MAGIC", "codec", "decode_draco", "decode_ktx2", "decode_meshopt", "ktx2_blocks",
           "missing_codec"]

# Extension -> (module to import, the pip requirement that provides it).
CODEC_PACKAGES: dict[str, tuple[str, str]] = {
    "EXT_meshopt_compression": ("meshoptimizer", "meshoptimizer (pip install 'vkpbr[bake]')"),
    "KHR_draco_mesh_compression": ("DracoPy", "DracoPy (pip install 'vkpbr[codecs]')"),
    "KHR_texture_basisu": ("opengl_basisu", "opengl-basisu (pip install 'vkpbr[codecs]')"),
}
KTX2_MAGIC = b"\xabKTX 20\xbb\r\n\x1a\n"
_MODULES: dict[str, ModuleType | None] = {}

# A decoded bufferView may be larger than the file by this much plus _MAX_RATIO times its
# compressed bytes: meshopt's attribute codec reaches ~60:1 on constant data, never more.
_SLACK = 64 << 20
_MAX_RATIO = 128


def codec(extension: str) -> ModuleType | None:
    """The decoder module of a codec extension, None when its package is not installed."""
    name = CODEC_PACKAGES[extension][0]
    if name not in _MODULES:
        try:
            _MODULES[name] = importlib.import_module(name)
        except (ImportError, OSError):  # absent, or a broken build (a missing shared library)
            _MODULES[name] = None
    return _MODULES[name]


def missing_codec(extension: str) -> str | None:
    """The requirement to install for `extension`, None when it is there (or not a codec)."""
    if extension not in CODEC_PACKAGES or codec(extension) is not None:
        return None
    return CODEC_PACKAGES[extension][1]


def decode_meshopt(path: object, what: str, data: memoryview, info: dict,
                   view_length: int) -> memoryview:
    """Decompress one EXT_meshopt_compression bufferView.

    Parameters
    ----------
    path : the glTF file (for errors).
    what : "bufferView N" (for errors).
    data : the compressed bytes (the extension's byteOffset/byteLength range of its buffer).
    info : the extension object (count, byteStride, mode, filter).
    view_length : the parent bufferView's byteLength, which must be count * byteStride.

    Returns
    -------
    The decoded bytes, view_length long, filters applied.

    Raises
    ------
    SceneError : bad parameters, a size mismatch or a payload the decoder rejects.
    """
    count, stride = info.get("count"), info.get("byteStride")
    mode, filt = info.get("mode"), info.get("filter", "NONE")
    for name, v in (("count", count), ("byteStride", stride)):
        if isinstance(v, bool) or not isinstance(v, int) or v < 0:
            raise SceneError(path, f"{what}: EXT_meshopt_compression {name} {v!r} is invalid")
    if count * stride != view_length:
        raise SceneError(path, f"{what}: EXT_meshopt_compression count {count} x byteStride "
                               f"{stride} != the bufferView's byteLength {view_length}")
    if view_length > _SLACK + _MAX_RATIO * len(data):
        raise SceneError(path, f"{what}: EXT_meshopt_compression claims {view_length} bytes "
                               f"from {len(data)} compressed ones")
    mo = codec("EXT_meshopt_compression")
    assert mo is not None  # the caller checked
    try:
        if mode == "ATTRIBUTES":
            if stride % 4 or not 0 < stride <= 256:
                raise SceneError(path, f"{what}: ATTRIBUTES byteStride {stride} is not a "
                                       "multiple of 4 in 4..256")
            out = _as_bytes(mo.decode_vertex_buffer(count, stride, data), view_length)
            return memoryview(_filter(path, what, mo, out, count, stride, filt))
        if mode in ("TRIANGLES", "INDICES"):
            if stride not in (2, 4):
                raise SceneError(path, f"{what}: {mode} byteStride {stride} is not 2 or 4")
            if filt != "NONE":
                raise SceneError(path, f"{what}: {mode} with filter {filt!r}")
            if mode == "TRIANGLES":
                if count % 3:
                    raise SceneError(path, f"{what}: TRIANGLES count {count} is not a "
                                           "multiple of 3")
                idx = mo.decode_index_buffer(count, 4, data)
            else:
                idx = mo.decode_index_sequence(count, 4, data)
            # Decoded as 32-bit whatever the stride: the bitstream does not depend on it, and
            # the binding returns a uint32 array (a 2-byte decode would be packed into it).
            idx = np.asarray(idx, dtype=np.uint32).reshape(-1)
            if len(idx) != count:
                raise ValueError(f"decoded {len(idx)} indices, expected {count}")
            if stride == 2 and len(idx) and int(idx.max()) > 0xFFFF:
                raise SceneError(path, f"{what}: decoded index {int(idx.max())} does not fit "
                                       "its 2-byte stride")
            return memoryview(idx.astype("<u2" if stride == 2 else "<u4").tobytes())
    except (RuntimeError, ValueError) as exc:
        # The C decoder returns a non-zero code for a truncated or corrupt stream.
        raise SceneError(path, f"{what}: corrupt EXT_meshopt_compression data ({exc})") from exc
    raise SceneError(path, f"{what}: unknown EXT_meshopt_compression mode {mode!r}")


def _as_bytes(arr: np.ndarray, n: int) -> np.ndarray:
    """A decoder's output array as n uint8."""
    out = np.ascontiguousarray(arr).view(np.uint8).reshape(-1)
    if out.size != n:
        raise ValueError(f"decoded {out.size} bytes, expected {n}")
    return out


def _filter(path: object, what: str, mo: ModuleType, raw: np.ndarray, count: int, stride: int,
            filt: object) -> bytes:
    """Apply an ATTRIBUTES filter (Appendix B) to the decoded bytes."""
    if filt == "NONE":
        return raw.tobytes()
    if filt == "OCTAHEDRAL":
        if stride not in (4, 8):
            raise SceneError(path, f"{what}: OCTAHEDRAL filter needs byteStride 4 or 8")
        typed = raw.view("<i1" if stride == 4 else "<i2")
        return np.asarray(mo.decode_filter_oct(typed, count, stride)).tobytes()
    if filt == "QUATERNION":
        if stride != 8:
            raise SceneError(path, f"{what}: QUATERNION filter needs byteStride 8")
        return np.asarray(mo.decode_filter_quat(raw.view("<i2"), count, stride)).tobytes()
    if filt == "EXPONENTIAL":
        return np.asarray(mo.decode_filter_exp(raw.view("<u4"), count, stride)).tobytes()
    raise SceneError(path, f"{what}: unknown EXT_meshopt_compression filter {filt!r}")


def decode_draco(path: object, what: str, data: bytes) -> tuple[np.ndarray, dict[int, np.ndarray]]:
    """Decode one KHR_draco_mesh_compression payload.

    Returns
    -------
    faces : (M,) uint32 triangle-list indices.
    attributes : Draco unique id -> (N, K) decoded values (float32 for quantised floats, the
        stored integer type otherwise), every one with the same N.

    Raises
    ------
    SceneError : a payload DracoPy rejects, a point cloud, or attributes of unequal lengths.
    """
    draco = codec("KHR_draco_mesh_compression")
    assert draco is not None  # the caller checked
    try:
        mesh = draco.decode(bytes(data))
    except Exception as exc:  # noqa: BLE001 - DracoPy raises bare Exception subclasses and
        # ValueError/RuntimeError from its C++ layer; every one means "not a valid payload"
        raise SceneError(path, f"{what}: corrupt KHR_draco_mesh_compression data "
                               f"({type(exc).__name__}: {exc})") from exc
    faces = getattr(mesh, "faces", None)
    if faces is None:
        raise SceneError(path, f"{what}: the Draco payload is a point cloud, not a mesh")
    faces = np.asarray(faces, dtype=np.int64).reshape(-1)
    attrs: dict[int, np.ndarray] = {}
    n = None
    for a in mesh.attributes:
        arr = np.asarray(a["data"])
        arr = arr.reshape(len(arr), -1) if arr.ndim else arr.reshape(1, -1)
        n = len(arr) if n is None else n
        if len(arr) != n:
            raise SceneError(path, f"{what}: Draco attributes of {n} and {len(arr)} points")
        attrs[int(a["unique_id"])] = arr
    if n is None:
        raise SceneError(path, f"{what}: the Draco payload holds no attributes")
    if len(faces) and (faces.min() < 0 or faces.max() >= n):
        raise SceneError(path, f"{what}: Draco face index {int(faces.max())} >= {n} points")
    return faces.astype(np.uint32), attrs


def ktx2_size(data: bytes) -> tuple[int, int]:
    """(width, height) from a KTX2 header (KTX 2.0 spec 3.1), read before any transcoding so
    that the texture limits apply first; ValueError for a header that is not KTX2."""
    if len(data) < 80 or data[:12] != KTX2_MAGIC:
        raise ValueError("not a KTX2 file (bad identifier or truncated header)")
    width, height = np.frombuffer(data, "<u4", count=2, offset=20)
    return int(width), max(1, int(height))


def decode_ktx2(data: bytes) -> np.ndarray:
    """A KTX2 image (KHR_texture_basisu: Basis Universal ETC1S or UASTC; or plain RGBA8) ->
    (H, W, 4) uint8 RGBA of its base level (mips are rebuilt on upload, as for PNG).

    Raises
    ------
    ValueError : a payload the transcoder rejects, or a format it cannot turn into RGBA8 (the
        caller reports it as an undecodable texture and binds the default).
    """
    basisu = codec("KHR_texture_basisu")
    if basisu is None:
        raise ValueError("KTX2 needs " + CODEC_PACKAGES["KHR_texture_basisu"][1])
    width, height = ktx2_size(data)
    if _vk_format(data) != 0:  # not Basis Universal (vkFormat UNDEFINED): raw texels
        return _plain_rgba8(data, width, height)
    try:
        texture = basisu.open(data)
        if (texture.width, texture.height) != (width, height):
            raise ValueError("KTX2 header and payload sizes differ")
        image = texture.transcode(basisu.Target.RGBA8)
    except basisu.BasisuError as exc:  # UnsupportedError is one
        raise ValueError(f"corrupt or unsupported KTX2 ({exc})") from exc
    px = np.asarray(image.data, np.uint8)
    if px.shape != (height, width, 4):
        raise ValueError(f"KTX2 level 0 transcoded to {px.shape}, not {(height, width, 4)}")
    return px


def ktx2_blocks(data: bytes, target: str = "bc7") -> list[np.ndarray] | None:
    """Every mip level of a Basis Universal KTX2 transcoded to GPU blocks (`target` "bc7":
    BC7 RGBA, 16 bytes a 4x4 block), largest first, each (blocks high, blocks wide, 16) uint8;
    None when the file is not Basis Universal or does not hold the full mip chain (the GPU
    cannot make mips of block formats, so such a texture stays RGBA8 with blitted mips).

    Raises ValueError as decode_ktx2 does (the caller has decoded it already, so it is rare).
    """
    basisu = codec("KHR_texture_basisu")
    if basisu is None or _vk_format(data) != 0:
        return None
    width, height = ktx2_size(data)
    try:
        levels = basisu.open(data).transcode_levels({"bc7": basisu.Target.BC7}[target])
    except basisu.BasisuError as exc:
        raise ValueError(f"corrupt or unsupported KTX2 ({exc})") from exc
    if len(levels) != mip_level_count(width, height):
        return None
    out = []
    for k, level in enumerate(levels):
        w, h = max(width >> k, 1), max(height >> k, 1)
        blocks = np.asarray(level.data, np.uint8)
        if blocks.shape != (-(-h // 4), -(-w // 4), 16):
            raise ValueError(f"KTX2 level {k} transcoded to {blocks.shape} blocks for {w}x{h}")
        out.append(np.ascontiguousarray(blocks))
    return out


# KTX 2.0 (spec 3.1): vkFormat at byte 12, supercompressionScheme at 44, level 0's byteOffset
# and byteLength at 80 and 88 (the level index follows the 80-byte header).
_RGBA8_FORMATS = (37, 43)  # VK_FORMAT_R8G8B8A8_UNORM, _SRGB


def _vk_format(data: bytes) -> int:
    return int(np.frombuffer(data, "<u4", count=1, offset=12)[0])


def _plain_rgba8(data: bytes, width: int, height: int) -> np.ndarray:
    """Level 0 of an uncompressed RGBA8 KTX2 (no supercompression)."""
    fmt, scheme = _vk_format(data), int(np.frombuffer(data, "<u4", count=1, offset=44)[0])
    if fmt not in _RGBA8_FORMATS or scheme != 0:
        raise ValueError(f"KTX2 vkFormat {fmt} (supercompression {scheme}) is not supported: "
                         "Basis Universal or plain RGBA8 only")
    if len(data) < 96:
        raise ValueError("KTX2 level index is truncated")
    offset, length = (int(v) for v in np.frombuffer(data, "<u8", count=2, offset=80))
    n = width * height * 4
    if length < n or offset + n > len(data):
        raise ValueError("KTX2 level 0 is shorter than its header says")
    return np.frombuffer(data, np.uint8, count=n, offset=offset).reshape(height, width, 4).copy()
