"""Uniform block layouts, descriptor bindings, debug views and modes: defined once, here.

Each uniform block is a list of (name, GLSL type) pairs. From it we derive a NumPy structured
dtype with explicit std140 offsets (vec3 aligned to 16, mat4 column-major) and the GLSL block
text; `vkpbr.render.codegen` writes the GLSL into shaders/generated.glsl, which every shader
includes. A test reads the member offsets back out of the compiled SPIR-V and compares.

Descriptor sets follow the report (renderer-spec section 1):
  set 0: binding 0 the views (VIEW_RECORD: camera matrices, eye, planes; record 0 for a
         single frame, one per view for a batch); binding 1 frame settings (view, BRDF,
         tonemap, ...)
  set 1: bindings 0-4 base colour, metallic, roughness, normal, occlusion; 5 emissive;
         6-19 the KHR_materials_* layers' textures (MATERIAL_TEXTURES); 20 material factors
  set 2: lighting, one per frame: binding 0 Lighting {view position, light count, mode,
         flags, environment}; 1 the punctual lights (a storage buffer of LightRecord, the
         course's one light being lights[0]); 2-4 the environment's pre-filtered maps
  set 3: shadows (render/shadows.py)
The course's set 2 was one Light block {vec4 lightPos; vec3 color; float intensity; vec4
viewPos}; its contents now live in the view record's eye and lights[0].
"""

from __future__ import annotations

import enum
import struct
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from vkpbr.scene.material_table import LAYER_PARAMS, PARAMS, TEXTURES
from vkpbr.shading import (
    AMBIENT,
    MAX_LIGHTS,
    MIN_ROUGHNESS,
    MIN_SHEEN_ROUGHNESS,
    SHEEN_ALBEDO_FIT,
    SHEEN_FIT_MIN_N_DOT_V,
    Brdf,
    Lighting,
    Named,
    Tonemap,
)

__all__ = [
    "Std140Block",
    "VIEW_RECORD",
    "SETTINGS",
    "MATERIAL",
    "LIGHTING",
    "LIGHT_RECORD",
    "STORAGE",
    "StorageArray",
    "LightKind",
    "PipelinePath",
    "RasterPath",
    "COMPUTE_SET",
    "STORAGE_IMAGES",
    "DRAW_RECORD",
    "WRITABLE_STORAGE",
    "VISIBILITY_FORMAT",
    "OUTPUT_IMAGES",
    "Lighting",
    "MAX_LIGHTS",
    "PUSH",
    "draw_push",
    "BLOCKS",
    "Named",
    "View",
    "VIEW_HELP",
    "ViewKind",
    "VIEW_KIND",
    "Brdf",
    "Tonemap",
    "TbnMode",
    "Ao",
    "SETS",
    "HAND_DECLARED_SETS",
    "MATERIAL_TEXTURES",
    "MATERIAL_BINDING",
    "MIN_ROUGHNESS",
    "MIN_SHEEN_ROUGHNESS",
    "SHEEN_ALBEDO_FIT",
    "SHEEN_FIT_MIN_N_DOT_V",
    "AMBIENT",
]

# Shading constants and choices are defined in vkpbr.shading (the NumPy reference shares them)
# and re-exported here with the blocks that carry them to the shaders.

_STRUCT_CODE = {np.float32: "f", np.int32: "i", np.uint32: "I"}

_BASE = {  # GLSL type -> (base alignment, size, numpy dtype, shape)
    "float": (4, 4, np.float32, ()),
    "int": (4, 4, np.int32, ()),
    "uint": (4, 4, np.uint32, ()),
    "vec2": (8, 8, np.float32, (2,)),
    "vec3": (16, 12, np.float32, (3,)),
    "vec4": (16, 16, np.float32, (4,)),
    "uvec4": (16, 16, np.uint32, (4,)),
    "mat4": (16, 64, np.float32, (4, 4)),
}


