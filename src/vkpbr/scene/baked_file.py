# The GPU-ready baked scene file (.vkpbr): versioned, checksummed, 64-byte aligned sections
# that load with np.frombuffer and no parsing of vertex data. The format (reader and writer)
# lives in scene/ beside the other file formats, so that load_scene reads .vkpbr files without
# importing bake/; bake/ computes what goes in and writes it through this module.
#
# References: docs/baked-format.md (the layout, byte by byte); renderer-spec.md section 5 (the
# course's .comp5822mesh this replaces); PNG's signature (a non-ASCII first magic byte catches
# text-mode transfers). Every check here exists so that a bad file raises BakeFormatError
# with the reason instead of crashing the renderer or reading out of bounds.
"""Read and write `.vkpbr` baked scenes (format version 2: images carry full mip chains).

The container is a 64-byte header, a table of named sections (offset, size, CRC-32) and the
sections themselves, each starting on a 64-byte boundary so that vertex streams can be
viewed in place (``np.frombuffer`` or ``np.memmap``) and uploaded as they are. Non-array data
(materials, node names, lights, cameras, image records, the source key) is one JSON section.
"""

from __future__ import annotations

import dataclasses
import json
import mmap as _mmap
import os
import struct
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from vkpbr.atomic import atomic_writer
from vkpbr.errors import BakeFormatError, JsonError
from vkpbr.json_input import SCENE_JSON_LIMITS, decode_json
from vkpbr.scene.material_table import PARAMS
from vkpbr.scene.mips import is_mip_chain
from vkpbr.scene.resources import ResourcePolicy, policy_image
from vkpbr.scene.types import (
    TEXTURE_SLOTS,
    Camera,
    Image,
    Light,
    Material,
    Mesh,
    Node,
    Sampler,
    Scene,
    TextureRef,
)

__all__ = [
    "ALIGN",
    "FORMAT_VERSION",
    "MAGIC",
    "MESH_DTYPE",
    "STREAMS",
    "BakedImage",
    "BakedScene",
    "load_baked_scene",
    "read_baked",
    "write_baked",
]

MAGIC = b"\x89VKPBAKE"
FORMAT_VERSION = 2  # 2: an image's "levels" are its full mip chain, with their colour space
ALIGN = 64
_HEADER = struct.Struct("<8sIIIIQII")  # magic, version, header size, sections, flags,
_HEADER_SIZE = 64  # file size, table crc, header crc (of the 36 bytes before it); zero padded
_ENTRY = np.dtype([("name", "S16"), ("offset", "<u8"), ("size", "<u8"), ("crc32", "<u4"),
                   ("reserved", "<u4")])
_MAX_SECTIONS = 4096

# Mesh flags: which optional source attributes the mesh had (missing ones are zero-filled).
HAS_TEXCOORDS, HAS_TEXCOORDS1, HAS_COLORS, TANGENTS_FROM_FILE = 1, 2, 4, 8
MESH_DTYPE = np.dtype([
    ("first_vertex", "<u4"), ("vertex_count", "<u4"), ("first_index", "<u4"),
    ("index_count", "<u4"), ("material", "<i4"), ("flags", "<u4"),
    ("bounds_min", "<f4", 3), ("bounds_max", "<f4", 3),
])  # 48 bytes; indices are local to the mesh (draw with vertexOffset = first_vertex)
# Concatenated per-vertex (or per-index) streams: name -> (dtype, components, required).
STREAMS: dict[str, tuple[str, int, bool]] = {
    "positions": ("<f4", 3, True), "normals": ("<f4", 3, True), "texcoords": ("<f4", 2, True),
    "tangents": ("<f4", 4, True), "qtangents": ("<f4", 4, True),
    "packed_frames": ("<u4", 1, True), "texcoords1": ("<f4", 2, False),
    "colors": ("<f4", 4, False), "indices": ("<u4", 1, True),
}


