"""A Scene uploaded to the GPU: vertex streams, indices, textures, material descriptor sets.

Geometry: every mesh's streams are concatenated into one buffer per attribute (position,
texcoord, normal, tangent, QTangent, packed frame) plus one index buffer, so a frame binds
vertex buffers once per pipeline and each draw is one vkCmdDrawIndexed with offsets.
The QTangent and packed streams are built on first use of their path (`ensure_streams`):
the default vectors path never pays for them (~0.4 s of Sponza's load on 2 CPU cores); the
viewer asks for all three up front. On GPUs, whose first auto frames take the compute path
(which binds them), they are built on a thread while the textures upload. A
TEXCOORD_1 stream exists only when some mesh has TEXCOORD_1; otherwise the TEXCOORD_0 buffer
is bound for the shader's second UV input, so such scenes (Sponza) cost no extra memory.

COLOR_0 (glTF vertex colours, multiplying the base colour) is an RGBA16 UNORM stream when some
mesh has it (meshes without get white); otherwise one white value is bound with stride 0.

Materials: each texture carries its own UV set and KHR_texture_transform into the MATERIAL
block (`uv_transform_rows`).

Textures: one GPU image per (source image, colour space), full mip chain (the image's own
when it brings one for that colour space, as baked files do: uploaded as it is; otherwise made
by GPU blits, which cost nothing next to the ~1.5 s that NumPy takes for Sponza's 71 Mpixels
on 2 cores, so decoded scenes keep them); the scalar maps
(metallic, roughness, occlusion) are views with a component swizzle that moves the wanted
channel into R, so glTF's packed metallic-roughness texture is stored once and read twice.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import functools
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer, upload_buffer
from vkpbr.gpu.descriptors import DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.gpu.image import Image, ImageView, Sampler, SamplerSpec, TextureUploader
from vkpbr.render import layouts as L
from vkpbr.render.deform import convex_weights, deformed_records
from vkpbr.scene.material_table import PARAMS, TEXTURES
from vkpbr.scene.types import (
    SRGB_TEXTURE_SLOTS,
    Material,
    Mesh,
    Node,
    Scene,
    TextureRef,
    expand_instances,
    points_box,
)

__all__ = ["GpuScene", "Draw", "drawn", "draw_nodes", "material_block", "prepare_mesh", "uv_transform_rows"]

_SWIZZLE = {0: "rrrr", 1: "gggg", 2: "bbbb", 3: "aaaa"}
# Tangent-space normals and other linear vectors (RGB as stored, no swizzle).
_NORMAL_SLOTS = frozenset(s.name for s in TEXTURES if s.kind in ("normal", "vector"))
STREAMS = ("positions", "texcoords", "normals", "tangents")  # built at load
LAZY_STREAMS = ("qtangents", "packed_frames")  # built by ensure_streams on first use


def default_layers() -> dict[str, np.ndarray]:
    """The MATERIAL block's layer factors (layouts.LAYER_FIELDS) of a material with none of
    the KHR_materials_* extensions, float32: generated.glsl's MATERIAL_DEFAULT_* (shade.glsl)."""
    return dict(L.LAYER_DEFAULTS)


def has_default_layers(block: np.ndarray) -> bool:
    """Whether a material's block shades as the default layers (no layer texture, no coat
    normal map, every factor the default's): shade.glsl's SHADE_LAYERS false gives it."""
    return bool(default_layer_mask([block])[0])


def default_layer_mask(blocks: list[np.ndarray]) -> np.ndarray:
    """`has_default_layers` of every block at once, (M,) bool: the blocks as one table, a
    comparison a field (a scene change asks for every material: MetalRoughSpheres' 98 had
    taken ~2,000 small comparisons, ~15 ms of Python a swap)."""
    if not blocks:
        return np.zeros(0, bool)
    table = np.array(blocks, dtype=blocks[0].dtype).reshape(len(blocks))
    maps = L.MATERIAL_HAS_LAYER_MAPS | L.MATERIAL_HAS_CLEARCOAT_NORMAL_MAP
    ok = (table["flags"].astype(np.int64) & maps) == 0
    for f, v in default_layers().items():
        got = table[f].astype(np.float32).reshape(len(table), -1)
        ok &= np.all(got == np.asarray(v, np.float32).reshape(1, -1), axis=1)
    return ok


def _shared_metallic_roughness(mat: Material) -> bool:
    """Whether the material's metallic and roughness maps are one texture read the same way
    (glTF's metallicRoughnessTexture: roughness in G), differing only in their channel."""
    m, r = mat.metallic_texture, mat.roughness_texture
    return (m is not None and r is not None and r.channel == 1
            and dataclasses.replace(m, channel=1) == r)