@dataclass(frozen=True)
class Std140Block:
    """A uniform (or push-constant) block laid out by the std140 rules."""

    name: str  # GLSL block name
    instance: str  # GLSL instance name
    fields: tuple[tuple[str, str], ...]

    # Cached: a block's layout never changes, and a scene with tens of thousands of materials
    # asks for MATERIAL's dtype once per material.
    @cached_property
    def offsets(self) -> dict[str, int]:
        out, offset = {}, 0
        for name, glsl in self.fields:
            align, size, _, _ = _BASE[glsl]
            offset = (offset + align - 1) // align * align
            out[name] = offset
            offset += size
        return out

    @cached_property
    def size(self) -> int:
        name, glsl = self.fields[-1]
        end = self.offsets[name] + _BASE[glsl][1]
        return (end + 15) // 16 * 16

    @cached_property
    def dtype(self) -> np.dtype:
        offs = self.offsets
        return np.dtype(
            {
                "names": [n for n, _ in self.fields],
                "formats": [(_BASE[t][2], _BASE[t][3]) for _, t in self.fields],
                "offsets": [offs[n] for n, _ in self.fields],
                "itemsize": self.size,
            }
        )

    @cached_property
    def packer(self) -> struct.Struct:
        """The block as a little-endian `struct.Struct` over its members' scalars in order
        (a mat4 as its 16 floats column by column; padding skipped): the per-frame writer,
        one `pack_into` instead of NumPy structured-field writes (~4x cheaper)."""
        fmt, at = ["<"], 0
        for name, glsl in self.fields:
            _, size, dtype, shape = _BASE[glsl]
            offset = self.offsets[name]
            fmt.append("x" * (offset - at) + _STRUCT_CODE[dtype] * int(np.prod(shape, dtype=int)))
            at = offset + size
        fmt.append("x" * (self.size - at))
        return struct.Struct("".join(fmt))

    @cached_property
    def pack_into(self):  # noqa: ANN201 - a generated function
        """`pack_into(buffer, **fields)`: write the block into a writable buffer by field
        name, every field required (keyword-only: a missing or misspelt name is a TypeError).
        Vectors are sequences of their length, a mat4 its 16 floats column by column.

        Generated once per block from `fields`, so it costs one `struct.pack_into` call
        (~1 us) and cannot disagree with the layout's order, which positional packing could.
        """
        args, parts = [], []
        for name, glsl in self.fields:
            _, _, _, shape = _BASE[glsl]
            args.append(name)
            parts.append(f"*{name}" if shape else name)
        src = (f"def pack_into(buffer, *, {', '.join(args)}):\n"
               f"    _pack(buffer, 0, {', '.join(parts)})\n")
        scope: dict = {"_pack": self.packer.pack_into}
        exec(compile(src, f"<std140 {self.name}>", "exec"), scope)  # noqa: S102 - our own text
        return scope["pack_into"]

    def zeros(self) -> np.ndarray:
        return np.zeros((), dtype=self.dtype)

    def glsl(self, qualifier: str) -> str:
        lines = [f"{qualifier} {self.name} {{"]
        lines += [f"    {t} {n};" for n, t in self.fields]
        lines.append(f"}} {self.instance};")
        return "\n".join(lines)


def mat4_to_std140(m: np.ndarray) -> np.ndarray:
    """GLSL mat4 is column-major: the one place a row-major NumPy matrix is transposed."""
    return np.ascontiguousarray(np.asarray(m, dtype=np.float32).T)


# One view a frame or a batch draws through (render/views.py builds and writes them): set 0's
# Views storage buffer holds one per view, which every shader reads as views[view_index]
# (generated.glsl: 0 for a single frame; a batch's shaders take their instance's or tile's).
# mat4 and vec4 members and a trailing uint: std140 here is also the std430 layout of the
# storage array (stride 208 either way).
VIEW_RECORD = Std140Block("ViewRecord", "view_record", (
    ("VP", "mat4"),  # clip from world: reversed-Z, infinite far plane (render/camera.py)
    ("inv_VP", "mat4"),  # world from clip: the compute path's pixel rays, its background's
    ("eye_near", "vec4"),  # xyz: the eye; w: znear (depth readback is znear / depth)
    ("forward_far", "vec4"),  # xyz: unit view direction; w: zfar (the depth view's scale)
    ("intrinsics", "vec4"),  # sx, sy, ox, oy: NDC x = sx x / -z + ox, y = -sy y / -z + oy
    ("viewport", "uvec4"),  # x, y, width, height: the pixels of its target the view covers
    ("layer", "uint"),  # the layer of a layered batch target it is drawn into (else 0)
    # Where its world's draw records start in Instances (render/worlds.py: a batch of worlds
    # holds the renderer's state then one run of draw records per world; else 0).
    ("instance_base", "uint"),
    # Where its world's material factors start in WorldFactors (render/worlds.py: 3 vec4 a
    # material, FACTOR_VEC4S) plus one; 0: the materials' own (frames, plain batches).
    ("factor_base", "uint"),
    # Its world's shadow maps in ShadowWorldDepths plus one (render/world_shadows.py: a batch
    # of worlds whose poses move casters); 0: the shadow images (frames, other batches).
    ("shadow_base", "uint"),
))

SETTINGS = Std140Block(
    "Settings",
    "settings",
    (
        ("view", "int"),  # View
        ("brdf", "int"),  # Brdf
        ("tonemap", "int"),  # Tonemap
        ("flags", "uint"),  # SETTINGS_* bits below
        ("exposure", "float"),  # linear multiplier (2 ** EV)
    ),
)
SETTINGS_NORMAL_MAPPING = 1  # use normal maps
SETTINGS_OCCLUSION = 2  # use occlusion maps
SETTINGS_SRGB_TARGET = 4  # the colour target encodes sRGB in hardware

