# The bake stage: Scene -> GPU-ready BakedScene (clean, deduplicate, optimise, frames).
#
# References: renderer-spec.md sections 4-5 (tangent frames; the course bake merged vertices
# within 1e-5, this one merges exact duplicates only, so baking never moves a vertex);
# A. Kapoulkine, meshoptimizer (vertex cache optimisation, Forsyth-style; fetch order = first
# use); Khronos glTF 2.0 spec (use the file's TANGENT when present).
"""Bake scenes into `BakedScene`s, report on them, and bake files with a content-keyed cache.

Per mesh: non-finite or out-of-range data is repaired or dropped, exact duplicate vertices
are merged, degenerate triangles (a repeated index) are removed, triangles are reordered for
the post-transform vertex cache (meshoptimizer when installed; otherwise the source order is
kept), vertices are renumbered in first-use order (fetch locality, and unreferenced vertices
disappear), tangents come from the file or from `generate_tangents`, and each frame is also
stored as a QTangent quaternion and a packed uint32. Output is deterministic: the same scene
gives the same bytes.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import logging
import os
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import numpy as np

from ..errors import BakeFormatError, SceneError
from ..json_input import SCENE_JSON_LIMITS, read_json
from ..scene.baked_file import (
    HAS_COLORS,
    HAS_TEXCOORDS,
    HAS_TEXCOORDS1,
    MESH_DTYPE,
    TANGENTS_FROM_FILE,
    BakedImage,
    BakedScene,
    read_baked,
    write_baked,
)
from ..scene.loader import load_scene
from ..scene.mips import mip_chain
from ..scene.resources import ResourcePolicy, is_regular_file, read_resource
from ..scene.textures import decode_images
from ..scene.types import SRGB_TEXTURE_SLOTS, Mesh, Scene, expand_instances, points_box
from .frames import (
    frame_angular_error_deg,
    pack_qtangent,
    qtangent_to_tbn,
    tbn_to_qtangent,
    unpack_qtangent,
)
from .tangents import generate_tangents, normalize_safe, orthonormal_tangent, tangent_uv_set


@functools.cache
def _meshopt() -> Any:
    """meshoptimizer, optional: a C++ vertex cache optimiser (the bake works, less optimally,
    without it); imported when a bake runs, not with the module (a cache hit needs none)."""
    try:
        import meshoptimizer
    except ImportError:  # pragma: no cover - depends on the environment
        return None
    return meshoptimizer

__all__ = ["bake_file", "bake_report", "bake_scene", "cached_bake", "embed_images", "embed_sources", "source_key",
           "TEXTURE_MODES"]

log = logging.getLogger(__name__)

_Z = np.array([0.0, 0.0, 1.0], dtype=np.float32)


def _finite(a: np.ndarray | None, fill: float = 0.0) -> np.ndarray | None:
    if a is None:
        return None
    a = np.asarray(a, dtype=np.float32)
    return np.where(np.isfinite(a), a, np.float32(fill))


def _vertex_normals(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Area-weighted smooth normals (the cross product's length is twice the area)."""
    fn = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]).astype(np.float64)
    corners = tri.reshape(-1)
    acc = np.stack([np.bincount(corners, np.repeat(fn[:, k], 3), len(p)) for k in range(3)], 1)
    return normalize_safe(acc, _Z)[0].astype(np.float32)


