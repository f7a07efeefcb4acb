"""Scene data: plain dataclasses holding NumPy arrays. No Vulkan here.

Every loader (glTF, OBJ/MTL, .comp5822mesh, baked .vkpbr, the built-in default scene) produces
a `Scene`; the renderer consumes one. Conventions:

- Right-handed world space, +Y up (glTF). Lengths in scene units (metres for glTF).
- Arrays are C-contiguous: positions/normals (N, 3) float32, texcoords (N, 2) float32 with
  glTF's convention (origin at the image's top-left, v down), tangents (N, 4) float32 with
  w = +-1 handedness (bitangent = w * cross(n, t)), indices (M,) uint32, M a multiple of 3.
- Textures hold encoded bytes or decoded pixels; decoding is deferred so that a loader can
  decode many images in parallel (see `vkpbr.scene.textures`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from vkpbr.scene.camera import Camera  # noqa: F401 - defined there, a scene type like the others
from vkpbr.scene.material_table import DEFAULTS as _D
from vkpbr.scene.material_table import TEXTURES
from vkpbr.scene.tree import NodeTree

__all__ = [
    "AlphaMode",
    "Camera",
    "Image",
    "Light",
    "Material",
    "Mesh",
    "Node",
    "Sampler",
    "Scene",
    "TextureRef",
    "Skin",
    "Animation",
    "AnimationChannel",
    "AnimationSampler",
    "expand_instances",
    "MeshBox",
    "mesh_box",
    "points_box",
    "scene_bounds",
    "TEXTURE_SLOTS",
    "SRGB_TEXTURE_SLOTS",
]

AlphaMode = Literal["opaque", "mask", "blend"]
Wrap = Literal["repeat", "clamp", "mirror"]
Filter = Literal["linear", "nearest"]


@dataclass
class Image:
    """One source image. Exactly one of `pixels`, `data` or `path` is the source.

    pixels: (H, W, 4) uint8 RGBA, already decoded (generated textures, decoded files).
    data:   encoded bytes (PNG/JPEG...) embedded in the scene file.
    path:   a file on disk.
    `name` is what warnings and errors print (usually the file name).
    refused: why the path policy (vkpbr.scene.resources) will not read `path` ("outside the
        scene's folder", "not regular files"); such an image is never opened and is reported
        and replaced like a missing file.
    mips:   levels 1.. of the mip chain below `pixels` (baked files; see vkpbr.scene.mips),
        each (h, w, 4) uint8, filtered as sRGB colour when `mips_srgb`; () = made on upload.
    """

    name: str
    pixels: np.ndarray | None = None
    data: bytes | None = None
    path: Path | None = None
    mime_type: str | None = None
    mips: tuple[np.ndarray, ...] = ()
    mips_srgb: bool = False
    refused: str | None = None


@dataclass(frozen=True)
class Sampler:
    """Texture addressing and filtering (glTF sampler semantics)."""

    wrap_s: Wrap = "repeat"
    wrap_t: Wrap = "repeat"
    mag_filter: Filter = "linear"
    min_filter: Filter = "linear"
    mipmaps: bool = True


@dataclass
class TextureRef:
    """A material's use of an image.

    channel: which channel of the image holds a scalar map (0=R, 1=G, 2=B, 3=A); glTF's packed
        metallic-roughness texture is referenced twice, metallic with channel 2 and roughness
        with channel 1, and the renderer serves both from one GPU image through swizzled views.
    texcoord: which UV set (0 or 1).
    offset/rotation/scale: KHR_texture_transform (uv' = T * R * S * uv).
    """

    image: int
    sampler: Sampler = field(default_factory=Sampler)
    channel: int = 0
    texcoord: int = 0
    offset: tuple[float, float] = (0.0, 0.0)
    rotation: float = 0.0
    scale: tuple[float, float] = (1.0, 1.0)


@dataclass
class Material:
    """Metallic-roughness material (glTF 2.0 core) with the KHR_materials_* layers. Factors
    multiply the textures. KHR_materials_emissive_strength is folded into emissive_factor.

    The numeric parameters' defaults, ranges and glTF properties are rows of
    vkpbr.scene.material_table (`_D[...]` below): a parameter is that row and its field here."""

    name: str = "default"
    base_color_factor: tuple[float, float, float, float] = _D["base_color_factor"]
    metallic_factor: float = _D["metallic_factor"]
    roughness_factor: float = _D["roughness_factor"]
    emissive_factor: tuple[float, float, float] = _D["emissive_factor"]
    normal_scale: float = _D["normal_scale"]
    occlusion_strength: float = _D["occlusion_strength"]
    alpha_mode: AlphaMode = "opaque"
    alpha_cutoff: float = _D["alpha_cutoff"]
    double_sided: bool = False
    # False: invisible to shadow maps (a bulb around its own light; Blender's shadow mode none).
    casts_shadows: bool = True
    base_color_texture: TextureRef | None = None  # sRGB; alpha in A
    metallic_texture: TextureRef | None = None  # linear; `channel` picks the component
    roughness_texture: TextureRef | None = None  # linear; `channel` picks the component
    normal_texture: TextureRef | None = None  # linear, tangent space, xyz*2-1
    occlusion_texture: TextureRef | None = None  # linear, R
    emissive_texture: TextureRef | None = None  # sRGB
    # Separate alpha mask (OBJ map_d, .comp5822mesh): `channel` holds coverage. When None the
    # alpha comes from base_color_texture's A, as in glTF.
    alpha_texture: TextureRef | None = None  # linear
    # The KHR_materials_* extensions. Defaults are the core material's: every layer off, ior
    # 1.5 (F0 0.04), white specular. Their textures (below) multiply the factors.
    unlit: bool = False  # KHR_materials_unlit: the base colour is the radiance
    # KHR_materials_pbrSpecularGlossiness (converted when read: scene/gltf_materials.py):
    # roughness_factor and roughness_texture hold glossiness, roughness = 1 - their product.
    glossiness: bool = False
    ior: float = _D["ior"]  # KHR_materials_ior: dielectric F0 = ((ior - 1) / (ior + 1))^2
    specular_factor: float = _D["specular_factor"]  # KHR_materials_specular: dielectric weight
    specular_color_factor: tuple[float, float, float] = _D["specular_color_factor"]  # scales F0
    clearcoat_factor: float = _D["clearcoat_factor"]  # KHR_materials_clearcoat
    clearcoat_roughness_factor: float = _D["clearcoat_roughness_factor"]
    sheen_color_factor: tuple[float, float, float] = _D["sheen_color_factor"]  # KHR_materials_sheen
    sheen_roughness_factor: float = _D["sheen_roughness_factor"]
    transmission_factor: float = _D["transmission_factor"]  # KHR_materials_transmission
    thickness_factor: float = _D["thickness_factor"]  # KHR_materials_volume: 0 = thin-walled
    attenuation_distance: float = _D["attenuation_distance"]  # 0 = infinite (no absorption)
    attenuation_color: tuple[float, float, float] = _D["attenuation_color"]
    clearcoat_normal_scale: float = _D["clearcoat_normal_scale"]
    anisotropy_strength: float = _D["anisotropy_strength"]  # KHR_materials_anisotropy
    anisotropy_rotation: float = _D["anisotropy_rotation"]  # radians from the tangent
    iridescence_factor: float = _D["iridescence_factor"]  # KHR_materials_iridescence
    iridescence_ior: float = _D["iridescence_ior"]  # the thin film's
    iridescence_thickness_minimum: float = _D["iridescence_thickness_minimum"]  # nanometres
    iridescence_thickness_maximum: float = _D["iridescence_thickness_maximum"]
    # KHR_materials_diffuse_transmission
    diffuse_transmission_factor: float = _D["diffuse_transmission_factor"]
    diffuse_transmission_color_factor: tuple[float, float, float] = _D["diffuse_transmission_color_factor"]
    dispersion: float = _D["dispersion"]  # KHR_materials_dispersion: 20 / Abbe number
    # The extensions' textures; `channel` picks a scalar map's component, as for metallic.
    clearcoat_texture: TextureRef | None = None  # linear; glTF: R
    clearcoat_roughness_texture: TextureRef | None = None  # linear; glTF: G
    clearcoat_normal_texture: TextureRef | None = None  # linear, tangent space, xyz*2-1
    sheen_color_texture: TextureRef | None = None  # sRGB; RGB
    sheen_roughness_texture: TextureRef | None = None  # linear; glTF: A
    specular_texture: TextureRef | None = None  # linear; glTF: A
    specular_color_texture: TextureRef | None = None  # sRGB; RGB
    transmission_texture: TextureRef | None = None  # linear; glTF: R
    thickness_texture: TextureRef | None = None  # linear; glTF: G
    anisotropy_texture: TextureRef | None = None  # linear; RG direction * 2 - 1, B strength
    iridescence_texture: TextureRef | None = None  # linear; glTF: R
    iridescence_thickness_texture: TextureRef | None = None  # linear; glTF: G (min..max)
    diffuse_transmission_texture: TextureRef | None = None  # linear; glTF: A
    diffuse_transmission_color_texture: TextureRef | None = None  # sRGB; RGB


# Every Material texture slot (the field is f"{slot}_texture"), and those holding colour
# (sRGB-encoded: decoded by the GPU's sRGB formats); the others are linear data.
TEXTURE_SLOTS = tuple(slot.name for slot in TEXTURES)
SRGB_TEXTURE_SLOTS = frozenset(slot.name for slot in TEXTURES if slot.srgb)


@dataclass
class Mesh:
    """One triangle list with one material (a glTF primitive, an OBJ group)."""

    name: str
    positions: np.ndarray  # (N, 3) float32
    indices: np.ndarray  # (M,) uint32, M % 3 == 0
    normals: np.ndarray | None = None  # (N, 3) float32; None -> flat normals are generated
    texcoords: np.ndarray | None = None  # (N, 2) float32, TEXCOORD_0
    texcoords1: np.ndarray | None = None  # (N, 2) float32, TEXCOORD_1
    tangents: np.ndarray | None = None  # (N, 4) float32; None -> generated when normal-mapped
    colors: np.ndarray | None = None  # (N, 4) float32 COLOR_0, multiplies base colour
    material: int = -1  # index into Scene.materials; -1 = the default material
    qtangents: np.ndarray | None = None  # (N, 4) float32 QTangent frames (baked scenes)
    packed_frames: np.ndarray | None = None  # (N,) uint32 packed frames (baked scenes)
    # Skinning (glTF JOINTS_0/1, WEIGHTS_0/1; docs/animation.md): up to 8 influences a vertex,
    # set 0's four then set 1's, zeros where a set is absent; weights sum to 1 per row.
    joints: np.ndarray | None = None  # (N, 8) uint16 indices into the node's Skin.joints
    weights: np.ndarray | None = None  # (N, 8) float32
    # Morph targets: {"POSITION" | "NORMAL" | "TANGENT": (T, N, 3) float32 displacements}, an
    # attribute the targets do not give is absent; morph_weights the mesh's default weights.
    morph_targets: dict[str, np.ndarray] = field(default_factory=dict)
    morph_weights: np.ndarray | None = None  # (T,) float64, zeros when the file gives none

    @property
    def vertex_count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def triangle_count(self) -> int:
        return int(self.indices.shape[0] // 3)


@dataclass
class Node:
    """An instance of a mesh in the world: `matrix` is the full model-to-world transform.

    instances: (K, 4, 4) float32 per-instance transforms (glTF EXT_mesh_gpu_instancing), each
        relative to `matrix`: instance k's model-to-world transform is matrix @ instances[k].
        None = one instance, `matrix` alone. The mesh is stored once, never copied per
        instance; `instance_matrices` gives the K world matrices.
    """

    mesh: int
    matrix: np.ndarray = field(default_factory=lambda: np.eye(4, dtype=np.float32))  # (4, 4)
    name: str = ""
    instances: np.ndarray | None = None  # (K, 4, 4) float32
    # The class the file gives it: glTF `extras: {"semantic": 3}` or `{"semantic": "chair"}`
    # on the node (else on its mesh); None: none given (vkpbr.scene.semantics).
    semantic: int | str | None = None
    # The node of Scene.tree this hangs from (its index there); -1: not yet given one
    # (Scene.node_tree() then gives each such Node a root of its own).
    tree: int = -1

    @property
    def instance_count(self) -> int:
        return 1 if self.instances is None else int(len(self.instances))

    def instance_matrices(self) -> np.ndarray:
        """(K, 4, 4) float64 model-to-world matrices, one per instance (K = 1 without)."""
        m = np.asarray(self.matrix, dtype=np.float64)
        if self.instances is None:
            return m[None]
        return m @ np.asarray(self.instances, dtype=np.float64)


def expand_instances(nodes: list[Node]) -> list[Node]:
    """Nodes with one Node per instance (matrix = world matrix, instances None), in order; a
    node without instances is returned as is. For consumers that draw or store one matrix
    per node (the renderer until it draws instanced, the baked format)."""
    out: list[Node] = []
    for node in nodes:
        if node.instances is None:
            out.append(node)
            continue
        for k, world in enumerate(node.instance_matrices()):
            out.append(Node(mesh=node.mesh, matrix=world.astype(np.float32),
                            name=f"{node.name}[{k}]"))
    return out


@dataclass(frozen=True)
class Light:
    """A punctual light (glTF KHR_lights_punctual).

    kind : "point", "spot" or "directional".
    position : world position (point and spot lights).
    direction : unit world direction the light travels (spot and directional; glTF's -Z of
        the light's node).
    color, intensity : linear RGB and a scale: candela for point and spot lights, lux for
        directional ones (glTF's units).
    falloff : "inverse_square" (physical; glTF) or "none" (the course's: no attenuation).
    range : distance where a point or spot light's influence ends (glTF's smooth window);
        0 = infinite.
    inner_cone, outer_cone : spot cone half-angles in radians, 0 <= inner < outer <= pi/2
        (glTF's defaults 0 and pi/4).
    shadows : whether the light casts shadows (the physically based mode).
    """

    position: tuple[float, float, float] = (0.0, 2.0, 0.0)
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    intensity: float = 1.0
    falloff: Literal["none", "inverse_square"] = "none"
    range: float = 0.0  # 0 = infinite (glTF)
    kind: Literal["point", "spot", "directional"] = "point"
    direction: tuple[float, float, float] = (0.0, -1.0, 0.0)
    inner_cone: float = 0.0
    outer_cone: float = math.pi / 4
    shadows: bool = True


@dataclass
class Skin:
    """A glTF skin, its joints as tree nodes (Scene.tree indices).

    joints : (J,) int64 tree indices; a vertex's JOINTS value j means joints[j].
    inverse_bind : (J, 4, 4) float64 inverse bind matrices (identity where the file has none).
    skeleton : the tree index of the skeleton root the file names, None if it names none (it is
        informative only: joint matrices use the joints' world transforms alone).
    """

    name: str
    joints: np.ndarray
    inverse_bind: np.ndarray
    skeleton: int | None = None


Interpolation = Literal["STEP", "LINEAR", "CUBICSPLINE"]


@dataclass
class AnimationSampler:
    """Keyframes: `input` (k,) float64 strictly increasing times in seconds; `output` the
    values, (k, C) float64 for STEP and LINEAR, (k, 3, C) for CUBICSPLINE (in-tangent, value,
    out-tangent per keyframe, as glTF stores them). C is 3 (translation, scale), 4 (rotation
    quaternion x, y, z, w), T (morph weights) or the pointed-at property's size."""

    input: np.ndarray
    output: np.ndarray
    interpolation: Interpolation = "LINEAR"


@dataclass
class AnimationChannel:
    """What one sampler drives.

    path : "translation", "rotation", "scale" or "weights" of tree node `node` (also when a
        KHR_animation_pointer names a node's property), or "pointer" for the other
        KHR_animation_pointer targets.
    node : the tree index for node paths, else None.
    pointer : the KHR_animation_pointer string ("/materials/0/pbrMetallicRoughness/
        baseColorFactor"), None for a plain channel.
    kind, index, member : a pointer's target parsed: kind "material" | "light" | "camera" |
        "mesh", the file's index of that object, and the vkpbr field it sets
        ("base_color_factor", "metallic_factor", "roughness_factor", "emissive_factor",
        "emissive_strength", "color", "intensity", "range", "inner_cone", "outer_cone",
        "yfov", "weights"); None for node paths.
    targets : the Scene objects a pointer changes: indices into scene.materials,
        scene.lights or scene.cameras (every one made from that file object), or for
        "/meshes/M/weights" the tree nodes showing mesh M; () for node paths.
    rest : (C,) float64, a pointer's property as the file gives it (else glTF's default):
        its value with no animation playing (for emissive_strength, the strength that
        Material.emissive_factor already includes); None for node paths.
    """

    sampler: int
    path: Literal["translation", "rotation", "scale", "weights", "pointer"]
    node: int | None = None
    pointer: str | None = None
    kind: str | None = None
    index: int | None = None
    member: str | None = None
    targets: tuple[int, ...] = ()
    rest: np.ndarray | None = None


@dataclass
class Animation:
    """A glTF animation: channels, each driven by one of `samplers`."""

    name: str
    channels: list[AnimationChannel] = field(default_factory=list)
    samplers: list[AnimationSampler] = field(default_factory=list)

    @property
    def duration(self) -> float:
        """Seconds from 0 to the last keyframe of any sampler a channel uses (0 when none):
        times past it hold the last values."""
        ends = [float(self.samplers[c.sampler].input[-1]) for c in self.channels]
        return max(ends, default=0.0)


@dataclass
class Scene:
    """Everything a renderer needs, as plain arrays."""

    name: str
    meshes: list[Mesh] = field(default_factory=list)
    materials: list[Material] = field(default_factory=list)
    images: list[Image] = field(default_factory=list)
    nodes: list[Node] = field(default_factory=list)
    lights: list[Light] = field(default_factory=list)
    cameras: list[Camera] = field(default_factory=list)
    # KHR_materials_variants: the file's variant names (the one loaded is chosen at load time).
    variants: list[str] = field(default_factory=list)
    source: Path | None = None  # the file it was loaded from, if any
    # The file's node hierarchy (vkpbr.scene.tree); None: flat (see node_tree()).
    tree: NodeTree | None = None
    # glTF skins and animations (docs/animation.md; sampled by vkpbr.scene.animation).
    skins: list[Skin] = field(default_factory=list)
    animations: list[Animation] = field(default_factory=list)

    def node_tree(self) -> NodeTree:
        """The node hierarchy: the file's, else one root per Node (made once, then kept);
        every Node's `tree` then names its tree node."""
        if self.tree is None or any(n.tree < 0 or n.tree >= len(self.tree) for n in self.nodes):
            self.tree = NodeTree.flat([n.matrix for n in self.nodes],
                                      [n.name or f"node {i}" for i, n in enumerate(self.nodes)])
            for i, n in enumerate(self.nodes):
                n.tree = i
        return self.tree

    def find(self, pattern: str) -> np.ndarray:
        """Indices into `node_tree()` of the nodes whose name or path ("truck/wheel") matches
        the shell-style `pattern` ("wheel*"), in tree order; empty when none does."""
        return self.node_tree().find(pattern)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World-space axis-aligned bounds of everything the scene draws: (lo, hi), two (3,)
        float64 arrays, the minimum and maximum x, y, z over every node's mesh (each instance
        of EXT_mesh_gpu_instancing included) after its world transform. Each mesh's own box
        is transformed (its 8 corners), so a rotated mesh's bounds may be a little loose. An
        empty scene gives two zero vectors. `CameraBatch.orbit / .sphere / .look_at_random
        (bounds=scene.bounds())` frame views with it; `Renderer.scene.bounds()` is the
        loaded scene's."""
        return scene_bounds(self)

    @property
    def triangle_count(self) -> int:
        return sum(self.meshes[n.mesh].triangle_count * n.instance_count for n in self.nodes)

    @classmethod
    def from_trimesh(cls, scene_or_mesh: object, name: str | None = None) -> Scene:
        """A Scene from a `trimesh.Trimesh` or `trimesh.Scene`. Needs trimesh (`pip install
        'vkpbr[trimesh]'`).

        Parameters
        ----------
        scene_or_mesh : a Trimesh (one Mesh, one identity Node) or a trimesh Scene (one Mesh
            per triangle geometry, one Node per graph node that instances one, with the
            node's world transform). Point clouds and paths are skipped with a warning.
        name : the Scene's name (default: the trimesh object's, else "trimesh").

        Returns
        -------
        Scene whose meshes have float32 positions (N, 3), normals (N, 3) (the file's, else
        flat), texcoords (N, 2) with glTF's top-left origin, colors (N, 4) linear, uint32
        indices; materials from PBRMaterial (factors, textures, alpha mode, double-sided) or
        SimpleMaterial (through trimesh's to_pbr); images decoded to (H, W, 4) uint8; the
        scene's camera, if it has one.

        Raises
        ------
        UsageError : trimesh not installed (with the install line), not a trimesh Trimesh or
            Scene, a node with a non-finite transform, or nothing with triangles in it.
        """
        # trimesh_parts reads the trimesh object into plain arrays and imports no scene type,
        # so this import makes no cycle; the dataclasses are built here, where they live.
        from vkpbr.scene.trimesh_parts import read_trimesh

        parts = read_trimesh(scene_or_mesh, name)
        materials = [Material(**m.fields, **{slot: TextureRef(image=image, channel=channel)
                                             for slot, (image, channel) in m.textures.items()})
                     for m in parts.materials]
        return cls(name=parts.name,
                   meshes=[Mesh(**fields) for fields in parts.meshes],
                   materials=materials,
                   images=[Image(name=n, pixels=pixels) for n, pixels in parts.images],
                   nodes=[Node(mesh=mesh, matrix=matrix, name=n) for mesh, matrix, n in parts.nodes],
                   cameras=parts.cameras)


MeshBox = Callable[[int], tuple[np.ndarray, np.ndarray]]  # mesh index -> (min, max)


def points_box(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) per column of (N, K) points (N > 0), in their dtype: `points.min(axis=0)`
    and `.max(axis=0)`, column by column. NumPy reduces a C-ordered (N, 3) array along axis 0
    3 elements at a time, 12-18x slower than a column's strided reduction (0.11 ms against
    9 us for 4,300 vertices, 13.7 against 0.76 ms for 528,000: MetalRoughSpheresNoTextures'
    bounds were a third of its load from the bake cache)."""
    cols = range(points.shape[1])
    lo = np.array([points[:, k].min() for k in cols], dtype=points.dtype)
    hi = np.array([points[:, k].max() for k in cols], dtype=points.dtype)
    return lo, hi


def mesh_box(scene: Scene) -> MeshBox:
    """Mesh i's (min, max) over its positions, per axis in their dtype, computed when asked
    (`scene_bounds`' default; a GpuScene computes each mesh's once for all its users)."""
    def box(i: int) -> tuple[np.ndarray, np.ndarray]:
        return points_box(scene.meshes[i].positions)

    return box


def scene_bounds(scene: Scene, box: MeshBox | None = None) -> tuple[np.ndarray, np.ndarray]:
    """`Scene.bounds()`, each mesh's own box from `box(mesh index)` (None: `mesh_box`)."""
    box = mesh_box(scene) if box is None else box
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    corners = np.array(
        [[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=np.float64
    )
    for node in scene.nodes:
        if len(scene.meshes[node.mesh].positions) == 0:
            continue
        pmin, pmax = box(node.mesh)
        corners_box = pmin + corners * (pmax - pmin)
        for m in node.instance_matrices():  # every instance of EXT_mesh_gpu_instancing
            world = corners_box @ m[:3, :3].T + m[:3, 3]
            lo = np.minimum(lo, world.min(axis=0))
            hi = np.maximum(hi, world.max(axis=0))
    if not np.all(np.isfinite(lo)):
        return np.zeros(3), np.zeros(3)
    return lo, hi