# The material's textures, in binding order (set 1, bindings 0-19; the Material block is
# binding 20): the table's bound slots (scene/material_table.py TEXTURES), the core's six, then
# the KHR_materials_* layers'. 20 samplers of set 1 + 5 of set 2 + 2 of set 3 = 27 a stage
# (lavapipe allows 32, NVIDIA far more; Vulkan's guaranteed minimum, 16, is below that).
MATERIAL_TEXTURES = tuple(slot.name for slot in TEXTURES if slot.bound)
MATERIAL_BINDING = len(MATERIAL_TEXTURES)  # set 1's Material block


def _uv_fields() -> tuple[tuple[str, str], ...]:
    """Per texture, its KHR_texture_transform as the two rows of a 2x3 matrix (uv' = M (u, v, 1)).

    Row 0's fourth component holds the texture's UV set (0.0 = TEXCOORD_0, 1.0 = TEXCOORD_1):
    std140 pads each 3-float row to a vec4 anyway, so the set index costs no bytes there, where
    a separate uint per texture would need 16 bytes each (std140 array stride) or bit packing.
    Row 1's fourth component is unused.
    """
    return tuple((f"{slot}_uv_row{r}", "vec4") for slot in MATERIAL_TEXTURES for r in (0, 1))


def _parameter_fields() -> tuple[tuple[str, str], ...]:
    """The material table's parameters as block members (the Material field's name and type),
    ordered so that std140 wastes no bytes: vec4s, then each vec3 with a float in its 16
    bytes' last 4 (the next free float of the table after it, else the first free one), then
    the other floats."""
    fields = [(p.name, p.glsl) for p in PARAMS]
    free = [f for f in fields if f[1] == "float"]
    out = [f for f in fields if f[1] == "vec4"]
    for k, vec3 in enumerate(fields):
        if vec3[1] != "vec3":
            continue
        after = [f for f in free if fields.index(f) > k]
        pair = (after or free)[:1]
        out += [vec3, *pair]
        free = [f for f in free if f not in pair]
    return tuple(out + free + [f for f in fields if f[1] not in ("vec4", "vec3", "float")])


MATERIAL = Std140Block(
    "Material",
    "material",
    (
        *_parameter_fields(),  # scene/material_table.py: one name from the file to the shader
        ("flags", "uint"),  # MATERIAL_* bits below
        *_uv_fields(),  # 2 vec4 a texture
    ),
)
MATERIAL_HAS_NORMAL_MAP = 1
MATERIAL_DOUBLE_SIDED = 2
MATERIAL_HAS_OCCLUSION_MAP = 4
MATERIAL_BLEND = 8  # alphaMode BLEND: output alpha for the blended pass
MATERIAL_UNLIT = 16  # KHR_materials_unlit: the final view is the base colour
MATERIAL_HAS_CLEARCOAT_NORMAL_MAP = 32
# Any of the KHR_materials_* layers' textures (LAYER_TEXTURES) / an emissive texture: without
# them shade.glsl takes the white default's 1.0 instead of sampling (8 texture reads a pixel).
MATERIAL_HAS_LAYER_MAPS = 64
MATERIAL_HAS_EMISSIVE_MAP = 128
# glTF's packed metallic-roughness texture: the metallic binding's view holds metallic in R
# and roughness in G (render/gpu_scene.py), so shade.glsl reads both with one sample.
MATERIAL_SHARED_METALLIC_ROUGHNESS = 256
# KHR_materials_pbrSpecularGlossiness (Material.glossiness): roughness = 1 - factor x texel.
MATERIAL_GLOSSINESS = 512
# KHR_materials_anisotropy's texture (direction RG, strength B): read only when present.
MATERIAL_HAS_ANISOTROPY_MAP = 1024
# The KHR_materials_* layers' factors (shade.glsl material_layers' LAYER_FACTOR), their
# values in a material without the extensions (generated.glsl MATERIAL_DEFAULT_*), and their
# textures (MATERIAL_HAS_LAYER_MAPS).
LAYER_FIELDS = tuple(p.name for p in LAYER_PARAMS)
LAYER_DEFAULTS = {p.name: np.atleast_1d(np.asarray(p.default, np.float32)) for p in LAYER_PARAMS}
LAYER_TEXTURES = tuple(p.texture for p in LAYER_PARAMS if p.texture is not None)

LIGHTING = Std140Block(
    "Lighting",
    "lighting",
    (
        ("light_count", "uint"),  # records in `lights` this frame
        ("mode", "int"),  # Lighting
        ("flags", "uint"),  # LIGHTING_* bits below
        ("env_intensity", "float"),  # scale of the environment's radiance
        ("env_rotation", "vec4"),  # x, y: cos, sin of the rotation about +Y; z: max lod
        ("ambient_color", "vec4"),  # rgb: the course's ambient weight (0.02), 0 otherwise
    ),
)
LIGHTING_SHADOWS = 1  # shadow maps are sampled
LIGHTING_IBL = 2  # image-based lighting from the environment
LIGHTING_BACKGROUND = 4  # the environment is drawn where nothing else is
LIGHTING_SCREEN_TRANSMISSION = 8  # transmission samples the opaque copy (render/transmission.py)
LIGHTING_AO = 16  # the image-based light is occluded by the frame's GTAO (render/ao.py, set 2 ao_map)
# The largest copy of the opaque scene (render/transmission.py), square: the Sample Viewer's
# transmission framebuffer's size; shade.glsl's blur by roughness is relative to it.
OPAQUE_COPY_MAX_SIZE = 1024

