# trimesh interop: a trimesh.Trimesh or trimesh.Scene -> vkpbr Scene (`Scene.from_trimesh`),
# and `load_scene`'s reader for the formats vkpbr does not parse itself (PLY, STL, OFF, ...),
# through trimesh as an optional extra (`pip install 'vkpbr[trimesh]'`). NumPy only; trimesh
# is imported only when a trimesh object or file is met, never when vkpbr is imported.
#
# Conversions: every trimesh geometry becomes one Mesh (a Trimesh has one material), every
# graph node that instances one a Node with its world transform. trimesh stores UVs with
# OpenGL's bottom-left origin (v up); vkpbr uses glTF's top-left, so v' = 1 - v. PBRMaterial
# maps field for field onto Material (glTF semantics, the packed metallic-roughness texture
# read twice through channels B and G); SimpleMaterial goes through trimesh's own to_pbr().
# Vertex and face colours are 8-bit sRGB-encoded in trimesh (PLY's convention) and linear in
# vkpbr (glTF COLOR_0): decoded with the sRGB curve, alpha kept linear. Normals: the file's
# own (trimesh caches them when a file or the user gives them), else None, so that
# `ensure_normals` makes flat ones: trimesh's computed vertex normals would smooth an STL box.
# Reference: trimesh's docs (trimesh.org), trimesh/visual/material.py.

from __future__ import annotations

import io
import logging
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from vkpbr.errors import SceneError, UsageError
from vkpbr.scene.color import SRGB_TO_LINEAR_U8
from vkpbr.scene.geometry import ensure_normals, normalize_mesh_arrays
from vkpbr.scene.resources import ResourcePolicy, ResourceRefused, read_resource
from vkpbr.scene.types import Camera, Image, Material, Mesh, Node, Scene, TextureRef

__all__ = ["INSTALL_HINT", "TRIMESH_SUFFIXES", "from_trimesh", "load_trimesh", "trimesh_formats"]

log = logging.getLogger(__name__)

INSTALL_HINT = "pip install 'vkpbr[trimesh]'"
# The formats `load_scene` hands to trimesh (what trimesh 4/5 reads without extra packages,
# less those vkpbr reads itself). Used for the message when trimesh is missing.
TRIMESH_SUFFIXES = (".ply", ".stl", ".off", ".xyz", ".dxf", ".3mf", ".dae", ".zip")


def trimesh_formats() -> frozenset[str] | None:
    """The suffixes (".ply", ...) the installed trimesh loads, or None without trimesh."""
    try:
        import trimesh
    except ImportError:
        return None
    return frozenset(f".{f}" for f in trimesh.available_formats())


# -- materials and textures ---------------------------------------------------------------------


class _Images:
    """PIL images -> Scene.images, each decoded once however many materials use it."""

    def __init__(self, images: list[Image]) -> None:
        self.images = images
        self.index: dict[int, int] = {}

    def ref(self, pil: Any, channel: int = 0) -> TextureRef | None:
        if pil is None:
            return None
        key = id(pil)
        if key not in self.index:
            rgba = np.ascontiguousarray(np.asarray(pil.convert("RGBA"), dtype=np.uint8))
            name = getattr(pil, "filename", "") or f"trimesh image {len(self.images)}"
            self.index[key] = len(self.images)
            self.images.append(Image(name=str(name), pixels=rgba))
        return TextureRef(image=self.index[key], channel=channel)


def _factor(value: Any, n: int, default: tuple[float, ...]) -> tuple[float, ...]:
    """A trimesh colour or factor: None -> default; uint8 (trimesh's colours) -> /255."""
    if value is None:
        return default
    a = np.asarray(value)
    a = a.astype(np.float64) / 255.0 if a.dtype == np.uint8 else a.astype(np.float64)
    a = a.reshape(-1)
    if a.size < n:  # RGB where RGBA is wanted: opaque
        a = np.concatenate([a, default[a.size:]])
    return tuple(float(x) for x in a[:n])