@dataclass
class Draw:
    """One indexed draw: a mesh instance with its material and pipeline class."""

    mesh: int
    material: int
    first_index: int
    index_count: int
    vertex_offset: int
    model: np.ndarray  # (4, 4) float64 model matrix as loaded (the scene state's rest pose)
    alpha_mode: str  # the material's: "opaque" | "mask" | "blend" (render/passes.py classifies)
    double_sided: bool
    casts_shadows: bool = True  # drawn into shadow maps (Material.casts_shadows)
    node: int = -1  # the scene node it draws (the dataset outputs' instance table)
    instance: int = -1  # which of the node's EXT_mesh_gpu_instancing instances; -1: none
    deformed: bool = False  # posed by the deform step (render/deform.py): never culled
    skinned: bool = False  # deformed by a skin: posed in world space (its model: the frame)
    unbounded: bool = False  # deformed with no bounding sphere (weights not convex): never culled
    center: np.ndarray = field(default_factory=lambda: np.zeros(3))  # world, for blend sorting


def _uv_stream(mesh: Mesh, uv: np.ndarray | None, fallback: np.ndarray) -> np.ndarray:
    """(N, 2) float32 UVs, `fallback` when the mesh has none; a wrong length is an error
    (it would make the GPU read past the stream)."""
    if uv is None:
        return fallback
    if np.shape(uv) != (mesh.vertex_count, 2):
        raise ValueError(f"mesh {mesh.name!r}: texcoords of shape {np.shape(uv)}, need ({mesh.vertex_count}, 2)")
    return np.ascontiguousarray(uv, dtype=np.float32)


def _color_stream(mesh: Mesh) -> np.ndarray:
    """COLOR_0 as (N, 4) RGBA16 UNORM (linear, as glTF; white where the mesh has none):
    8 bytes a vertex, with no visible loss next to float32."""
    if mesh.colors is None:
        return np.full((mesh.vertex_count, 4), 65535, np.uint16)
    c = np.asarray(mesh.colors, dtype=np.float32)
    if c.shape != (mesh.vertex_count, 4):
        raise ValueError(f"mesh {mesh.name!r}: colors of shape {c.shape}, need ({mesh.vertex_count}, 4)")
    c = np.nan_to_num(c, nan=1.0, posinf=1.0, neginf=0.0)
    return np.round(np.clip(c, 0.0, 1.0) * 65535.0).astype(np.uint16)


def prepare_mesh(mesh: Mesh, tangent_uv_set: int = 0, frames: bool = True) -> dict[str, np.ndarray]:
    """All vertex streams of a mesh, computing what the file did not supply.

    Returns positions (N,3) f32, texcoords (N,2) f32, texcoords1 (N,2) f32, normals (N,3) f32,
    tangents (N,4) f32, colors (N,4) u16 (COLOR_0, white if absent), qtangents (N,4) f32 and
    packed_frames (N,) u32. A mesh without
    TEXCOORD_1 gets its TEXCOORD_0 as texcoords1: then it renders the same whether or not some
    other mesh of the scene brings a TEXCOORD_1 stream (scenes with none bind TEXCOORD_0 for
    set 1 too), and a texture asking for a set the mesh lacks still gets real coordinates.
    Generated tangents follow `tangent_uv_set`, the set the normal texture reads. With
    `frames=False`, qtangents / packed_frames are only those the mesh brings (else None).
    """
    from vkpbr.bake.frames import pack_qtangent, tbn_to_qtangent
    from vkpbr.bake.tangents import generate_tangents

    n = mesh.vertex_count
    pos = np.ascontiguousarray(mesh.positions, dtype=np.float32)
    uv = _uv_stream(mesh, mesh.texcoords, np.zeros((n, 2), np.float32))
    uv1 = _uv_stream(mesh, mesh.texcoords1, uv)
    if mesh.normals is None:
        raise ValueError(f"mesh {mesh.name!r} has no normals (loaders must supply them)")
    nrm = np.ascontiguousarray(mesh.normals, dtype=np.float32)
    colors = _color_stream(mesh)
    idx = np.ascontiguousarray(mesh.indices, dtype=np.uint32)
    tan = mesh.tangents
    if tan is None:
        tan = generate_tangents(pos, nrm, uv1 if tangent_uv_set == 1 else uv, idx)
    tan = np.ascontiguousarray(tan, dtype=np.float32)
    q = getattr(mesh, "qtangents", None)
    packed = getattr(mesh, "packed_frames", None)
    if frames:
        q = tbn_to_qtangent(nrm, tan) if q is None else q
        packed = pack_qtangent(q) if packed is None else packed
    return {
        "positions": pos,
        "texcoords": uv,
        "texcoords1": uv1,
        "colors": colors,
        "normals": nrm,
        "tangents": tan,
        "qtangents": None if q is None else np.ascontiguousarray(q, dtype=np.float32),
        "packed_frames": None if packed is None else np.ascontiguousarray(packed, dtype=np.uint32),
    }