# One punctual light, as the shaders read it (shaders/lights.glsl). Only vec4 members, so the
# std140 layout here is also the std430 layout of the storage buffer's array elements.
LIGHT_RECORD = Std140Block(
    "LightRecord",
    "light",
    (
        ("position_range", "vec4"),  # xyz world position; w range (0 = infinite)
        ("direction_kind", "vec4"),  # xyz unit direction the light travels; w LightKind
        ("color_falloff", "vec4"),  # rgb colour * intensity; w 0 none, 1 inverse square
        ("cone", "vec4"),  # x spot angle scale, y spot offset (KHR_lights_punctual)
        ("shadow", "vec4"),  # x first shadow layer / cube (-1: none); y-w render/shadows.py
    ),
)


@dataclass(frozen=True)
class StorageArray:
    """A storage buffer holding an unsized array of one record layout (a Std140Block, laid
    out std140 in the buffer too) or of one GLSL scalar/vector type (std430)."""

    name: str  # GLSL block name
    element: Std140Block | str  # the record, or a GLSL type such as "float" or "vec2"
    member: str  # the array's GLSL name

    @property
    def layout(self) -> str:
        return "std140" if isinstance(self.element, Std140Block) else "std430"


# One mesh instance as the compute path reads it (render/compute_path.py writes them).
# Its matrices are the draw's Instances record (the scene state's, render/scene_state.py).
DRAW_RECORD = Std140Block("DrawRecord", "draw_record", (
    ("info", "uvec4"),  # first index, vertex offset, material, 1 if the scene has COLOR_0
    ("ids", "uvec4"),  # instance id, semantic id (dataset outputs; 0 = background), 0, 0
))

STORAGE = {
    "Lights": StorageArray("Lights", LIGHT_RECORD, "lights"),
    # Every view drawn (VIEW_RECORD) and, per (chunk, draw) of a batch, the views that see
    # the draw (render/batch.py).
    "Views": StorageArray("Views", VIEW_RECORD, "views"),
    "VisibleViews": StorageArray("VisibleViews", "uint", "visible_views"),
    # Every draw record's matrices, the frame slot's copy of the scene state
    # (render/scene_state.py): model, then the normal matrix (the inverse transpose), 2 a
    # record. Every step that places geometry reads them here (pbr.vert by gl_InstanceIndex,
    # so that a node's K instances (EXT_mesh_gpu_instancing) are one draw call; a batch's and
    # the shadow maps' draws by the pushed record index; the compute path by the draw).
    "Instances": StorageArray("Instances", "mat4", "instance_matrices"),
    "Draws": StorageArray("Draws", DRAW_RECORD, "draws"),
    "Indices": StorageArray("Indices", "uint", "indices"),
    "Positions": StorageArray("Positions", "float", "positions"),  # 3 floats a vertex
    "Texcoords0": StorageArray("Texcoords0", "vec2", "texcoords0"),
    "Texcoords1": StorageArray("Texcoords1", "vec2", "texcoords1"),
    "Colors": StorageArray("Colors", "uint", "colors"),  # RGBA16 UNORM: 2 uints a vertex
    "Normals": StorageArray("Normals", "float", "normals"),  # 3 floats a vertex
    "Tangents": StorageArray("Tangents", "vec4", "tangents"),
    "QTangents": StorageArray("QTangents", "vec4", "qtangents"),
    "PackedFrames": StorageArray("PackedFrames", "uint", "packed_frames"),
    # Per material, per frame: (pixel count, list offset, scatter cursor, 0) (classify.comp).
    "Bins": StorageArray("Bins", "uvec4", "bins"),
    "BinArgs": StorageArray("BinArgs", "uint", "bin_args"),  # 3 per material: dispatch sizes
    "PixelList": StorageArray("PixelList", "uint", "pixel_list"),  # pixel indices by material
    "Materials": StorageArray("Materials", MATERIAL, "materials"),  # GpuScene's blocks
    # The compute rasteriser (render/compute_path.py, shaders/raster.comp): a row a draw in
    # the raster units' submission order (first triangle, flags: 1 double-sided, 2 masked,
    # 4 blended, the draw's index, 0), the 64-bit depth|triangle per pixel, the big
    # triangles' list (a count, the dispatch size, then (triangle, view) pairs), the winners'
    # depths a float a pixel (copied into the depth buffer).
    "RasterDraws": StorageArray("RasterDraws", "uvec4", "raster_draws"),
    "RasterDepthIds": StorageArray("RasterDepthIds", "uint64_t", "raster"),
    "RasterBig": StorageArray("RasterBig", "uint", "raster_big"),
    "RasterSpheres": StorageArray("RasterSpheres", "vec4", "raster_spheres"),  # per draw, its mesh's
    "RasterDepths": StorageArray("RasterDepths", "float", "raster_depths"),
    # The masked draws' big triangles: per masked draw a count and a dispatch size, then its
    # segment of (triangle, view, chunk) entries.
    "RasterMaskedBig": StorageArray("RasterMaskedBig", "uint", "raster_masked_big"),
    # vec4s: the previous VP (4), (valid, first posed vertex, 0, 0) as uint bits, then per
    # draw its previous model matrix (4) and (deformed, 0, 0, 0) (render/scene_state.py).
    "Motion": StorageArray("Motion", "vec4", "motion"),
    # A batch of worlds' material factors (render/worlds.py): per (world, material) base
    # colour, (emissive, metallic), (roughness, 0, 0, 0); a stand-in without worlds.
    "WorldFactors": StorageArray("WorldFactors", "vec4", "world_factors"),
    "PrevPositions": StorageArray("PrevPositions", "float", "prev_positions"),  # 3 a vertex
}
# Storage buffers the compute path writes (declared without `readonly`).
WRITABLE_STORAGE = ("Bins", "BinArgs", "PixelList", "RasterDepthIds", "RasterBig", "RasterDepths",
                    "RasterMaskedBig")