@dataclass
class BakedImage:
    """An image as the baked file holds it: exactly one of path, data or levels is set.

    path:   a file on disk (absolute in memory; stored relative to the baked file).
    data:   encoded bytes (PNG/JPEG) copied from a source that embedded them.
    levels: the full raw RGBA8 mip chain (vkpbr.scene.mips.mip_chain), (h, w, 4) uint8 arrays,
        level 0 first, down to 1x1: nothing to decode and nothing to filter at load.
    srgb:   the levels were filtered as sRGB colour (the image is a base colour or emissive map).
    """

    name: str
    path: Path | None = None
    data: bytes | None = None
    mime_type: str | None = None
    levels: list[np.ndarray] = field(default_factory=list)
    srgb: bool = False


@dataclass
class BakedScene:
    """A baked scene: one set of concatenated streams and a table of meshes into them.

    streams: name -> array, see `STREAMS`; vertex streams have V rows, "indices" has I.
    mesh_table: (K,) `MESH_DTYPE`; mesh_names: K names.
    source_key: sha256 hex of the source file(s), "" when unknown.
    bake_seconds: how long `bake_scene` took (not stored in the file).
    """

    name: str
    mesh_table: np.ndarray
    mesh_names: list[str]
    streams: dict[str, np.ndarray]
    materials: list[Material] = field(default_factory=list)
    images: list[BakedImage] = field(default_factory=list)
    nodes: list[Node] = field(default_factory=list)
    lights: list[Light] = field(default_factory=list)
    cameras: list[Camera] = field(default_factory=list)
    source_key: str = ""
    source_files: list[str] = field(default_factory=list)
    bake_seconds: float = 0.0

    def mesh_stream(self, mesh: int, name: str) -> np.ndarray:
        """The slice of stream `name` that belongs to mesh `mesh` (a view, no copy)."""
        row = self.mesh_table[mesh]
        if name == "indices":
            start, count = int(row["first_index"]), int(row["index_count"])
        else:
            start, count = int(row["first_vertex"]), int(row["vertex_count"])
        return self.streams[name][start:start + count]


def _pad(n: int) -> int:
    return -n % ALIGN