def _clean(mesh: Mesh) -> tuple[dict[str, np.ndarray], np.ndarray, int]:
    """Repair one mesh: returns (attributes, (T, 3) int64 triangles, flags)."""
    p = np.asarray(mesh.positions, dtype=np.float32).reshape(-1, 3)
    tri = np.asarray(mesh.indices, dtype=np.int64).reshape(-1, 3)
    n_vert = len(p)
    ok_vertex = np.isfinite(p).all(axis=1)
    # A triangle with an index out of range or a non-finite corner cannot be drawn: drop it.
    in_range = ((tri >= 0) & (tri < n_vert)).all(axis=1)
    tri = tri[in_range]
    tri = tri[ok_vertex[tri].all(axis=1)]
    flags = 0
    attrs = {"positions": np.where(ok_vertex[:, None], p, 0.0).astype(np.float32)}
    for name, src, flag, fill in (("texcoords", mesh.texcoords, HAS_TEXCOORDS, 0.0),
                                  ("texcoords1", mesh.texcoords1, HAS_TEXCOORDS1, 0.0),
                                  ("colors", mesh.colors, HAS_COLORS, 1.0)):
        if src is not None and len(src) == n_vert:
            attrs[name] = _finite(src, fill)
            flags |= flag
    if mesh.tangents is not None and len(mesh.tangents) == n_vert:
        attrs["tangents"] = _finite(mesh.tangents)
        flags |= TANGENTS_FROM_FILE
    if mesh.normals is None or len(mesh.normals) != n_vert:
        # No normals: flat shading (types.Mesh). Give every corner its own vertex and the
        # face normal; deduplication then re-merges corners of coplanar neighbours.
        corners = tri.reshape(-1)
        attrs = {k: v[corners] for k, v in attrs.items()}
        fp = attrs["positions"].reshape(-1, 3, 3)
        fn = normalize_safe(np.cross(fp[:, 1] - fp[:, 0], fp[:, 2] - fp[:, 0]), _Z)[0]
        attrs["normals"] = np.repeat(fn, 3, axis=0).astype(np.float32)
        tri = np.arange(len(corners), dtype=np.int64).reshape(-1, 3)
    else:
        nrm, ok = normalize_safe(_finite(mesh.normals))
        if not ok.all():  # zero or non-finite normals: use the smooth normal of the faces
            nrm[~ok] = _vertex_normals(attrs["positions"], tri)[~ok]
        attrs["normals"] = nrm
    return attrs, tri, flags