# The compute path's own set (render/compute_path.py), numbered after SETS: the target's
# images, the scene's geometry as storage buffers, the per-material pixel bins. Its other sets
# are the frame's and, for shading, each material's own set 1. (binding, kind, name).
COMPUTE_SET: tuple[tuple[int, str, str], ...] = (
    (0, "storage_image", "out_image"),  # the target's colour (UNORM view of an sRGB image)
    (1, "storage_image", "visibility"),  # (draw index + 1, primitive index); 0: nothing
    (2, "storage", "Draws"),
    (3, "storage", "Indices"),
    (4, "storage", "Positions"),
    (5, "storage", "Texcoords0"),
    (6, "storage", "Texcoords1"),
    (7, "storage", "Colors"),
    (8, "storage", "Normals"),
    (9, "storage", "Tangents"),
    (10, "storage", "QTangents"),
    (11, "storage", "PackedFrames"),
    (12, "storage", "Bins"),
    (13, "storage", "BinArgs"),
    (14, "storage", "PixelList"),
    # The frame's blocks and the materials as storage buffers: the compute path reads no
    # uniform block, which lavapipe 22.3 would compile a variant of the shader for per new set
    # of values (never freed) and, once a loop depends on one, crash compiling. (The views
    # are set 0's storage buffer, read there by every path.)
    (15, "block", "Settings"),
    (16, "block", "Lighting"),
    (17, "storage", "Materials"),
    # Dataset outputs (Renderer.render(outputs=...)), written by shade.comp's OUTPUTS variant.
    (18, "storage_image", "out_ids"),  # instance, semantic
    (19, "storage_image", "out_normal"),  # world shading normal (normal-mapped)
    (20, "storage_image", "out_normal_geometric"),  # world interpolated vertex normal
    (21, "storage_image", "out_depth_range"),  # distance along the view axis, to the eye; motion
    # The compute rasteriser (raster.comp).
    (22, "storage", "RasterDraws"),
    (23, "storage", "RasterDepthIds"),
    (24, "storage", "RasterBig"),
    (25, "storage", "RasterSpheres"),  # per draw its mesh's bounding sphere (culling)
    (26, "storage", "RasterDepths"),  # resolved: copied into the depth buffer
    (27, "storage", "RasterMaskedBig"),
    # The motion output (render/scene_state.py): the frame slot's previous view and draw
    # matrices, and the deformed vertices' previous positions (render/deform.py).
    (28, "storage", "Motion"),
    (29, "storage", "PrevPositions"),
)
# GLSL declarations of the storage images (their formats and access).
STORAGE_IMAGES = {
    "out_image": "writeonly uniform image2D",  # format from the view (WriteWithoutFormat)
    "visibility": "layout(rg32ui) uniform uimage2D",  # written by raster.comp's resolve
    "out_ids": "layout(rg32ui) writeonly uniform uimage2D",
    "out_normal": "writeonly uniform image2D",
    "out_normal_geometric": "writeonly uniform image2D",
    "out_depth_range": "writeonly uniform image2D",
}
# The dataset outputs' images: name -> (Vulkan format, bytes a pixel, NumPy dtype, channels).
OUTPUT_IMAGES = {
    "out_ids": ("VK_FORMAT_R32G32_UINT", 8, "uint32", 2),
    "out_normal": ("VK_FORMAT_R32G32B32A32_SFLOAT", 16, "float32", 4),
    "out_normal_geometric": ("VK_FORMAT_R32G32B32A32_SFLOAT", 16, "float32", 4),
    # depth, range, then the motion (render/scene_state.py): where the point was in the
    # previous frame's image, in pixels from where it is now (x right, y down)
    "out_depth_range": ("VK_FORMAT_R32G32B32A32_SFLOAT", 16, "float32", 4),
    # GTAO's visibility (render/ao.py), copied from the frame slot's "ao" image.
    "out_ao": ("VK_FORMAT_R32_SFLOAT", 4, "float32", 1),
}
VISIBILITY_FORMAT = "VK_FORMAT_R32G32_UINT"