def uv_transform_rows(ref: TextureRef | None) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A texture's MATERIAL rows (layouts._uv_fields): KHR_texture_transform's
    uv' = T(offset) R(rotation) S(scale) uv as the two rows of a 2x3 matrix, with the UV set in
    row 0's fourth component. glTF: R = [[cos, sin], [-sin, cos]] (counter-clockwise in UV
    space, whose v points down). No texture: identity on set 0."""
    if ref is None:
        return (1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0)
    c, s = float(np.cos(ref.rotation)), float(np.sin(ref.rotation))
    (ox, oy), (sx, sy) = ref.offset, ref.scale
    return (c * sx, s * sy, ox, float(ref.texcoord)), (-s * sx, c * sy, oy, 0.0)


def _concat(arrays: list[np.ndarray], dtype: type, width: int) -> np.ndarray:
    if not arrays:
        return np.zeros((1, width), dtype)
    return np.ascontiguousarray(np.concatenate(arrays), dtype=dtype)


class MaterialSets:
    """Material i's descriptor set (its textures and its MATERIAL block), made when a pass
    about to bind it asks (`prepare`: a pass's sets in one allocation and one write) or the
    first time it is indexed (`sets[i]`): a file can list tens of thousands of materials that
    no primitive uses, and a set costs ~0.5 ms of Python to write (16 bindings, each a struct
    of the Vulkan binding), so unused ones cost nothing."""

    def __init__(self, device: Device, pool: DescriptorPool, layout: DescriptorSetLayout,
                 ubo: Buffer, stride: int, textures: list[list[tuple[ImageView, Sampler]]],
                 base: int = 0) -> None:
        self.device, self.pool, self.layout = device, pool, layout
        self.ubo, self.stride, self.textures = ubo, stride, textures
        self.base = base  # the frame slot's copy of the blocks in `ubo`
        self._sets: dict[int, object] = {}

    def __len__(self) -> int:
        return len(self.textures)

    def __getitem__(self, i: int) -> object:
        if i not in self._sets:
            if not -len(self) <= i < len(self):
                raise IndexError(f"material {i} of {len(self)}")
            self.prepare([i % len(self)])
        return self._sets[i % len(self)]

    def prepare(self, materials: Iterable[int]) -> None:
        """The sets of `materials` (indices in range) that are not made yet, made at once:
        one allocation and one write for all (a pass about to bind them: render/passes.py)."""
        missing = sorted({int(i) for i in materials} - self._sets.keys())
        if not missing:
            return
        writer = DescriptorWriter(self.device)
        for i, dset in zip(missing, self.pool.allocate_many(self.layout, len(missing)),
                           strict=True):
            for binding, (view, sampler) in enumerate(self.textures[i]):
                writer.sampler(dset, binding, view, sampler)
            writer.uniform(dset, L.MATERIAL_BINDING, self.ubo, L.MATERIAL.size,
                           offset=self.base + i * self.stride)
            self._sets[i] = dset
        writer.update()


class GpuScene:
    """Owns the GPU copies of one Scene. Built by `Renderer`; destroy with `destroy()`."""

    def __init__(
        self, device: Device, scene: Scene, material_layout: DescriptorSetLayout, slots: int = 1,
        ahead: Any = None,
    ) -> None:
        """`ahead`: the vkpbr.bake.ahead.SceneAhead that loaded `scene`, whose images decoded
        while the device was made are used where this device would decode them the same."""
        self.device = device
        self._ahead = ahead
        self.slots = slots  # frame slots: each has its own copy of the material blocks
        self.scene = scene
        self._owned: list = []
        self._boxes: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}  # (mesh_box)
        self.timings: dict[str, float] = {}
        # Skinned and morphed draw records: each gets its own posed copy of its mesh's
        # vertices after the meshes' (render/deform.py).
        self.deformed = deformed_records(scene)
        t0 = time.perf_counter()
        # Decode images (Pillow, threads, GIL released; loaded ahead: done already or under
        # way) while the geometry streams are built and sent; the textures then go in the same
        # uploader's batches, and the whole upload is waited for once (its flush).
        uploader = TextureUploader(self.device)
        try:
            with concurrent.futures.ThreadPoolExecutor(1) as pool:
                decoding = pool.submit(self._decoded_pixels)
                self._upload_geometry(uploader)
                uploader.submit()  # (copied on the GPU while the decode finishes)
                t1 = time.perf_counter()
                pixels, blocks = decoding.result()
                t_decoded = time.perf_counter()  # (textures' share spent waiting on the decode)
            self._frames = self._start_frames()
            self._upload_textures(pixels, blocks, uploader)
        except BaseException:
            uploader.abandon()  # (no batch left in flight; the caller destroys the rest)
            raise
        t2 = time.perf_counter()
        self._create_materials(material_layout)
        self.draws = self._build_draws()
        self.timings.update(geometry=t1 - t0, textures=t2 - t1, materials=time.perf_counter() - t2)
        self.decode_wait = t_decoded - t1  # (benchmarks/bench_load.py)
        self.upload_stats = uploader.stats  # (the same: where the upload's seconds went)

    def mesh_box(self, mesh: int) -> tuple[np.ndarray, np.ndarray]:
        """Mesh `mesh`'s (min, max) over its positions (per axis, in their dtype), computed
        once: the draws, the scene state, the bounds and both culling-sphere tables ask for
        each box (MetalRoughSpheresNoTextures' 0.5M vertices: ~10 ms each on 2 cores, on
        every scene change). Read-only; made again if the mesh's positions are replaced."""
        p = self.scene.meshes[mesh].positions
        got = self._boxes.get(mesh)
        if got is None or got[0] is not p:
            lo, hi = points_box(p)
            lo.flags.writeable = hi.flags.writeable = False
            got = self._boxes[mesh] = (p, lo, hi)
        return got[1], got[2]

    def _own(self, obj):  # noqa: ANN001, ANN202 - any gpu object
        self._owned.append(obj)
        return obj

    # --- geometry ---------------------------------------------------------------------------
    def _upload_geometry(self, uploader: TextureUploader | None = None) -> None:
        """Every mesh's streams and indices (and the posed regions after them) through
        `uploader`'s batches, sent by its caller; None: uploaded now (instances.py's regrowth)."""
        if uploader is None:
            uploader = TextureUploader(self.device)
            try:
                self._upload_geometry(uploader)
            except BaseException:
                uploader.abandon()
                raise
            uploader.flush()
            return
        per_mesh = [prepare_mesh(m, self._tangent_uv_set(m), frames=False)
                    for m in self.scene.meshes]
        self.vertex_offsets = np.cumsum([0] + [m.vertex_count for m in self.scene.meshes])
        regions = per_mesh + [per_mesh[r.mesh] for r in self.deformed]  # posed copies last
        sizes = [m.vertex_count for m in self.scene.meshes] + [
            self.scene.meshes[r.mesh].vertex_count for r in self.deformed]
        self.posed_offsets = [int(o) for o in np.cumsum([0] + sizes)[len(per_mesh):-1]]
        self.index_offsets = np.cumsum([0] + [len(m.indices) for m in self.scene.meshes])
        self.streams: dict[str, Buffer] = {}
        self.stream_bytes: dict[str, int] = {}
        self.has_texcoords1 = any(m.texcoords1 is not None for m in self.scene.meshes)
        self.has_colors = any(m.colors is not None for m in self.scene.meshes)
        optional = (("texcoords1",) if self.has_texcoords1 else ()) + (
            ("colors",) if self.has_colors else ())
        uploads = {name: [p[name] for p in regions] or [np.zeros(4, np.uint8)]
                   for name in STREAMS + optional}
        # Per mesh (normal, tangent, QTangent or None, packed or None) for ensure_streams.
        self._frame_sources: list[tuple] | None = [
            (p["normals"], p["tangents"], p["qtangents"], p["packed_frames"]) for p in regions]
        if not self.has_colors:
            # COLOR_0 absent everywhere: one white RGBA16 value, read with stride 0.
            uploads["colors"] = [np.full(4, 65535, np.uint16)]
        indices = [np.asarray(m.indices, dtype=np.uint32) for m in self.scene.meshes]
        # Every stream and the indices through one staging buffer and one submission (storage
        # too: the compute path reads vertices in its shader, render/compute_path.py), each
        # mesh's part copied once into the staging memory.
        made = [uploader.add_buffer(arrays, "vertex|storage", name)
                for name, arrays in uploads.items()]
        made.append(uploader.add_buffer(indices or [np.zeros(3, np.uint32)], "index|storage",
                                        "indices"))
        buffers = dict(zip(uploads, made, strict=False))
        for name in STREAMS + optional:
            self.streams[name] = self._own(buffers[name])
            self.stream_bytes[name] = int(sum(a.nbytes for a in uploads[name]))
        if not self.has_texcoords1:
            # The shader's TEXCOORD_1 input reads the TEXCOORD_0 buffer: an alias, not a copy
            # (not in stream_bytes, owned once).
            self.streams["texcoords1"] = self.streams["texcoords"]
        if not self.has_colors:
            self.streams["colors"] = self._own(buffers["colors"])
            self.stream_bytes["colors"] = 8
        self.index_buffer = self._own(made[-1])
        self.vertex_count = int(sum(sizes))

    def _add_stream(self, name: str, data: np.ndarray) -> None:
        # Storage too: the compute path reads vertices in its shader (render/compute_path.py).
        self.streams[name] = self._own(upload_buffer(self.device, data, "vertex|storage", name=name))
        self.stream_bytes[name] = int(data.nbytes)

    def _start_frames(self) -> concurrent.futures.Future | None:
        """On a GPU, the QTangent and packed streams built on a thread while the textures
        upload: auto's first frames take the compute path there, which binds them (0.3-0.6 s
        of Sponza's first frame when built then)."""
        if (self.device.info.kind == "cpu" or self._frame_sources is None
                or all(q is not None and pk is not None for _, _, q, pk in self._frame_sources)):
            return None  # (a baked scene brings both)
        from vkpbr.bake.frames import frame_streams

        pool = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="vkpbr-frames")
        try:
            return pool.submit(frame_streams, self._frame_sources)
        finally:
            pool.shutdown(wait=False)

    def ensure_streams(self, names: tuple[str, ...] = LAZY_STREAMS) -> None:
        """Build the QTangent / packed-frame streams among `names` not built yet (a mesh's own
        baked ones are used as they are). Safe at any time: a new buffer is bound only by
        command buffers recorded after it exists."""
        from vkpbr.bake.frames import frame_streams

        missing = [n for n in LAZY_STREAMS if n in names and n not in self.streams]
        if not missing or self._frame_sources is None:
            return
        if self._frames is not None:  # started at load: both streams
            qs, packed = self._frames.result()
            self._frames = None
        else:
            qs, packed = frame_streams(self._frame_sources, packed="packed_frames" in missing)
        # Keep the quaternions: the other path's stream, built later, starts from them.
        at = np.cumsum([0] + [len(n) for n, _, _, _ in self._frame_sources])
        self._frame_sources = [(n, t, qs[a:b], pk) for a, b, (n, t, _, pk) in
                               zip(at[:-1], at[1:], self._frame_sources, strict=True)]
        if "qtangents" in missing:
            self._add_stream("qtangents", _concat([qs] if len(qs) else [], np.float32, 4))
        if "packed_frames" in missing:
            self._add_stream("packed_frames", _concat([packed] if len(packed) else [], np.uint32, 1))
        if all(n in self.streams for n in LAZY_STREAMS):
            self._frame_sources = None  # nothing left to build from

    def _tangent_uv_set(self, mesh: Mesh) -> int:
        from vkpbr.bake.tangents import tangent_uv_set

        materials = self.scene.materials
        return tangent_uv_set(materials[mesh.material] if 0 <= mesh.material < len(materials) else None)

    def bytes_per_vertex(self) -> dict[str, int]:
        """Vertex bytes of each TBN path (position + texcoord(s) + frame)."""
        base = 12 + 8 + (8 if self.has_texcoords1 else 0)
        return {"vectors": base + 12 + 16, "quat": base + 16, "packed": base + 4}

    # --- textures ---------------------------------------------------------------------------
    def _decoded_pixels(self) -> tuple[list[np.ndarray | None], dict[int, list[np.ndarray]]]:
        """Every image's RGBA8, and the BC7 levels of the KTX2 ones that hold their mips
        (by image index) where the device samples BC7."""
        images = self.scene.images
        blocks: dict[int, list[np.ndarray]] = {}
        if all(img.pixels is not None for img in images):
            return [img.pixels for img in images], blocks
        max_size = int(self.device.limits.maxImageDimension2D)
        decoded_for = getattr(self._ahead, "decoded_for", None)  # (any other Future: none)
        self._ahead = None
        got = decoded_for(max_size) if decoded_for is not None else None
        if got is not None:  # (not kept here beyond the upload)
            return list(got), blocks
        from vkpbr.scene.textures import decode_images

        pixels = decode_images(self.scene, max_size=max_size,  # a Scene: errors name its file
                               blocks="bc7" if self.device.bc7_textures else None,
                               block_levels=blocks)
        return pixels, blocks

    def _merge_alpha_masks(self, pixels: list[np.ndarray | None]) -> list[Material]:
        """Materials with a separate alpha mask (OBJ map_d, .comp5822mesh) get one image whose
        RGB is the base colour and whose A is the mask: the shader reads alpha from base colour.
        Returns the materials to use (the scene's own objects are not modified)."""
        out = list(self.scene.materials)
        merged: dict[tuple[int, int, int], int] = {}
        for i, mat in enumerate(out):
            aref = mat.alpha_texture
            if aref is None or not 0 <= aref.image < len(pixels) or pixels[aref.image] is None:
                continue
            bref = mat.base_color_texture
            base_ok = bref is not None and 0 <= bref.image < len(pixels) and pixels[bref.image] is not None
            key = (bref.image if base_ok else -1, aref.image, aref.channel)
            if key not in merged:
                alpha = pixels[aref.image][..., aref.channel]
                if base_ok:
                    rgba = pixels[bref.image].copy()
                    if alpha.shape != rgba.shape[:2]:
                        from PIL import Image as PilImage

                        alpha = np.asarray(PilImage.fromarray(alpha).resize(
                            (rgba.shape[1], rgba.shape[0]), PilImage.BILINEAR))
                else:
                    rgba = np.full(alpha.shape + (4,), 255, np.uint8)
                rgba[..., 3] = alpha
                merged[key] = len(pixels)
                pixels.append(rgba)
            ref = bref if base_ok else aref
            out[i] = dataclasses.replace(
                mat, base_color_texture=dataclasses.replace(ref, image=merged[key], channel=0),
                alpha_texture=None)
        return out

    def _upload_textures(self, decoded: list[np.ndarray | None],
                         block_levels: dict[int, list[np.ndarray]], uploader: TextureUploader
                         ) -> None:
        pixels = list(decoded)
        self.scene_materials = self._merge_alpha_masks(pixels)
        # Which colour space each image is used in (base colour and emissive are sRGB).
        usage: dict[tuple[int, bool], None] = {}
        for mat in self.scene_materials:
            for slot in L.MATERIAL_TEXTURES:
                ref = getattr(mat, f"{slot}_texture")
                if ref is not None and 0 <= ref.image < len(pixels) and pixels[ref.image] is not None:
                    usage[(ref.image, slot in SRGB_TEXTURE_SLOTS)] = None
        self.images: dict[tuple[int, bool], Image] = {}
        for image_index, srgb in usage:
            fmt = "srgb" if srgb else "unorm"
            source = self.scene.images[image_index] if image_index < len(self.scene.images) else None
            name = source.name if source else "alpha-merged"
            blocks = block_levels.get(image_index)
            if blocks is not None:  # KTX2 with its mips, as BC7 (the file's own levels)
                h, w = pixels[image_index].shape[:2]
                self.images[(image_index, srgb)] = self._own(uploader.add_blocks(
                    blocks, (w, h), fmt, name=name))
                continue
            mips = ()
            if (source is not None and source.mips and source.mips_srgb == srgb
                    and pixels[image_index] is source.pixels):  # not downscaled on decode
                mips = source.mips
            self.images[(image_index, srgb)] = self._own(uploader.add(
                pixels[image_index], fmt, name=name, mips=mips))
        # 1x1 defaults for missing maps: white base colour and scalar maps (the factors then
        # act alone), a flat tangent-space normal, black emission.
        defaults = {
            "white_srgb": (np.full((1, 1, 4), 255, np.uint8), "srgb"),
            "white": (np.full((1, 1, 4), 255, np.uint8), "unorm"),
            "normal": (np.array([[[128, 128, 255, 255]]], np.uint8), "unorm"),
        }
        self.default_images = {
            k: self._own(uploader.add(px, fmt, mipmaps=False, name=k))
            for k, (px, fmt) in defaults.items()
        }
        uploader.flush()
        self.texture_bytes = sum(img.bytes for img in self.images.values())
        self._views: dict[tuple[int, str], ImageView] = {}
        self._samplers: dict[SamplerSpec, Sampler] = {}
        self._textures: dict[tuple, tuple[ImageView, Sampler, bool]] = {}

    def _view(self, image: Image, swizzle: str) -> ImageView:
        key = (id(image), swizzle)
        if key not in self._views:
            self._views[key] = self._own(ImageView(image, swizzle=swizzle))
        return self._views[key]

    def _sampler(self, spec: SamplerSpec) -> Sampler:
        if spec not in self._samplers:
            self._samplers[spec] = self._own(Sampler(self.device, spec))
        return self._samplers[spec]

    def stand_in(self) -> tuple[ImageView, Sampler]:
        """A 1x1 white texture and its sampler, for a binding that is written but not read
        (the transmission's copy in scenes without one: render/transmission.py)."""
        return self._view(self.default_images["white"], "iiii"), self._sampler(SamplerSpec())

    def _texture(self, ref: TextureRef | None, slot: str, with_roughness: bool = False
                 ) -> tuple[ImageView, Sampler, bool]:
        """The view, sampler and presence of one material texture; `with_roughness`: the
        metallic view of a shared metallic-roughness texture, metallic in R, roughness in G."""
        srgb = slot in SRGB_TEXTURE_SLOTS
        scalar = slot not in SRGB_TEXTURE_SLOTS and slot not in _NORMAL_SLOTS
        image = self.images.get((ref.image, srgb)) if ref is not None else None
        key = (slot, with_roughness, None if image is None else (ref.image, ref.sampler, ref.channel))
        if key not in self._textures:  # many materials share a few textures (or none)
            self._textures[key] = self._texture_binding(image, ref, slot, srgb, scalar,
                                                        with_roughness)
        return self._textures[key]

    def _texture_binding(self, image: Image | None, ref: TextureRef | None, slot: str,
                         srgb: bool, scalar: bool, with_roughness: bool
                         ) -> tuple[ImageView, Sampler, bool]:
        if image is None or ref is None:
            # White: the factor alone decides (emissive's is 0 by default); a flat normal.
            default = "normal" if slot in _NORMAL_SLOTS else "white_srgb" if srgb else "white"
            return self._view(self.default_images[default], "iiii"), self._sampler(SamplerSpec()), False
        s = ref.sampler
        spec = SamplerSpec(s.wrap_s, s.wrap_t, s.mag_filter, s.min_filter, s.mipmaps)
        swizzle = _SWIZZLE[ref.channel] if scalar else "iiii"
        if with_roughness:
            metal = "rgba"[ref.channel]
            swizzle = f"{metal}g{metal}{metal}"
        return self._view(image, swizzle), self._sampler(spec), True

    # --- materials --------------------------------------------------------------------------
    def _create_materials(self, layout: DescriptorSetLayout) -> None:
        """Each material's set (its textures and its MATERIAL block). The blocks have a copy
        per frame slot, in host-visible memory (and as the compute path's storage table), so
        that a material's factors change between frames (set_material, animation) without
        touching a frame in flight: a slot's sets name its own copies."""
        materials = list(self.scene_materials)
        self.materials: list[Material] = materials + [Material(name="vkpbr-default")]
        self.default_material = len(self.materials) - 1
        self.material_layout = layout
        self.material_blocks: list[np.ndarray] = []  # as loaded (compute_path.py's table too)
        views: list[list[tuple[ImageView, Sampler]]] = []
        for mat in self.materials:
            has, bound = {}, []
            shared = _shared_metallic_roughness(mat)
            for slot in L.MATERIAL_TEXTURES:
                view, sampler, present = self._texture(getattr(mat, f"{slot}_texture"), slot,
                                                       shared and slot == "metallic")
                has[slot] = present
                bound.append((view, sampler))
            block = material_block(mat, has)
            if shared and has["metallic"]:
                block["flags"] |= L.MATERIAL_SHARED_METALLIC_ROUGHNESS
            self.material_blocks.append(block)
            views.append(bound)
        self._material_buffers(views)

    def _material_buffers(self, views: list[list[tuple[ImageView, Sampler]]]) -> None:
        """The MATERIAL blocks' buffers (a copy per frame slot), the sets' pool and each
        slot's sets, for `self.materials` with their texture `views`."""
        align = int(self.device.limits.minUniformBufferOffsetAlignment)
        s_align = int(self.device.limits.minStorageBufferOffsetAlignment)
        self._ubo_stride = (L.MATERIAL.size + align - 1) // align * align
        n = len(self.materials)
        self._ubo_slot = self._ubo_stride * n
        self.material_ubo = self._own(Buffer(self.device, self._ubo_slot * self.slots, "uniform",
                                             host_visible=True, device_local=True, name="materials"))
        self._table_bytes = L.MATERIAL.size * n
        self._table_stride = (self._table_bytes + s_align - 1) // s_align * s_align
        self.material_table = self._own(Buffer(self.device, self._table_stride * self.slots, "storage",
                                               host_visible=True, device_local=True,
                                               name="material records"))
        layout = self.material_layout
        self.pool = self._own(DescriptorPool(self.device, [(layout, n * self.slots)]))
        # Each slot's sets are made as draws first bind them (MaterialSets): unused materials
        # cost no descriptor set in any slot.
        self.slot_material_sets = [
            MaterialSets(self.device, self.pool, layout, self.material_ubo, self._ubo_stride,
                         views, base=s * self._ubo_slot) for s in range(self.slots)]
        for s in range(self.slots):
            self.write_materials(s, self.material_blocks)
        self.material_sets = self.slot_material_sets[0]  # (slot 0's: tools and tests)

    def copy_material(self, i: int) -> int:
        """A new material, a copy of material `i` (its textures and factors), for draws that
        take their own factors (set_material(node=)); returns its index. The blocks' buffers
        and sets are made again (the caller waits for the device and re-records)."""
        views = list(self.slot_material_sets[0].textures) + [self.slot_material_sets[0].textures[i]]
        self.materials.append(dataclasses.replace(self.materials[i]))
        self.material_blocks.append(self.material_blocks[i].copy())
        for old in (self.material_ubo, self.material_table, self.pool):
            self._owned.remove(old)
            old.destroy()
        self._material_buffers(views)
        return len(self.materials) - 1

    def instance_draws(self, mesh: int, count: int) -> list[Draw]:
        """`count` new draw records of mesh `mesh` (add_instances): no node (-1), the mesh's
        material, a zero model (hidden until placed)."""
        m = self.scene.meshes[mesh]
        mat_index = m.material if 0 <= m.material < len(self.scene.materials) else self.default_material
        mat = self.materials[mat_index]
        return [Draw(mesh=mesh, material=mat_index, first_index=int(self.index_offsets[mesh]),
                     index_count=len(m.indices), vertex_offset=int(self.vertex_offsets[mesh]),
                     model=np.zeros((4, 4)), alpha_mode=mat.alpha_mode,
                     double_sided=bool(mat.double_sided), casts_shadows=bool(mat.casts_shadows))
                for _ in range(count)]

    def write_materials(self, slot: int, blocks: list[np.ndarray]) -> None:
        """Frame slot `slot`'s copies of the MATERIAL blocks (after the slot's fence): one
        write to each buffer, not one a material."""
        table = np.zeros(len(blocks), L.MATERIAL.dtype)  # np.stack drops padding
        for i, block in enumerate(blocks):
            table[i] = block
        rows = np.zeros((len(blocks), self._ubo_stride), np.uint8)
        rows[:, :L.MATERIAL.size] = table.view(np.uint8).reshape(len(blocks), -1)
        self.material_ubo.write(rows, offset=slot * self._ubo_slot)
        self.material_table.write(table.tobytes(), offset=slot * self._table_stride)

    def material_table_region(self, slot: int) -> tuple[Buffer, int, int]:
        """(buffer, offset, size) of slot `slot`'s MATERIAL table (the compute path's)."""
        return self.material_table, slot * self._table_stride, self._table_bytes

    # --- draws ------------------------------------------------------------------------------
    def _build_draws(self) -> list[Draw]:
        draws = []
        posed = {(r.node, r.instance): (offset, r.skin is not None)
                 for r, offset in zip(self.deformed, self.posed_offsets, strict=True)}
        # Each mesh's weights tested once (a crowd's thousand nodes share one mesh)
        convex = functools.cache(lambda i: convex_weights(self.scene.meshes[i]))
        for node_index, instance, node, mat_index in drawn(self.scene):
            mesh = self.scene.meshes[node.mesh]
            mat = self.materials[mat_index]
            m = np.asarray(node.matrix, dtype=np.float64)
            offset, skinned = posed.get((node_index, instance), (int(self.vertex_offsets[node.mesh]), False))
            if skinned:
                m = np.eye(4)  # skinned vertices are posed in world space (render/deform.py)
            if len(mesh.positions):
                lo, hi = self.mesh_box(node.mesh)
                center_local = (lo + hi) / 2
            else:
                center_local = np.zeros(3)
            draws.append(Draw(
                mesh=node.mesh, material=mat_index,
                first_index=int(self.index_offsets[node.mesh]), index_count=len(mesh.indices),
                vertex_offset=offset,
                model=m, alpha_mode=mat.alpha_mode,
                double_sided=bool(mat.double_sided), casts_shadows=bool(mat.casts_shadows),
                center=m[:3, :3] @ center_local + m[:3, 3], node=node_index, instance=instance,
                deformed=(node_index, instance) in posed, skinned=skinned,
                unbounded=skinned and not convex(node.mesh),
            ))
        draws.sort(key=lambda d: d.material)  # fewer material binds within each pass
        return draws

    @property
    def gpu_bytes(self) -> int:
        return sum(self.stream_bytes.values()) + int(self.index_buffer.size) + self.texture_bytes

    def destroy(self) -> None:
        while self._owned:
            self._owned.pop().destroy()