def _dedup(attrs: dict[str, np.ndarray], tri: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Merge vertices whose attributes are all bitwise equal (after -0.0 -> +0.0)."""
    key = np.concatenate([attrs[k] for k in sorted(attrs)], axis=1)  # all (N, width)
    key = np.ascontiguousarray(key + np.float32(0.0))  # x + 0.0 turns -0.0 into +0.0
    rows = key.view(np.dtype((np.void, key.shape[1] * key.itemsize))).ravel()
    _, first, inverse = np.unique(rows, return_index=True, return_inverse=True)
    attrs = {k: v[first] for k, v in attrs.items()}
    tri = inverse.reshape(-1)[tri]
    # Triangles that now repeat a vertex have no area and can never produce a fragment.
    keep = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])
    return attrs, tri[keep]


def _optimise(attrs: dict[str, np.ndarray], tri: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Vertex-cache triangle order, then first-use vertex order (drops unused vertices)."""
    idx = np.ascontiguousarray(tri.reshape(-1), dtype=np.uint32)
    if _meshopt() is not None and len(idx):
        out = np.empty_like(idx)
        _meshopt().optimize_vertex_cache(out, idx, len(idx), len(attrs["positions"]))
        idx = out
    used, first = np.unique(idx, return_index=True)
    order = used[np.argsort(first, kind="stable")]  # old vertex ids in first-use order
    remap = np.empty(len(attrs["positions"]), dtype=np.uint32)
    remap[order] = np.arange(len(order), dtype=np.uint32)
    return {k: v[order] for k, v in attrs.items()}, remap[idx]


def _bake_mesh(mesh: Mesh, uv_set: int = 0) -> tuple[dict[str, np.ndarray], int]:
    """One mesh's streams and flags; generated tangents follow UV set `uv_set` (falling back
    to TEXCOORD_0 when the mesh has no TEXCOORD_1, as the renderer's fill does)."""
    attrs, tri, flags = _clean(mesh)
    attrs, tri = _dedup(attrs, tri)
    attrs, idx = _optimise(attrs, tri)
    n = attrs["normals"]
    if flags & TANGENTS_FROM_FILE:
        t4 = attrs["tangents"]
        t = orthonormal_tangent(n.astype(np.float64), t4[:, :3].astype(np.float64))
        w = np.where(t4[:, 3] < 0.0, -1.0, 1.0)
        attrs["tangents"] = np.concatenate([t, w[:, None]], axis=1).astype(np.float32)
    else:
        uv = attrs.get("texcoords1") if uv_set == 1 and "texcoords1" in attrs else attrs.get("texcoords")
        attrs["tangents"] = generate_tangents(attrs["positions"], n, uv, idx)
    attrs["qtangents"] = tbn_to_qtangent(n, attrs["tangents"])
    attrs["packed_frames"] = pack_qtangent(attrs["qtangents"])
    attrs["indices"] = idx
    return attrs, flags


def _srgb_images(scene: Scene) -> set[int]:
    """Indices of the images some material reads as sRGB colour (base colour, emissive,
    sheen and specular colour: SRGB_TEXTURE_SLOTS)."""
    return {t.image for m in scene.materials for slot in SRGB_TEXTURE_SLOTS
            for t in (getattr(m, f"{slot}_texture"),) if t is not None}


def _images(scene: Scene) -> list[BakedImage]:
    """Image references as they are (no decoding): path or encoded bytes; decoded pixels (a
    generated texture) are stored with their full mip chain."""
    srgb = _srgb_images(scene)
    out = []
    for i, img in enumerate(scene.images):
        levels = mip_chain(np.asarray(img.pixels), i in srgb) if img.pixels is not None else []
        out.append(BakedImage(img.name, path=None if (img.data or levels) else img.path,
                              data=img.data, mime_type=img.mime_type, levels=levels,
                              srgb=bool(levels) and i in srgb))
    return out


@np.errstate(under="ignore")  # subnormal input data underflows harmlessly
def bake_scene(scene: Scene, progress: bool = False) -> BakedScene:
    """Bake every mesh of `scene` into one set of GPU-ready streams.

    Parameters
    ----------
    scene : the source scene (not modified)
    progress : show a tqdm bar over meshes

    Returns
    -------
    BakedScene with streams positions (V, 3), normals (V, 3), texcoords (V, 2), tangents
    (V, 4), qtangents (V, 4) float32, packed_frames (V,) uint32, indices (I,) uint32 local to
    each mesh, plus texcoords1 / colors when any mesh has them. Images are referenced (a file
    path, or the encoded bytes a .glb embeds), not decoded; decoded pixels are stored with
    their mip chain; `embed_images` replaces references by mip chains.
    """
    start = time.perf_counter()
    _warn_unbaked(scene)
    parts: list[dict[str, np.ndarray]] = []
    table = np.zeros(len(scene.meshes), dtype=MESH_DTYPE)
    first_v = first_i = 0
    from tqdm import tqdm  # (0.1-0.25 s to import: only when a bake runs)

    meshes = tqdm(scene.meshes, desc="bake", unit="mesh", disable=not progress, leave=False)
    for i, mesh in enumerate(meshes):
        material = scene.materials[mesh.material] if 0 <= mesh.material < len(scene.materials) else None
        attrs, flags = _bake_mesh(mesh, tangent_uv_set(material))
        parts.append(attrs)
        nv, ni = len(attrs["positions"]), len(attrs["indices"])
        p = attrs["positions"]
        lo, hi = points_box(p) if nv else (np.zeros(3), np.zeros(3))
        table[i] = (first_v, nv, first_i, ni, mesh.material, flags, lo, hi)
        first_v, first_i = first_v + nv, first_i + ni
    if first_v >= 2**32 or first_i >= 2**32:
        raise ValueError("scene too large for 32-bit stream offsets")

    def cat(name: str, width: int, dtype: type, fill: float = 0.0) -> np.ndarray:
        chunks = [a[name] if name in a else np.full((len(a["positions"]), width), fill, dtype)
                  for a in parts]
        shape = (0, width) if width > 1 else (0,)
        return np.concatenate(chunks).astype(dtype, copy=False) if chunks else np.zeros(shape, dtype)

    streams = {"positions": cat("positions", 3, np.float32), "normals": cat("normals", 3, np.float32),
               "texcoords": cat("texcoords", 2, np.float32), "tangents": cat("tangents", 4, np.float32),
               "qtangents": cat("qtangents", 4, np.float32),
               "packed_frames": cat("packed_frames", 1, np.uint32).reshape(-1),
               "indices": cat("indices", 1, np.uint32).reshape(-1)}
    if any("texcoords1" in a for a in parts):
        streams["texcoords1"] = cat("texcoords1", 2, np.float32)
    if any("colors" in a for a in parts):
        streams["colors"] = cat("colors", 4, np.float32, 1.0)
    return BakedScene(
        name=scene.name, mesh_table=table, mesh_names=[m.name for m in scene.meshes],
        streams=streams, materials=list(scene.materials), images=_images(scene),
        nodes=expand_instances(scene.nodes), lights=list(scene.lights), cameras=list(scene.cameras),
        bake_seconds=time.perf_counter() - start,
    )


@np.errstate(under="ignore")
def bake_report(scene: Scene, baked: BakedScene) -> dict[str, Any]:
    """Numbers about a bake: memory per vertex, frame precision, sizes, time.

    Returns
    -------
    dict with ``bytes_per_vertex`` {"vectors", "quat", "packed"} (position + uv(s) + frame,
    from the stream dtypes; TEXCOORD_1 counts only when baked), ``tbn_error_deg`` {"mean",
    "p99", "max"} (packed vs float frame, N/T/B worst angle per vertex), ``quat_error_deg``
    (same for the float quaternion), ``vertices``, ``triangles``, ``source_vertices``,
    ``source_triangles``, ``meshes``, ``seconds``.
    """
    s = baked.streams

    def size(name: str) -> int:
        a = s[name]
        return int(a.itemsize * (a.shape[1] if a.ndim > 1 else 1))

    # A second UV set is a stream of its own only when some mesh has one (texcoords1).
    base = size("positions") + size("texcoords") + (size("texcoords1") if "texcoords1" in s else 0)
    n, t = s["normals"], s["tangents"]

    def stats(err: np.ndarray) -> dict[str, float]:
        if not len(err):
            return {"mean": 0.0, "p99": 0.0, "max": 0.0}
        return {"mean": float(err.mean()), "p99": float(np.percentile(err, 99)),
                "max": float(err.max())}

    packed = frame_angular_error_deg(n, t, *qtangent_to_tbn(unpack_qtangent(s["packed_frames"])))
    quat = frame_angular_error_deg(n, t, *qtangent_to_tbn(s["qtangents"]))
    return {
        "bytes_per_vertex": {"vectors": base + size("normals") + size("tangents"),
                             "quat": base + size("qtangents"),
                             "packed": base + size("packed_frames")},
        "tbn_error_deg": stats(packed),
        "quat_error_deg": stats(quat),
        "vertices": int(len(s["positions"])),
        "triangles": int(len(s["indices"]) // 3),
        "source_vertices": int(sum(m.vertex_count for m in scene.meshes)),
        "source_triangles": int(sum(m.triangle_count for m in scene.meshes)),
        "meshes": len(scene.meshes),
        "seconds": float(baked.bake_seconds),
        "vertex_cache_order": "meshoptimizer" if _meshopt() is not None else "source order",
    }


def _dependencies(path: Path, allow_outside_paths: bool = False) -> list[Path]:
    """Files a source depends on: a .gltf's external buffers and images, an .obj's mtllibs
    (those the path policy lets the loader read: regular files, inside the source's folder
    tree unless `allow_outside_paths`)."""
    deps: list[Path] = []
    try:
        if path.suffix.lower() == ".gltf":
            doc = read_json(path, SCENE_JSON_LIMITS)
            uris = [x.get("uri") for x in doc.get("buffers", []) + doc.get("images", [])]
            deps = [path.parent / u for u in uris if u and not u.startswith("data:")]
        elif path.suffix.lower() == ".obj":
            with open(path, encoding="utf-8", errors="replace") as f:
                deps = [path.parent / line.split(None, 1)[1].strip()
                        for line in f if line.startswith("mtllib ")]
    except (OSError, ValueError, AttributeError, TypeError):  # JsonError is a ValueError
        return []  # the loader reports a broken source; the key then covers the main file
    policy = ResourcePolicy(path, allow_outside=allow_outside_paths)
    out = set()
    for d in deps:
        try:
            file = policy.resolve(os.path.relpath(unquote(str(d)), path.parent))
        except (SceneError, ValueError):
            continue  # refused: the loader says so (or never reads it)
        if is_regular_file(file):
            out.add(file)
    return sorted(out)


def source_key(path: str | Path, allow_outside_paths: bool = False) -> tuple[str, list[str]]:
    """sha256 over a source file and its dependencies (names, sizes and contents).

    Returns
    -------
    (hex digest, file names relative to the source's folder)
    """
    path = Path(path)
    files = [path, *_dependencies(path, allow_outside_paths)]
    h = hashlib.sha256()
    names = []
    for f in files:
        name = f.name if f == path else Path(os.path.relpath(f, path.parent)).as_posix()
        data = read_resource(f)
        h.update(f"{name}\0{len(data)}\0".encode())
        h.update(data)
        names.append(name)
    return h.hexdigest(), names


def embed_images(scene: Scene, baked: BakedScene, workers: int | None = None) -> int:
    """Store every image of `scene` in `baked` as decoded RGBA8 with its full mip chain
    (`vkpbr.scene.mips.mip_chain`, filtered in linear light for sRGB colour maps), so that
    loading neither decodes nor filters. Images that cannot be decoded (a missing file, corrupt
    data) keep their reference. Decoding and filtering run on `workers` threads (default
    min(8, CPU count)); NumPy and Pillow release the GIL for the heavy parts.

    Returns
    -------
    The number of images embedded.
    """
    srgb = _srgb_images(scene)
    workers = max(1, workers or min(8, os.cpu_count() or 1))
    pixels = decode_images(scene, workers=workers)  # a Scene: errors name its file
    with ThreadPoolExecutor(workers) as pool:
        chains = list(pool.map(lambda ip: None if ip[1] is None else mip_chain(ip[1], ip[0] in srgb),
                               enumerate(pixels)))
    images = list(baked.images)
    for i, (img, levels) in enumerate(zip(scene.images, chains, strict=True)):
        if levels is not None:
            images[i] = BakedImage(img.name, mime_type=None, levels=levels, srgb=i in srgb)
    baked.images = images
    return sum(levels is not None for levels in chains)


# The textures a bake writes (`bake_file(textures=...)`, `vkpbr bake --textures`).
TEXTURE_MODES = ("source", "decoded", "external")
_MAGIC = ((b"\x89PNG\r\n\x1a\n", "image/png"), (b"\xff\xd8\xff", "image/jpeg"),
          (b"\xabKTX 20\xbb\r\n\x1a\n", "image/ktx2"), (b"RIFF", "image/webp"),
          (b"GIF8", "image/gif"), (b"BM", "image/bmp"))


def _sniff_mime(data: bytes, fallback: str | None) -> str | None:
    """The MIME type the first bytes of an encoded image say, else `fallback`."""
    return next((mime for magic, mime in _MAGIC if data.startswith(magic)), fallback)


def embed_sources(scene: Scene, baked: BakedScene, source: Path) -> int:
    """Store each texture the source names as a file in `baked` as that file's bytes, as
    they are (PNG, JPEG, KTX2: compressed, decoded at load like a .glb's images), so the
    baked file is self-contained and about as large as its sources. Returns how many.

    Raises
    ------
    SceneError : a texture that cannot be read (missing, refused by the path policy, over
        the texture file limit): the baked file would render it untextured.
    """
    from ..scene.limits import limits

    cap = limits().max_texture_file_bytes
    images = list(baked.images)
    count = 0
    for i, (img, b) in enumerate(zip(scene.images, images, strict=True)):
        if b.path is None:
            continue
        why = img.refused
        data = b""
        if not why:
            try:
                data = read_resource(b.path, max_bytes=cap + 1)
            except OSError as exc:
                why = exc.strerror or str(exc)
            else:
                if len(data) > cap:
                    why = f"over the {cap:,}-byte texture file limit"
        if why:
            raise SceneError(source, f"texture {img.name}: cannot embed it ({why}); the baked "
                                     "file would render it untextured (fix the file, or bake "
                                     "with --textures external)")
        images[i] = BakedImage(b.name, data=data, mime_type=_sniff_mime(data, img.mime_type))
        count += 1
    baked.images = images
    return count


def _check_external(source: Path, out_path: Path, images: list[BakedImage],
                    allow_outside_paths: bool) -> None:
    """--textures external: every referenced file exists and, unless `allow_outside_paths`,
    lies in the baked file's folder tree (else loading it renders untextured)."""
    tree = out_path.resolve().parent
    for img in images:
        if img.path is None:
            continue
        path = Path(img.path).resolve()
        if not path.is_file():
            raise SceneError(source, f"texture {img.name}: no such file; the baked file would "
                                     "render it untextured")
        if not allow_outside_paths and not path.is_relative_to(tree):
            raise SceneError(source, f"texture {img.name} lies outside {tree}, the baked file's "
                                     "folder: loading it would render untextured; bake with "
                                     "--textures source (the default) to store it inside, "
                                     "or write the .vkpbr beside the source")


def _external_textures_note(out_path: Path, images: list[BakedImage]) -> str | None:
    """One line about the textures a baked file refers to on disk, or None if there are none."""
    external = [Path(img.path).resolve() for img in images if img.path is not None]
    if not external:
        return None
    folders = sorted({f.parent for f in external})
    where = (str(folders[0]) if len(folders) == 1
             else f"{len(folders)} folders under {os.path.commonpath(folders)}")
    rel = None
    if len(folders) == 1:
        with contextlib.suppress(ValueError):  # another drive (Windows): stored absolute
            rel = os.path.relpath(folders[0], out_path.resolve().parent)
    tree = out_path.resolve().parent
    outside = "" if all(f.is_relative_to(tree) for f in external) else (
        "; they lie outside the baked file's folder, so loading it needs --allow-outside-paths")
    return (f"{out_path.name}: {len(external)} of {len(images)} textures stay external files; they "
            f"must stay in {where}" + (f" ({Path(rel).as_posix()} from the baked file)" if rel else "")
            + ", or bake with --textures source to store them inside" + outside)


def _warn_unbaked(scene: Scene) -> None:
    """One line when the scene moves: the baked format keeps the rest pose only (its nodes
    are flat world matrices), so animations, skins and morph targets are not stored."""
    morphs = sum(bool(m.morph_targets) for m in scene.meshes)
    skinned = sum(m.joints is not None for m in scene.meshes)
    if scene.animations or scene.skins or morphs:
        warnings.warn(f"{scene.source or scene.name}: animations ({len(scene.animations)}), "
                      f"skins ({len(scene.skins)}, {skinned} skinned meshes) and morph targets "
                      f"({morphs} meshes) are not baked: the baked file is the rest pose "
                      "(load the glTF file to animate it)", stacklevel=3)


def bake_file(source_path: str | Path, out_path: str | Path, embed_textures: bool = False,
              progress: bool = True, strict: bool = False,
              allow_outside_paths: bool = False, variant: str | None = None,
              textures: str | None = None, _cache: bool = False) -> dict[str, Any]:
    """Load a scene file, bake it, write `out_path`.

    Parameters
    ----------
    source_path : any format `load_scene` reads.
    out_path : the .vkpbr file to write (atomically).
    textures : what the file holds of textures the source names as files: "source" (the
        default) their files' bytes as they are (`embed_sources`: self-contained, about as
        large as the sources), "decoded" RGBA8 mip chains (`embed_images`: loads fastest,
        ~30x larger), "external" references to the files (they must stay where they are;
        one outside the baked file's folder is an error unless `allow_outside_paths`).
        Textures the source embeds (a .glb's) are stored as they are in every mode.
    embed_textures : the earlier name of textures="decoded".
    progress : a tqdm bar over meshes.
    strict : a missing texture file is an error (see `load_scene`).
    allow_outside_paths : read files the source names outside its folder tree (see
        `load_scene`).
    variant : the glTF material variant baked (KHR_materials_variants; see `load_scene`).

    Returns
    -------
    `bake_report` plus ``out``, ``file_bytes``, ``load_seconds``, ``embed_seconds``,
    ``write_seconds``, ``source_sha256``, ``embedded_textures``, ``external_textures`` and
    ``outside_textures`` (external ones outside the baked file's folder: loading it then needs
    ``allow_outside_paths``).
    Textures left as files are logged (INFO, "vkpbr.bake.bake"): how many, and where they must
    stay for the baked file to find them.
    """
    from vkpbr.user_paths import check_writable_file

    source_path, out_path = Path(source_path), Path(out_path)
    check_writable_file(out_path, "bake_file: out")  # before the work, not after it
    t0 = time.perf_counter()
    scene = load_scene(source_path, strict=strict, allow_outside_paths=allow_outside_paths,
                       variant=variant)
    t1 = time.perf_counter()
    baked = bake_scene(scene, progress=progress)
    baked.source_key, baked.source_files = source_key(source_path, allow_outside_paths)
    te = time.perf_counter()
    mode = textures or ("decoded" if embed_textures else "source")
    if mode not in TEXTURE_MODES:
        raise ValueError(f"textures={mode!r}: expected one of {', '.join(TEXTURE_MODES)}")
    embedded = embed_images(scene, baked) if mode == "decoded" else 0
    if mode != "external":  # (what "decoded" could not decode fails here, naming it)
        embedded += embed_sources(scene, baked, source_path)
    elif not _cache:
        _check_external(source_path, out_path, baked.images, allow_outside_paths)
    t2 = time.perf_counter()
    size = write_baked(out_path, baked)
    note = _external_textures_note(out_path, baked.images)
    if note:
        log.info("%s", note)
    report = bake_report(scene, baked)
    report.update(out=str(out_path), file_bytes=size, load_seconds=t1 - t0,
                  embed_seconds=t2 - te, write_seconds=time.perf_counter() - t2,
                  source_sha256=baked.source_key, embedded_textures=embedded,
                  external_textures=sum(img.path is not None for img in baked.images),
                  outside_textures=sum(img.path is not None and not Path(img.path).resolve()
                                       .is_relative_to(out_path.resolve().parent)
                                       for img in baked.images))
    return report


# cached_bake's index of the keys it computed (in the cache folder): a source whose files have
# not changed (size and modification time) since is not read and hashed again.
KEYS_FILE = "bake-keys.json"
_KEYS_MAX = 20_000  # entries kept (the oldest are dropped)
_RACY_NS = 2_000_000_000  # a file changed this close to when its key was recorded: hash it


def _file_stats(files: list[Path]) -> list[list[Any]] | None:
    try:
        return [[str(f), st.st_size, st.st_mtime_ns] for f in files for st in [f.stat()]]
    except OSError:
        return None


def _read_keys(cache_dir: Path) -> dict[str, Any]:
    try:
        data = read_json(cache_dir / KEYS_FILE)
    except (OSError, ValueError):  # none yet, or unreadable: keys are computed again
        return {}
    return data if isinstance(data, dict) else {}


def _remembered(cache_dir: Path, entry: str, stats: list[list[Any]] | None) -> Path | None:
    """The bake recorded for `entry` when its files' sizes and times are those recorded, were
    older than the record by _RACY_NS (a file written within the file system's clock tick of
    the record could have changed unseen: git's "racily clean"), and the bake is unchanged."""
    rec = _read_keys(cache_dir).get(entry)
    if stats is None or not isinstance(rec, dict) or rec.get("stats") != stats:
        return None
    recorded = rec.get("recorded_ns")
    if not isinstance(recorded, int) or any(m >= recorded - _RACY_NS for _, _, m in stats):
        return None
    out = Path(str(rec.get("out")))
    if out.parent != cache_dir or _file_stats([out]) != [rec.get("out_stat")]:
        return None
    return out


def _remember(cache_dir: Path, entry: str, stats: list[list[Any]] | None, out: Path) -> None:
    out_stat = _file_stats([out])
    if stats is None or out_stat is None:
        return
    keys = _read_keys(cache_dir)
    keys.pop(entry, None)
    keys[entry] = {"stats": stats, "out": str(out), "out_stat": out_stat[0],
                   "recorded_ns": time.time_ns()}
    for old in list(keys)[: max(0, len(keys) - _KEYS_MAX)]:
        del keys[old]
    from ..atomic import atomic_writer

    try:
        with atomic_writer(cache_dir / KEYS_FILE) as f:
            f.write(json.dumps(keys).encode())
    except OSError as exc:  # a read-only cache: keys are hashed again next time
        log.debug("%s: not written (%s)", cache_dir / KEYS_FILE, exc)


def cached_bake(source_path: str | Path, cache_dir: str | Path,
                allow_outside_paths: bool = False, variant: str | None = None) -> Path:
    """Path of an up-to-date bake of `source_path` in `cache_dir`, baking only when needed.

    The file name carries the source's content hash, so an edited source misses the cache;
    an existing file that fails validation is baked again. The hash is computed again only
    when a file of the source changed size or modification time since it was last computed
    (KEYS_FILE in `cache_dir`; a file changed within 2 s of that is hashed regardless), so a
    hit reads neither the sources nor the bake: loading it checks the bake's checksums. Load the result with
    ``load_scene(out, root=source_path.parent)``: its external textures lie beside the source,
    not in the cache. A material `variant` is baked in: each variant has its own file.
    """
    from vkpbr.user_paths import check_writable_folder

    source_path, cache_dir = Path(source_path), Path(cache_dir)
    check_writable_folder(cache_dir, "cache folder", f"{source_path.stem}-0123456789abcdef.vkpbr")
    tag = "" if variant is None else "-variant-" + hashlib.sha256(variant.encode()).hexdigest()[:8]
    entry = f"{source_path.resolve()}|{int(allow_outside_paths)}{tag}"
    stats = _file_stats([source_path, *_dependencies(source_path, allow_outside_paths)])
    out = _remembered(cache_dir, entry, stats)
    if out is not None:  # nothing changed since its key was computed: no hashing, no read
        return out
    key, _ = source_key(source_path, allow_outside_paths)
    out = cache_dir / f"{source_path.stem}-{key[:16]}{tag}.vkpbr"
    if out.is_file():
        try:
            if read_baked(out).source_key == key:
                _remember(cache_dir, entry, stats, out)
                return out
        except BakeFormatError:
            pass
    cache_dir.mkdir(parents=True, exist_ok=True)
    # The cache keeps references: its files are made again from the sources at will, and
    # load with root=source_path.parent.
    bake_file(source_path, out, progress=False, allow_outside_paths=allow_outside_paths,
              variant=variant, textures="external", _cache=True)
    _remember(cache_dir, entry, stats, out)
    return out