class LightKind(Named):
    POINT = 0
    SPOT = 1
    DIRECTIONAL = 2


# A draw's push constant: x = its record in Instances (a batch's and the shadow maps' draws,
# whose instance index says the view or the map layer).
PUSH = Std140Block("Draw", "draw", (("index", "uvec4"),))


def draw_push(index: int, atlas: tuple[int, int] = (0, 0), material: int = 0) -> np.ndarray:
    """The PUSH bytes of draw record `index`, the draw's `material` (whose factors a world
    of a batch may set: pbr.frag's BATCH build) and in a compute batch the `atlas` size,
    which pbr.vert's ATLAS build maps each view's tile into."""
    return np.array([index, *atlas, material], np.uint32)

BLOCKS = (SETTINGS, MATERIAL, LIGHTING, PUSH)

# set -> (binding, kind, stages, name): the one table of descriptor bindings. kind: "uniform"
# (a block of BLOCKS), "storage" (an array of STORAGE), "sampler" (sampler2D) or another GLSL
# sampler type ("samplerCube", "sampler2DArrayShadow", ...).
SETS: dict[int, tuple[tuple[int, str, tuple[str, ...], str], ...]] = {
    0: (
        # The views: a frame slot's one record (render/frames.py), a batch's array (batch.py).
        (0, "storage", ("vertex", "fragment", "compute"), "Views"),
        (1, "uniform", ("vertex", "fragment", "compute"), "Settings"),
        # A batch's visible lists (render/batch.py): frames bind a stand-in they never read.
        (2, "storage", ("vertex",), "VisibleViews"),
        # The scene state's matrices, the slot's copy (render/scene_state.py).
        (3, "storage", ("vertex", "compute"), "Instances"),
        # A batch of worlds' material factors, lights and environment (render/batch.py
        # BatchViews: its views' factor_base; frames bind a stand-in they never read). In set
        # 0 so that the compute batch's kernels and its blended draws' pbr.frag read one table.
        (4, "storage", ("fragment", "compute"), "WorldFactors"),
    ),
    1: (
        *((i, "sampler", ("fragment", "compute"), f"{slot}_map")
          for i, slot in enumerate(MATERIAL_TEXTURES)),
        (MATERIAL_BINDING, "uniform", ("fragment", "compute"), "Material"),
    ),
    2: (
        (0, "uniform", ("fragment", "compute"), "Lighting"),
        (1, "storage", ("fragment", "compute"), "Lights"),
        # 2-4: the environment's maps (render/environment.py), always written: with no
        # environment a tiny black one is bound (lavapipe crashes drawing with a combined
        # image sampler descriptor left unwritten, even one no shader reads).
        (2, "samplerCube", ("fragment", "compute"), "env_specular"),
        (3, "samplerCube", ("fragment", "compute"), "env_irradiance"),
        (4, "sampler", ("fragment", "compute"), "brdf_lut"),
        # KHR_materials_transmission's linear, mip-mapped copy of the opaque scene
        # (render/transmission.py), a 1x1 stand-in in scenes where nothing transmits.
        (5, "sampler", ("fragment", "compute"), "opaque_copy"),
        # The frame's screen-space ambient occlusion (render/ao.py): GTAO's visibility a
        # pixel, read by texelFetch at the shaded pixel; a 1x1 stand-in until frames have it.
        # An array: the layered batch's views are its layers (frames read layer 0).
        (6, "sampler2DArray", ("fragment", "compute"), "ao_map"),
    ),
    # Shadows (render/shadows.py ShadowMaps owns the resources; declared in GLSL by hand in
    # shaders/shadow_data.glsl and shadow_sampling.glsl: ShadowData is a header then matrices).
    3: (
        (0, "storage", ("fragment", "compute"), "ShadowData"),
        (1, "sampler2DArrayShadow", ("fragment", "compute"), "shadow_maps"),
        (2, "samplerCubeArrayShadow", ("fragment", "compute"), "shadow_cubes"),
        # A batch of worlds' shadow maps, every world's (render/world_shadows.py): depths
        # read by hand (a stand-in where there are none).
        (3, "storage", ("fragment", "compute"), "ShadowWorldDepths"),
        # The frame's maps where the compute rasteriser draws them (render/shadow_raster.py):
        # its depth buffer, read by hand (a stand-in where the raster units draw them).
        (4, "storage", ("fragment", "compute"), "ShadowDepths"),
        # The cubes' faces as 2D layers, clamped to each face's edge (compare_cube picks the
        # face and gathers its texels, as the by-hand read of ShadowDepths does).
        (5, "sampler2DArrayShadow", ("fragment", "compute"), "shadow_cube_faces"),
    ),
}
# Sets whose GLSL declarations are not generated (codegen skips them).
HAND_DECLARED_SETS = frozenset({3})


