# A trimesh.Trimesh or trimesh.Scene read into plain parts (NumPy arrays, material field values,
# decoded images, node matrices) that `Scene.from_trimesh` (types.py) assembles into vkpbr's
# dataclasses. This module imports no scene type, so types.py imports it with a plain import and
# the arrows point one way: trimesh_import.py (load_scene's reader) -> types.py -> here.
# trimesh itself is imported only when a trimesh object is met (`pip install 'vkpbr[trimesh]'`).
#
# Conversions: every trimesh geometry becomes one mesh (a Trimesh has one material), every
# graph node that instances one a node with its world transform. trimesh stores UVs with
# OpenGL's bottom-left origin (v up); vkpbr uses glTF's top-left, so v' = 1 - v. PBRMaterial
# maps field for field onto Material (glTF semantics, the packed metallic-roughness texture
# read twice through channels B and G); SimpleMaterial goes through trimesh's own to_pbr().
# Vertex and face colours are 8-bit sRGB-encoded in trimesh (PLY's convention) and linear in
# vkpbr (glTF COLOR_0): decoded with the sRGB curve, alpha kept linear. Normals: the file's
# own (trimesh caches them when a file or the user gives them), else flat ones (normals.py):
# trimesh's computed vertex normals would smooth an STL box.
# Reference: trimesh's docs (trimesh.org), trimesh/visual/material.py.

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.scene.camera import Camera
from vkpbr.scene.color import SRGB_TO_LINEAR_U8
from vkpbr.scene.normals import unweld_flat

__all__ = ["INSTALL_HINT", "MaterialParts", "TrimeshParts", "read_trimesh"]

log = logging.getLogger(__name__)

INSTALL_HINT = "pip install 'vkpbr[trimesh]'"


@dataclass
class MaterialParts:
    """One Material: `fields` its factors and flags by field name, `textures` its texture
    slots ("base_color_texture", ...) as (image index, channel)."""

    fields: dict[str, Any]
    textures: dict[str, tuple[int, int]]


@dataclass
class TrimeshParts:
    """A trimesh object as the fields of vkpbr's scene types.

    meshes: Mesh fields by name (positions, normals (N, 3), texcoords (N, 2), colors (N, 4)
        float32, indices (M,) uint32, name, material). images: (name, (H, W, 4) uint8 RGBA).
    nodes: (mesh index, (4, 4) float32 world matrix, name).
    """

    name: str
    meshes: list[dict[str, Any]] = field(default_factory=list)
    materials: list[MaterialParts] = field(default_factory=list)
    images: list[tuple[str, np.ndarray]] = field(default_factory=list)
    nodes: list[tuple[int, np.ndarray, str]] = field(default_factory=list)
    cameras: list[Camera] = field(default_factory=list)


# -- materials and textures ---------------------------------------------------------------------


class _Images:
    """PIL images -> TrimeshParts.images, each decoded once however many materials use it."""

    def __init__(self, images: list[tuple[str, np.ndarray]]) -> None:
        self.images = images
        self.index: dict[int, int] = {}

    def add(self, pil: Any, slot: str, textures: dict[str, tuple[int, int]],
            channel: int = 0) -> None:
        if pil is None:
            return
        key = id(pil)
        if key not in self.index:
            rgba = np.ascontiguousarray(np.asarray(pil.convert("RGBA"), dtype=np.uint8))
            name = getattr(pil, "filename", "") or f"trimesh image {len(self.images)}"
            self.index[key] = len(self.images)
            self.images.append((str(name), rgba))
        textures[slot] = (self.index[key], channel)


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