def material_block(mat: Material, has: dict[str, bool]) -> np.ndarray:
    """A material's MATERIAL block (layouts.MATERIAL) for `mat` with the texture slots
    `has` says are bound."""
    b = L.MATERIAL.zeros()
    for p in PARAMS:  # scene/material_table.py: the Material field is the block member
        b[p.name] = getattr(mat, p.name)
    for slot in L.MATERIAL_TEXTURES:
        rows = uv_transform_rows(getattr(mat, f"{slot}_texture"))
        b[f"{slot}_uv_row0"], b[f"{slot}_uv_row1"] = rows
    flags = 0
    if has["clearcoat_normal"]:
        flags |= L.MATERIAL_HAS_CLEARCOAT_NORMAL_MAP
    if has["anisotropy"]:
        flags |= L.MATERIAL_HAS_ANISOTROPY_MAP
    if mat.unlit:
        flags |= L.MATERIAL_UNLIT
    if mat.glossiness:
        flags |= L.MATERIAL_GLOSSINESS
    if has["normal"]:
        flags |= L.MATERIAL_HAS_NORMAL_MAP
    if has["occlusion"]:
        flags |= L.MATERIAL_HAS_OCCLUSION_MAP
    if has["emissive"]:
        flags |= L.MATERIAL_HAS_EMISSIVE_MAP
    if any(has[slot] for slot in L.LAYER_TEXTURES):
        flags |= L.MATERIAL_HAS_LAYER_MAPS
    if mat.double_sided:
        flags |= L.MATERIAL_DOUBLE_SIDED
    if mat.alpha_mode == "blend":
        flags |= L.MATERIAL_BLEND
    b["flags"] = flags
    return b