class View(Named):
    """Debug views, selected at run time through Settings.view (no pipeline rebuild)."""

    FINAL = 0
    D = 1
    F = 2
    G = 3
    SPECULAR = 4
    DIFFUSE = 5
    AMBIENT = 6
    GEOMETRIC_NORMAL = 7
    MAPPED_NORMAL = 8
    VIEW_DIR = 9
    LIGHT_DIR = 10
    BASE_COLOR = 11
    METALLIC = 12
    ROUGHNESS = 13
    OCCLUSION = 14
    ALPHA = 15
    TEXCOORDS = 16
    DEPTH = 17
    EMISSIVE = 18
    TANGENT = 19
    BITANGENT = 20
    SHADOW = 21
    IBL_DIFFUSE = 22
    IBL_SPECULAR = 23
    # The KHR_materials_* layers (shade.glsl; each mirrored in reference/brdf.py).
    IOR = 24
    DIELECTRIC_F0 = 25
    CLEARCOAT = 26
    SHEEN = 27
    TRANSMISSION = 28
    VOLUME = 29
    AO = 30  # the frame's screen-space ambient occlusion (render/ao.py)
    ANISOTROPY = 31  # KHR_materials_anisotropy's direction and strength
    IRIDESCENCE = 32  # KHR_materials_iridescence's thin-film Fresnel
    DIFFUSE_TRANSMISSION = 33  # KHR_materials_diffuse_transmission's radiance


VIEW_HELP = {
    View.FINAL: "the shaded image: emissive + ambient or IBL + sum over lights of "
                "(diffuse + specular) * light * n.l * shadow",
    View.D: "normal distribution D (GGX or Blinn-Phong, per --brdf) for the first light, grey, clipped at 1",
    View.F: "Schlick Fresnel F as RGB",
    View.G: "geometric masking G (Cook-Torrance; glTF: Smith, 4 n.l n.v V), first light, grey",
    View.SPECULAR: "specular radiance of the punctual lights: D F G / (4 n.v n.l) * light * n.l",
    View.DIFFUSE: "diffuse radiance of the punctual lights: c/pi (1-F)(1-M) * light * n.l",
    View.AMBIENT: "ambient radiance: 0.02 * c * occlusion (course lighting; 0 otherwise)",
    View.GEOMETRIC_NORMAL: "interpolated vertex normal (world), xyz*0.5+0.5",
    View.MAPPED_NORMAL: "shading normal after normal mapping (world), xyz*0.5+0.5",
    View.VIEW_DIR: "direction to the camera v (world), xyz*0.5+0.5",
    View.LIGHT_DIR: "direction to the first light l (world), xyz*0.5+0.5",
    View.BASE_COLOR: "base colour c (texture x factor), as a colour",
    View.METALLIC: "metalness M, grey",
    View.ROUGHNESS: "roughness r, grey",
    View.OCCLUSION: "ambient occlusion, grey",
    View.ALPHA: "base-colour alpha, grey",
    View.TEXCOORDS: "base-colour texture coordinates (its UV set, transformed): R = u, G = v (fract)",
    View.DEPTH: "linear depth: distance along the view axis / the far side of the scene's bounds (or the camera's zfar), grey",
    View.EMISSIVE: "emitted radiance Le",
    View.TANGENT: "tangent (world, from the vertex TBN), xyz*0.5+0.5",
    View.BITANGENT: "bitangent (world, handedness applied), xyz*0.5+0.5",
    View.SHADOW: "shadow factor of the first shadow-casting light (1 lit, 0 shadowed), grey",
    View.IBL_DIFFUSE: "image-based diffuse radiance (irradiance * diffuse colour, occluded)",
    View.IBL_SPECULAR: "image-based specular radiance (pre-filtered environment * split sum)",
    View.IOR: "index of refraction (KHR_materials_ior) as ior - 1, grey (1.5: 0.5; clipped at 1)",
    View.DIELECTRIC_F0: "the dielectric's F0 times its specular weight (KHR_materials_ior and "
                        "_specular): min(((ior-1)/(ior+1))^2 * specular colour, 1) * specular",
    View.CLEARCOAT: "clearcoat radiance (KHR_materials_clearcoat): the coat's GGX lobe of the "
                    "lights and the environment, times clearcoat * F_coat(n.v)",
    View.SHEEN: "sheen radiance (KHR_materials_sheen): the Charlie lobe of the lights and the "
                "environment",
    View.TRANSMISSION: "transmitted radiance (KHR_materials_transmission): the lights through "
                       "the surface and the refracted environment, after volume attenuation",
    View.VOLUME: "volume transmittance (KHR_materials_volume): attenuation colour ^ (thickness "
                 "/ attenuation distance), as a colour",
    View.ANISOTROPY: "anisotropy (KHR_materials_anisotropy): RG the direction in the tangent "
                      "plane (tangent, bitangent) * 0.5 + 0.5, B the strength",
    View.IRIDESCENCE: "the thin-film Fresnel of KHR_materials_iridescence on the dielectric's "
                       "F0 at n.v, times the iridescence factor, as RGB",
    View.DIFFUSE_TRANSMISSION: "diffusely transmitted radiance (KHR_materials_diffuse_transmission): "
                                "the Lambertian lobe through the surface of the lights and the "
                                "environment behind",
    View.AO: "screen-space ambient occlusion (GTAO, --ao): visibility of the image-based light, "
             "1 unoccluded, grey (1 where frames have none)",
}