def _material(mat: Any, images: _Images) -> Material:
    from trimesh.visual.material import PBRMaterial

    if not isinstance(mat, PBRMaterial):
        mat = mat.to_pbr()  # SimpleMaterial (OBJ-style): trimesh's own conversion
    out = Material(name=str(getattr(mat, "name", None) or "trimesh material"))
    out.base_color_factor = _factor(mat.baseColorFactor, 4, (1.0, 1.0, 1.0, 1.0))  # type: ignore[assignment]
    out.metallic_factor = 1.0 if mat.metallicFactor is None else float(mat.metallicFactor)
    out.roughness_factor = 1.0 if mat.roughnessFactor is None else float(mat.roughnessFactor)
    out.emissive_factor = _factor(mat.emissiveFactor, 3, (0.0, 0.0, 0.0))  # type: ignore[assignment]
    mode = str(mat.alphaMode or "OPAQUE").lower()
    out.alpha_mode = mode if mode in ("opaque", "mask", "blend") else "opaque"  # type: ignore[assignment]
    if mat.alphaCutoff is not None:
        out.alpha_cutoff = float(mat.alphaCutoff)
    out.double_sided = bool(mat.doubleSided)
    out.base_color_texture = images.ref(mat.baseColorTexture)
    out.metallic_texture = images.ref(mat.metallicRoughnessTexture, channel=2)  # glTF: B
    out.roughness_texture = images.ref(mat.metallicRoughnessTexture, channel=1)  # glTF: G
    out.normal_texture = images.ref(mat.normalTexture)
    out.occlusion_texture = images.ref(mat.occlusionTexture)
    out.emissive_texture = images.ref(mat.emissiveTexture)
    return out


# -- geometry -------------------------------------------------------------------------------------


def _colors(u8: np.ndarray) -> np.ndarray:
    """(N, 3|4) uint8 sRGB-encoded colours -> (N, 4) float32 linear RGB, linear alpha."""
    u8 = np.asarray(u8, dtype=np.uint8)
    out = np.ones((len(u8), 4), np.float32)
    out[:, :3] = SRGB_TO_LINEAR_U8[u8[:, :3]]
    if u8.shape[1] > 3:
        out[:, 3] = u8[:, 3] / 255.0
    return out


def _mesh(geom: Any, name: str, materials: list[Material], images: _Images,
          material_index: dict[int, int]) -> Mesh:
    positions = np.asarray(geom.vertices, dtype=np.float32)
    faces = np.asarray(geom.faces, dtype=np.int64).reshape(-1, 3)
    # Normals the file (or the user) gave; trimesh computes smooth ones on demand otherwise.
    normals = (np.asarray(geom.vertex_normals, dtype=np.float32)
               if "vertex_normals" in geom._cache else None)
    visual = geom.visual
    kind = getattr(visual, "kind", None)
    texcoords = colors = None
    material = -1
    if kind == "texture":
        uv = getattr(visual, "uv", None)
        if uv is not None and len(uv) == len(positions):
            uv = np.asarray(uv, dtype=np.float32)[:, :2]
            texcoords = np.stack([uv[:, 0], 1.0 - uv[:, 1]], axis=1)  # bottom-left -> top-left
        mat = getattr(visual, "material", None)
        if mat is not None:
            if id(mat) not in material_index:
                material_index[id(mat)] = len(materials)
                materials.append(_material(mat, images))
            material = material_index[id(mat)]
    elif kind == "vertex":
        colors = _colors(visual.vertex_colors)
    elif kind == "face":
        # One colour per face: every face gets its own three vertices.
        corners = faces.reshape(-1)
        positions = positions[corners]
        normals = normals[corners] if normals is not None else None
        colors = np.repeat(_colors(visual.face_colors), 3, axis=0)
        faces = np.arange(len(corners), dtype=np.int64).reshape(-1, 3)
    mesh = Mesh(name=name, positions=positions, indices=faces.reshape(-1).astype(np.uint32),
                normals=normals, texcoords=texcoords, colors=colors, material=material)
    return normalize_mesh_arrays(ensure_normals(mesh))


def _camera(tscene: Any) -> list[Camera]:
    """The trimesh scene's camera, if it has one (trimesh makes a default one on access)."""
    if not getattr(tscene, "has_camera", False):
        return []
    try:
        fov = np.asarray(tscene.camera.fov, dtype=np.float64)
        return [Camera.from_pose(np.asarray(tscene.camera_transform, dtype=np.float64),
                                 "opengl", yfov_deg=float(fov[1]), name="trimesh camera")]
    except (UsageError, ValueError, IndexError, TypeError) as exc:
        log.info("trimesh camera not used: %s", exc)
        return []


