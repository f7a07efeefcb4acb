# glTF 2.0 (.gltf / .glb) -> vkpbr Scene, the entry point. The importer is split by concept:
# gltf_document (JSON, GLB, buffers, accessors), gltf_meshes (primitives), gltf_materials
# (images, samplers, materials), gltf_nodes (hierarchy, cameras, lights), gltf_animation (skins,
# animations); the arrows point one way, from here down to gltf_document. Reference: the glTF 2.0 specification (Khronos).

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from vkpbr.errors import SceneError
from vkpbr.scene.gltf_animation import build_animations, build_skins
from vkpbr.scene.gltf_document import SUPPORTED_EXTENSIONS, GltfDocument
from vkpbr.scene.gltf_materials import apply_variant, build_materials, load_images
from vkpbr.scene.gltf_nodes import build_nodes_cameras_lights
from vkpbr.scene.resources import ResourcePolicy, read_resource
from vkpbr.scene.types import Scene

__all__ = ["load_gltf", "SUPPORTED_EXTENSIONS"]


def load_gltf(path: str | Path, policy: ResourcePolicy | None = None,
              variant: str | None = None) -> Scene:
    """Load a .gltf or .glb file.

    Parameters
    ----------
    path : the file; external buffers and images resolve relative to its folder.
    policy : where those files may lie (default: the file's folder tree only).
    variant : a KHR_materials_variants variant name: its materials replace the primitives'
        (None: the file's default materials). `Scene.variants` lists the file's names.

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
        raw = read_resource(path)
    except OSError as exc:
        raise SceneError(path, f"cannot read: {exc.strerror or exc}") from exc
    try:
        # Overflow/NaN from hostile values is handled explicitly (drop_nonfinite, range
        # checks), so numpy must not turn it into FloatingPointError under np.seterr(raise).
        with np.errstate(all="ignore"):
            return _build(GltfDocument(path, raw, policy or ResourcePolicy(path)), variant)
    except SceneError:
        raise
    except (TypeError, ValueError, KeyError, IndexError, AttributeError, OverflowError,
            RecursionError, struct.error) as exc:  # fmt: skip
        # A value of the wrong JSON type that no explicit check anticipated is still the file's
        # fault; keep the promise that users only ever see SceneError.
        raise SceneError(path, f"malformed glTF ({type(exc).__name__}: {exc})") from exc


def _build(ld: GltfDocument, variant: str | None = None) -> Scene:
    """The Scene of a parsed document (meshes on demand, only for nodes of the displayed scene)."""
    scene = Scene(name=ld.path.stem, source=ld.path)
    scene.variants = apply_variant(ld, variant)
    scene.images = load_images(ld)
    scene.materials = build_materials(ld, len(scene.images))
    links = build_nodes_cameras_lights(ld, scene)
    build_skins(ld, scene, links)
    build_animations(ld, scene, links)
    return scene