def _json_value(value: Any) -> Any:
    """Dataclass fields to JSON: tuples become lists, Paths strings."""
    if isinstance(value, dict):
        return {k: _json_value(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_value(v) for v in value]
    return value


def _image_record(img: BakedImage, blobs: list[bytes], base: int, folder: Path) -> dict:
    """JSON record of one image; appends its bytes to `blobs` (offsets from `base`)."""
    rec: dict[str, Any] = {"name": img.name, "mime_type": img.mime_type, "path": None,
                           "data": None, "levels": [], "srgb": bool(img.srgb)}
    offset = base + sum(len(b) for b in blobs)

    def put(raw: bytes) -> int:
        nonlocal offset
        start = offset
        blobs.append(raw + b"\0" * _pad(len(raw)))
        offset += len(blobs[-1])
        return start

    if img.path is not None:
        try:  # relative, so the baked file moves together with its textures
            rec["path"] = Path(os.path.relpath(Path(img.path).resolve(), folder)).as_posix()
        except ValueError:  # another drive (Windows): keep it absolute
            rec["path"] = Path(img.path).resolve().as_posix()
    if img.data is not None:
        rec["data"] = [put(bytes(img.data)), len(img.data)]
    levels = [np.ascontiguousarray(level, dtype=np.uint8) for level in img.levels]
    if levels and not is_mip_chain(levels):
        raise ValueError(f"image {img.name!r}: levels must be a full mip chain of (h, w, 4) "
                         "uint8 arrays down to 1x1 (vkpbr.scene.mips.mip_chain)")
    for lv in levels:
        rec["levels"].append([put(lv.tobytes()), int(lv.shape[1]), int(lv.shape[0])])
    return rec


def write_baked(path: str | os.PathLike[str], baked: BakedScene) -> int:
    """Write `baked` to `path` atomically (temporary file in the same folder, then replace).

    Parameters
    ----------
    path : destination, conventionally ``*.vkpbr``
    baked : the scene to write; arrays are converted to the stored little-endian dtypes

    Returns
    -------
    int: the file size in bytes
    """
    path = Path(path)
    folder = path.resolve().parent
    sections: list[tuple[str, bytes | memoryview]] = []
    n_vert = len(baked.streams["positions"])
    for name, (dtype, _comps, required) in STREAMS.items():
        arr = baked.streams.get(name)
        if arr is None:
            if required:
                raise ValueError(f"baked scene lacks the required stream {name!r}")
            continue
        arr = np.ascontiguousarray(arr, dtype=dtype)
        if name != "indices" and len(arr) != n_vert:
            raise ValueError(f"stream {name!r} has {len(arr)} rows, positions {n_vert}")
        sections.append((name, memoryview(arr.reshape(-1)).cast("B")))
    table = np.ascontiguousarray(baked.mesh_table, dtype=MESH_DTYPE)
    sections.insert(0, ("meshes", table.tobytes()))
    mats = np.ascontiguousarray([n.matrix for n in baked.nodes], dtype="<f4").reshape(-1, 4, 4)
    sections.insert(1, ("node_matrices", mats.tobytes()))

    blobs: list[bytes] = []
    images = [_image_record(img, blobs, 0, folder) for img in baked.images]
    if blobs:
        sections.append(("image_data", b"".join(blobs)))
    doc = {
        "format": "vkpbr-baked", "version": FORMAT_VERSION, "name": baked.name,
        "source": {"sha256": baked.source_key, "files": list(baked.source_files)},
        "meshes": [{"name": n} for n in baked.mesh_names],
        "materials": [_json_value(dataclasses.asdict(m)) for m in baked.materials],
        "images": images,
        "nodes": [{"mesh": int(n.mesh), "name": n.name} for n in baked.nodes],
        "lights": [_json_value(dataclasses.asdict(x)) for x in baked.lights],
        "cameras": [_json_value(dataclasses.asdict(c)) for c in baked.cameras],
    }
    text = json.dumps(doc, sort_keys=True, separators=(",", ":"), default=_json_default)
    sections.insert(0, ("scene", text.encode()))
    return write_sections(path, sections)


def write_sections(path: str | os.PathLike[str],
                   sections: list[tuple[str, bytes | memoryview]]) -> int:
    """Write named sections as a .vkpbr container (header, table, 64-byte aligned data, every
    checksum computed), atomically; returns the file size. `write_baked` builds the sections;
    the fuzz suite re-packs mutated ones through here, so that its files are intact and only
    their contents are wrong."""
    entries = np.zeros(len(sections), dtype=_ENTRY)
    offset = _HEADER_SIZE + entries.nbytes
    offset += _pad(offset)
    for i, (name, data) in enumerate(sections):
        entries[i] = (name.encode(), offset, len(data), zlib.crc32(data), 0)
        offset += len(data) + _pad(len(data))
    file_size = offset
    head = _HEADER.pack(MAGIC, FORMAT_VERSION, _HEADER_SIZE, len(sections), 0, file_size,
                        zlib.crc32(entries.tobytes()), 0)
    head = head[:36] + struct.pack("<I", zlib.crc32(head[:36]))
    head += b"\0" * (_HEADER_SIZE - len(head))

    with atomic_writer(Path(path), fsync=True) as f:
        f.write(head)
        f.write(entries.tobytes())
        f.write(b"\0" * _pad(_HEADER_SIZE + entries.nbytes))
        for _, data in sections:
            f.write(data)
            f.write(b"\0" * _pad(len(data)))
    return file_size


def read_sections(path: str | os.PathLike[str]) -> list[tuple[str, bytes]]:
    """The named sections of a .vkpbr file, checksums verified (BakeFormatError if not)."""
    path = Path(path)
    buf = memoryview(path.read_bytes())
    return [(name, bytes(data)) for name, data in _parse_sections(buf, path).items()]


def _json_default(obj: Any) -> Any:
    """NumPy scalars and arrays in scene fields (a Python caller's material factors, say)."""
    if isinstance(obj, np.generic | np.ndarray):
        return obj.tolist()
    raise TypeError(f"{type(obj).__name__} cannot be stored in a baked scene")


def _check(cond: bool, path: Path, problem: str) -> None:
    if not cond:
        raise BakeFormatError(path, problem)


def _parse_sections(buf: memoryview, path: Path) -> dict[str, memoryview]:
    """Validate header, table and checksums; return section name -> bytes view."""
    size = len(buf)
    _check(size >= _HEADER_SIZE, path, f"truncated: {size} bytes, the header alone is 64")
    magic, version, head_size, count, _flags, file_size, table_crc, head_crc = \
        _HEADER.unpack_from(buf, 0)
    _check(magic == MAGIC, path, "not a vkpbr baked file (bad magic)")
    _check(version == FORMAT_VERSION, path,
           f"baked format version {version}, this vkpbr reads version {FORMAT_VERSION} only; "
           "bake the scene again (vkpbr bake SOURCE --out FILE.vkpbr)")
    _check(zlib.crc32(buf[:36]) == head_crc, path, "corrupt header (checksum mismatch)")
    _check(head_size == _HEADER_SIZE, path, f"bad header size {head_size}")
    _check(file_size == size, path,
           f"truncated: {size} bytes, header says {file_size}" if size < file_size
           else f"{size - file_size} unexpected bytes after the end of the file")
    _check(count <= _MAX_SECTIONS, path, f"implausible section count {count}")
    table_end = _HEADER_SIZE + count * _ENTRY.itemsize
    _check(table_end <= size, path, "section table runs past the end of the file")
    raw_table = buf[_HEADER_SIZE:table_end]
    _check(zlib.crc32(raw_table) == table_crc, path, "corrupt section table (checksum mismatch)")
    out: dict[str, memoryview] = {}
    for e in np.frombuffer(raw_table, dtype=_ENTRY):
        name = e["name"].decode("ascii", "replace")
        off, n = int(e["offset"]), int(e["size"])
        _check(name not in out, path, f"section {name!r} appears twice")
        _check(off >= table_end and off % ALIGN == 0 and off + n <= size, path,
               f"section {name!r} (offset {off}, size {n}) is out of bounds or misaligned")
        data = buf[off:off + n]
        _check(zlib.crc32(data) == int(e["crc32"]), path,
               f"section {name!r} is corrupt (checksum mismatch)")
        out[name] = data
    return out


def _array(sections: dict[str, memoryview], name: str, dtype: Any, comps: int,
           path: Path) -> np.ndarray:
    _check(name in sections, path, f"missing section {name!r}")
    data = sections[name]
    item = np.dtype(dtype).itemsize * comps
    _check(len(data) % item == 0, path, f"section {name!r}: {len(data)} bytes is not a "
           f"whole number of {item}-byte items")
    arr = np.frombuffer(data, dtype=dtype)
    return arr.reshape(-1, comps) if comps > 1 else arr


def _build(cls: type, rec: dict, tuples: tuple[str, ...]) -> Any:
    return cls(**{k: tuple(v) if k in tuples else v for k, v in rec.items()})


def _material(rec: dict) -> Material:
    for key, value in list(rec.items()):
        if key.endswith("_texture") and value is not None:
            tex = dict(value)
            tex["sampler"] = Sampler(**tex["sampler"])
            rec[key] = _build(TextureRef, tex, ("offset", "scale"))
    # Files baked before the KHR_materials_* fields existed lack them: the defaults apply.
    return _build(Material, rec, tuple(p.name for p in PARAMS if p.size > 1))  # JSON lists


def _validate_counts(baked: BakedScene, path: Path) -> None:
    """Cross-check the mesh table, streams, nodes and materials; vectorised index check."""
    n_vert = len(baked.streams["positions"])
    n_idx = len(baked.streams["indices"])
    for name, arr in baked.streams.items():
        _check(name == "indices" or len(arr) == n_vert, path,
               f"stream {name!r} has {len(arr)} rows, positions has {n_vert}")
    t = baked.mesh_table
    _check(len(baked.mesh_names) == len(t), path, "mesh table and mesh names disagree")
    fv, vc = t["first_vertex"].astype(np.int64), t["vertex_count"].astype(np.int64)
    fi, ic = t["first_index"].astype(np.int64), t["index_count"].astype(np.int64)
    _check(bool(np.all(fv + vc <= n_vert) and np.all(fi + ic <= n_idx)), path,
           "a mesh's vertex or index range runs past its stream")
    _check(bool(np.all(ic % 3 == 0)), path, "a mesh's index count is not a multiple of 3")
    _check(bool(np.all((t["material"] >= -1) & (t["material"] < len(baked.materials)))),
           path, "a mesh refers to a material that does not exist")
    nz = ic > 0
    if nz.any():
        idx, starts, ends = baked.streams["indices"], fi[nz], (fi + ic)[nz]
        if np.array_equal(starts[1:], ends[:-1]) and ends[-1] == n_idx:
            # Back-to-back ranges (what bake writes): every mesh's max in one reduceat.
            mx = np.maximum.reduceat(idx, starts)
        else:  # unusual layout: one vectorised max per mesh
            mx = np.array([idx[a:b].max() for a, b in zip(starts, ends, strict=True)])
        _check(bool(np.all(mx < vc[nz])), path, "an index points past its mesh's vertices")
    # Indices from the JSON may be of any type: compare only integers (scene/validate.py
    # names the field of anything else).
    for node in baked.nodes:
        _check(not _is_int(node.mesh) or 0 <= node.mesh < len(t), path,
               f"node {node.name!r} refers to a missing mesh")
    for m in baked.materials:
        for tex in (getattr(m, f"{slot}_texture", None) for slot in TEXTURE_SLOTS):
            _check(tex is None or not _is_int(getattr(tex, "image", None))
                   or 0 <= tex.image < len(baked.images), path,
                   f"material {m.name!r} refers to a missing image")


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def read_baked(path: str | os.PathLike[str], *, mmap: bool = False) -> BakedScene:
    """Read and fully validate a `.vkpbr` file.

    Parameters
    ----------
    path : the baked file
    mmap : map the file instead of reading it (arrays become read-only views of the mapping)

    Returns
    -------
    BakedScene whose arrays are views into one buffer (no per-array copies)

    Raises
    ------
    BakeFormatError: wrong magic or version, truncated, checksum mismatch, sections out of
        bounds, inconsistent counts, malformed JSON. OSError: the file cannot be read.
    """
    path = Path(path)
    with open(path, "rb") as f:
        if mmap and os.fstat(f.fileno()).st_size > 0:
            buf = memoryview(_mmap.mmap(f.fileno(), 0, access=_mmap.ACCESS_READ))
        else:
            # Writable views for the caller, read in place: one copy, into memory not zeroed
            # first (a bytearray's zeroing was a quarter of a big scene's read)
            data = np.empty(os.fstat(f.fileno()).st_size, np.uint8)
            got = f.readinto(data)
            buf = memoryview(data)[:got]
    sections = _parse_sections(buf, path)
    try:
        doc = decode_json(bytes(sections["scene"]), path, SCENE_JSON_LIMITS)
    except KeyError:
        raise BakeFormatError(path, "missing section 'scene'") from None
    except JsonError as exc:
        raise BakeFormatError(path, f"scene section is not valid JSON: {exc.problem}") from None
    try:
        streams = {name: _array(sections, name, dt, c, path)
                   for name, (dt, c, req) in STREAMS.items() if req or name in sections}
        table = _array(sections, "meshes", MESH_DTYPE, 1, path)
        mats = _array(sections, "node_matrices", "<f4", 16, path).reshape(-1, 4, 4)
        _check(len(mats) == len(doc["nodes"]), path, "node matrices and nodes disagree")
        blob = sections.get("image_data", memoryview(b""))
        images = []
        for rec in doc["images"]:
            img = BakedImage(rec["name"], mime_type=rec["mime_type"], srgb=bool(rec["srgb"]))
            if rec["path"] is not None:
                img.path = path.resolve().parent / rec["path"]
            if rec["data"] is not None:
                off, n = rec["data"]
                _check(off >= 0 and off + n <= len(blob), path, "image bytes out of bounds")
                img.data = bytes(blob[off:off + n])
            for off, w, h in rec["levels"]:
                n = w * h * 4
                _check(off >= 0 and off + n <= len(blob) and w > 0 and h > 0, path,
                       f"image {img.name!r}: mip level out of bounds")
                img.levels.append(np.frombuffer(blob, np.uint8, n, off).reshape(h, w, 4))
            _check(not img.levels or is_mip_chain(img.levels), path,
                   f"image {img.name!r}: its levels are not a full mip chain")
            images.append(img)
        baked = BakedScene(
            name=doc["name"], mesh_table=table, mesh_names=[m["name"] for m in doc["meshes"]],
            streams=streams, materials=[_material(dict(m)) for m in doc["materials"]],
            images=images,
            nodes=[Node(int(n["mesh"]), mats[i], n["name"]) for i, n in enumerate(doc["nodes"])],
            lights=[_build(Light, dict(x), ("position", "color", "direction")) for x in doc["lights"]],
            cameras=[_build(Camera, dict(c), ("eye", "target", "up", "distortion")) for c in doc["cameras"]],
            source_key=doc["source"]["sha256"], source_files=list(doc["source"]["files"]),
        )
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise BakeFormatError(path, f"malformed scene description: {exc!r}") from None
    _validate_counts(baked, path)
    return baked


def load_baked_scene(path: str | os.PathLike[str], *, expected_source_key: str | None = None,
                     mmap: bool = False, policy: ResourcePolicy | None = None) -> Scene:
    """Load a `.vkpbr` file as a `Scene` (what the scene importer calls for .vkpbr files).

    Mesh arrays are views into the file's buffer; each mesh also carries `qtangents` (N, 4)
    float32 and `packed_frames` (N,) uint32. Texcoords are always present (zeros where the
    source had none). Embedded images come back decoded with their mip chain (`Image.pixels`
    level 0, `Image.mips` the rest, `Image.mips_srgb` their colour space): the renderer
    uploads them as they are. External textures stay paths (load_scene reports missing ones).

    Parameters
    ----------
    path : the baked file
    expected_source_key : when given, a file baked from other source content is rejected
    mmap : see `read_baked`
    policy : where external textures may lie (default: the baked file's folder tree; one
        outside it is reported and replaced like a missing texture).

    Raises
    ------
    BakeFormatError: see `read_baked`; also when stale (source key differs).
    """
    baked = read_baked(path, mmap=mmap)
    if expected_source_key is not None and baked.source_key != expected_source_key:
        raise BakeFormatError(path, "stale: baked from different source content; bake again")
    meshes = []
    for i, name in enumerate(baked.mesh_names):
        flags = int(baked.mesh_table[i]["flags"])

        def s(key: str, i: int = i) -> np.ndarray:
            return baked.mesh_stream(i, key)

        meshes.append(Mesh(
            name=name, positions=s("positions"), indices=s("indices"), normals=s("normals"),
            texcoords=s("texcoords"), tangents=s("tangents"),
            texcoords1=s("texcoords1") if flags & HAS_TEXCOORDS1 else None,
            colors=s("colors") if flags & HAS_COLORS else None,
            material=int(baked.mesh_table[i]["material"]),
            qtangents=s("qtangents"), packed_frames=s("packed_frames"),
        ))
    images = []
    for img in baked.images:
        if img.levels:
            images.append(Image(img.name, pixels=img.levels[0], mime_type=img.mime_type,
                                mips=tuple(img.levels[1:]), mips_srgb=img.srgb))
        else:
            if img.data is None and img.path is not None:
                images.append(policy_image(policy or ResourcePolicy(Path(path)), str(img.path),
                                           name=img.name, mime_type=img.mime_type))
            else:
                images.append(Image(img.name, data=img.data, mime_type=img.mime_type))
    return Scene(name=baked.name, meshes=meshes, materials=baked.materials, images=images,
                 nodes=baked.nodes, lights=baked.lights, cameras=baked.cameras,
                 source=Path(path))