def _material(mat: Any, images: _Images) -> MaterialParts:
    from trimesh.visual.material import PBRMaterial

    if not isinstance(mat, PBRMaterial):
        mat = mat.to_pbr()  # SimpleMaterial (OBJ-style): trimesh's own conversion
    mode = str(mat.alphaMode or "OPAQUE").lower()
    fields: dict[str, Any] = {
        "name": str(getattr(mat, "name", None) or "trimesh material"),
        "base_color_factor": _factor(mat.baseColorFactor, 4, (1.0, 1.0, 1.0, 1.0)),
        "metallic_factor": 1.0 if mat.metallicFactor is None else float(mat.metallicFactor),
        "roughness_factor": 1.0 if mat.roughnessFactor is None else float(mat.roughnessFactor),
        "emissive_factor": _factor(mat.emissiveFactor, 3, (0.0, 0.0, 0.0)),
        "alpha_mode": mode if mode in ("opaque", "mask", "blend") else "opaque",
        "double_sided": bool(mat.doubleSided),
    }
    if mat.alphaCutoff is not None:
        fields["alpha_cutoff"] = float(mat.alphaCutoff)
    textures: dict[str, tuple[int, int]] = {}
    images.add(mat.baseColorTexture, "base_color_texture", textures)
    images.add(mat.metallicRoughnessTexture, "metallic_texture", textures, channel=2)  # glTF: B
    images.add(mat.metallicRoughnessTexture, "roughness_texture", textures, channel=1)  # glTF: G
    images.add(mat.normalTexture, "normal_texture", textures)
    images.add(mat.occlusionTexture, "occlusion_texture", textures)
    images.add(mat.emissiveTexture, "emissive_texture", textures)
    return MaterialParts(fields, textures)


# -- geometry -------------------------------------------------------------------------------------


def _colors(u8: np.ndarray) -> np.ndarray:
    """(N, 3|4) uint8 sRGB-encoded colours -> (N, 4) float32 linear RGB, linear alpha."""
    u8 = np.asarray(u8, dtype=np.uint8)
    out = np.ones((len(u8), 4), np.float32)
    out[:, :3] = SRGB_TO_LINEAR_U8[u8[:, :3]]
    if u8.shape[1] > 3:
        out[:, 3] = u8[:, 3] / 255.0
    return out


def _mesh(geom: Any, name: str, parts: TrimeshParts, images: _Images,
          material_index: dict[int, int]) -> dict[str, Any]:
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
                material_index[id(mat)] = len(parts.materials)
                parts.materials.append(_material(mat, images))
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
    arrays = {k: v for k, v in (("positions", positions), ("normals", normals),
                                ("texcoords", texcoords), ("colors", colors)) if v is not None}
    indices = faces.reshape(-1).astype(np.uint32)
    if normals is None:
        arrays, indices = unweld_flat(arrays, indices)
    return {"name": name, "material": material, "indices": np.ascontiguousarray(indices),
            **{k: np.ascontiguousarray(v, dtype=np.float32) for k, v in arrays.items()}}


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


def read_trimesh(scene_or_mesh: Any, name: str | None = None) -> TrimeshParts:
    """The parts of a `trimesh.Trimesh` or `trimesh.Scene` (`Scene.from_trimesh` documents
    what they become). UsageError: not a trimesh Trimesh or Scene, trimesh not installed, a
    non-finite node transform, or nothing with triangles in it. Point clouds and paths are
    skipped with a warning."""
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
    parts = TrimeshParts(name=str(label))
    images = _Images(parts.images)
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
            mesh_index[geom_name] = len(parts.meshes)
            parts.meshes.append(_mesh(geom, str(geom_name), parts, images, material_index))
        m = np.asarray(matrix, dtype=np.float64)
        if not np.isfinite(m).all():
            raise UsageError(f"from_trimesh: node {node!r} has a non-finite transform")
        parts.nodes.append((mesh_index[geom_name], m.astype(np.float32), str(node)))
    if skipped:
        warnings.warn(f"from_trimesh: skipped {len(skipped)} geometries without triangles: "
                      f"{', '.join(sorted(skipped)[:3])}", stacklevel=3)
    if not parts.nodes:
        raise UsageError("from_trimesh: nothing with triangles to render")
    parts.cameras = _camera(tscene)
    return parts