def from_trimesh(scene_or_mesh: Any, name: str | None = None) -> Scene:
    """A vkpbr Scene from a `trimesh.Trimesh` or `trimesh.Scene`.

    Parameters
    ----------
    scene_or_mesh : a Trimesh (one Mesh, one identity Node) or a Scene (one Mesh per
        triangle geometry, one Node per graph node that instances one, with the node's world
        transform). Point clouds and paths are skipped with a warning.
    name : the Scene's name (default: the trimesh object's, else "trimesh").

    Returns
    -------
    Scene whose meshes have float32 positions (N, 3), normals (N, 3) (the file's, else flat),
    texcoords (N, 2) with glTF's top-left origin, colors (N, 4) linear, uint32 indices;
    materials from PBRMaterial (factors, textures, alpha mode, double-sided) or
    SimpleMaterial (through trimesh's to_pbr); images decoded to (H, W, 4) uint8; the
    scene's camera, if it has one.

    Raises
    ------
    UsageError : not a trimesh Trimesh or Scene, or nothing with triangles in it.
    """
    try:
        import trimesh
    except ImportError:
        raise UsageError(f"from_trimesh needs trimesh: {INSTALL_HINT}") from None
    if isinstance(scene_or_mesh, trimesh.Trimesh):
        tscene = trimesh.Scene(scene_or_mesh)
    elif isinstance(scene_or_mesh, trimesh.Scene):
        tscene = scene_or_mesh
    else:
        raise UsageError("from_trimesh: expected a trimesh.Trimesh or trimesh.Scene, got "
                         f"{type(scene_or_mesh).__name__}")
    label = name or getattr(scene_or_mesh, "metadata", {}).get("name") or "trimesh"
    scene = Scene(name=str(label))
    images = _Images(scene.images)
    material_index: dict[int, int] = {}
    mesh_index: dict[str, int] = {}
    skipped = set()
    for node in tscene.graph.nodes_geometry:
        matrix, geom_name = tscene.graph[node]
        geom = tscene.geometry.get(geom_name)
        if not isinstance(geom, trimesh.Trimesh):
            skipped.add(f"{geom_name} ({type(geom).__name__})")
            continue
        if len(geom.faces) == 0:
            skipped.add(f"{geom_name} (no faces)")
            continue
        if geom_name not in mesh_index:
            mesh_index[geom_name] = len(scene.meshes)
            scene.meshes.append(_mesh(geom, str(geom_name), scene.materials, images,
                                      material_index))
        m = np.asarray(matrix, dtype=np.float64)
        if not np.isfinite(m).all():
            raise UsageError(f"from_trimesh: node {node!r} has a non-finite transform")
        scene.nodes.append(Node(mesh=mesh_index[geom_name], matrix=m.astype(np.float32),
                                name=str(node)))
    if skipped:
        warnings.warn(f"from_trimesh: skipped {len(skipped)} geometries without triangles: "
                      f"{', '.join(sorted(skipped)[:3])}", stacklevel=2)
    if not scene.nodes:
        raise UsageError("from_trimesh: nothing with triangles to render")
    scene.cameras = _camera(tscene)
    return scene


# -- load_scene's fallback reader --------------------------------------------------------------


def _policy_resolver(policy: ResourcePolicy, refused: list[str]) -> Any:
    """A trimesh Resolver that reads the files a mesh names (a PLY's TextureFile) through
    vkpbr's path policy: inside the scene's folder tree, regular files only."""
    from trimesh.resolvers import Resolver

    class PolicyResolver(Resolver):
        def __init__(self) -> None:
            pass

        def get(self, key: str) -> bytes:
            try:
                return read_resource(policy.resolve(str(key), "texture"))
            except ResourceRefused as exc:
                refused.append(f"{key} ({exc.reason})")
                raise
            except OSError as exc:
                refused.append(f"{key} ({exc.strerror or exc})")
                raise

        def write(self, name: str, data: object) -> None:
            raise PermissionError("vkpbr's resolver is read-only")

        def namespaced(self, namespace: str) -> PolicyResolver:
            return self

        def keys(self) -> list[str]:
            return []

    return PolicyResolver()


def load_trimesh(path: str | Path, policy: ResourcePolicy | None = None) -> Scene:
    """Read a mesh file through trimesh (PLY, STL, OFF, ...): `load_scene`'s fallback.

    The file is read by vkpbr (regular files only) and handed to trimesh as bytes; files it
    names (a PLY's texture) go through `policy`. Raises SceneError naming the file: trimesh
    missing (with the install line), or whatever trimesh could not parse.
    """
    path = Path(path)
    try:
        import trimesh
    except ImportError:
        raise SceneError(path, f"reading {path.suffix or 'these'} files needs trimesh: "
                               f"{INSTALL_HINT}") from None
    policy = policy or ResourcePolicy(path)
    data = read_resource(path)  # an OSError here is load_scene's to report
    refused: list[str] = []
    try:
        loaded = trimesh.load_scene(io.BytesIO(data), file_type=path.suffix.lower().lstrip("."),
                                    resolver=_policy_resolver(policy, refused))
    except Exception as exc:  # noqa: BLE001 - a third-party parser: anything is "malformed"
        problem = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise SceneError(path, f"trimesh could not read it: {problem}") from None
    if refused:
        warnings.warn(f"{path}: {len(refused)} texture file(s) not read: {refused[0]}",
                      stacklevel=2)
    try:
        scene = from_trimesh(loaded, name=path.stem)
    except UsageError as exc:
        raise SceneError(path, str(exc).removeprefix("from_trimesh: ")) from None
    scene.source = path
    return scene