class ViewKind(enum.IntEnum):
    RADIANCE = 0  # exposure and tone mapping apply, then sRGB encoding
    COLOR = 1  # a linear colour shown as a colour (sRGB-encoded)
    DATA = 2  # raw values: stored byte = round(255 * clamp(value, 0, 1))


VIEW_KIND = {
    v: (
        ViewKind.RADIANCE
        if v in (View.FINAL, View.SPECULAR, View.DIFFUSE, View.AMBIENT, View.EMISSIVE,
                 View.IBL_DIFFUSE, View.IBL_SPECULAR, View.CLEARCOAT, View.SHEEN,
                 View.TRANSMISSION, View.DIFFUSE_TRANSMISSION)
        else ViewKind.COLOR
        if v in (View.BASE_COLOR, View.VOLUME)
        else ViewKind.DATA
    )
    for v in View
}


class PipelinePath(Named):
    """How frames are drawn: FORWARD shades in fragment shaders; COMPUTE rasterises a
    visibility buffer and shades it in compute shaders (render/compute_path.py: all SMs of an
    H100/H200, where only a few run fragment shaders); AUTO: the compute path on GPUs where
    the target allows it (measured faster on the H200 at every size), the forward path on
    CPUs and windows (docs/compute-path.md)."""

    AUTO = 0
    FORWARD = 1
    COMPUTE = 2


class RasterPath(Named):
    """What makes the compute path's visibility buffer: HARDWARE, the raster units (pbr.vert and
    pbr.frag's VISIBILITY build); COMPUTE, compute shaders (render/compute_path.py: a 64-bit
    atomic per covered pixel, on all SMs; masked draws alpha-tested there too); AUTO, the
    compute rasteriser on GPUs that have 64-bit storage atomics where the image fits one
    storage binding (the H200 measured it faster than the raster units at 128x128 to
    1920x1080: BENCHMARKS.md), the raster units on CPUs."""

    HARDWARE = 0
    COMPUTE = 1
    AUTO = 2


class Ao(Named):
    """Screen-space ambient occlusion of the image-based light (render/ao.py): OFF, or GTAO
    (XeGTAO's ground-truth ambient occlusion, between depth and shading) in one of its
    presets (render/ao.py PRESETS): GTAO at half resolution with a depth-aware upsample (the
    default), GTAO_FULL at full resolution, GTAO_LOW at half resolution with fewer samples."""

    OFF = 0
    GTAO = 1
    GTAO_FULL = 2
    GTAO_LOW = 3


class TbnMode(Named):
    """How the vertex stream carries the tangent frame (one vertex shader each)."""

    VECTORS = 0  # normal vec3 + tangent vec4
    QUAT = 1  # one float quaternion (QTangent, handedness in the sign)
    PACKED = 2  # the quaternion packed in one uint32


def enum_by_name(enum_type: type[enum.IntEnum], name: str | enum.IntEnum) -> enum.IntEnum:
    """Parse a user-facing name ("blinn-phong", "mapped_normal") into an enum member (a
    member is returned as it is)."""
    from vkpbr.errors import UsageError

    if isinstance(name, enum_type):
        return name
    if not isinstance(name, str):
        raise UsageError(f"{enum_type.__name__.lower()} {name!r}: expected a name such as "
                         f"{next(iter(enum_type)).name.lower()!r}")
    key = name.strip().upper().replace("-", "_")
    try:
        return enum_type[key]
    except KeyError:
        names = ", ".join(m.name.lower().replace("_", "-") for m in enum_type)
        raise UsageError(f"unknown {enum_type.__name__.lower()} {name!r}; choose one of: {names}") from None