def drawn(scene: Scene) -> list[tuple[int, int, Node, int]]:
    """(index in scene.nodes, instance or -1, node, material) of each draw record GpuScene
    makes: nodes (and their instances, `draw_nodes`) whose mesh exists and has triangles; a
    mesh without a material of the scene's takes the default one after them (index
    len(scene.materials), GpuScene.default_material)."""
    meshes, count = scene.meshes, len(scene.materials)
    return [(i, k, node, m if 0 <= (m := meshes[node.mesh].material) < count else count)
            for i, k, node in draw_nodes(scene.nodes)
            if 0 <= node.mesh < len(meshes) and len(meshes[node.mesh].indices)]


# --- EXT_mesh_gpu_instancing -------------------------------------------------------------------
def draw_nodes(nodes: list[Node]) -> list[tuple[int, int, Node]]:
    """(index in scene.nodes, instance or -1, node) per draw record: a node with `instances`
    (EXT_mesh_gpu_instancing) gets one record per instance (its world matrix, its instance id
    in the dataset outputs), kept adjacent; the frame's passes draw a node's records as one
    instanced draw call (passes._instance_runs; pbr.vert reads each record's matrices). The
    mesh is never copied."""
    out: list[tuple[int, int, Node]] = []
    for i, node in enumerate(nodes):
        expanded = expand_instances([node])
        out += [(i, k if node.instances is not None else -1, n) for k, n in enumerate(expanded)]
    return out
