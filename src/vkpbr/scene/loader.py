# One entry point for every scene format: picks the loader by file suffix, guarantees the
# renderer's invariants on the result (normals present, float32/uint32 C-contiguous arrays),
# whichever loader produced it, and reports missing texture files once for all formats
# (check_texture_files: one log line, or SceneError with strict). Every format's reader lives
# in scene/, the baked .vkpbr one included (scene/baked_file.py), so scene/ never imports bake/.

from __future__ import annotations

import os
import stat
from collections.abc import Callable
from pathlib import Path

from vkpbr.errors import SceneError
from vkpbr.scene.geometry import ensure_normals, normalize_mesh_arrays
from vkpbr.scene.presets import apply_presets
from vkpbr.scene.resources import ResourcePolicy
from vkpbr.scene.textures import check_texture_files
from vkpbr.scene.types import Scene
from vkpbr.scene.validate import validate_scene

__all__ = ["SUFFIXES", "load_scene"]

SUFFIXES = (".gltf", ".glb", ".obj", ".comp5822mesh", ".vkpbr")


def _loader(suffix: str) -> Callable[..., Scene] | None:
    # Imports are local so that loading one format never imports the others' dependencies
    # (the codecs for glTF, say).
    if suffix in (".gltf", ".glb"):
        from vkpbr.scene.gltf import load_gltf

        return load_gltf
    if suffix == ".obj":
        from vkpbr.scene.obj import load_obj

        return load_obj
    if suffix == ".comp5822mesh":
        from vkpbr.scene.comp5822 import read_comp5822mesh

        return read_comp5822mesh
    if suffix == ".vkpbr":
        from vkpbr.scene.baked_file import load_baked_scene

        return load_baked_scene
    return None


def _fallback(path: Path) -> Callable[..., Scene]:
    """trimesh for the formats vkpbr does not read itself (PLY, STL, OFF, ...), if installed;
    else a SceneError saying what is known, or how to read this format."""
    from vkpbr.scene.trimesh_import import (
        INSTALL_HINT,
        TRIMESH_SUFFIXES,
        load_trimesh,
        trimesh_formats,
    )

    suffix = path.suffix.lower()
    formats = trimesh_formats()
    if formats is not None and suffix in formats:
        return load_trimesh
    if formats is None and suffix in TRIMESH_SUFFIXES:
        raise SceneError(path, f"{suffix} files load through trimesh, which is not installed: "
                               f"{INSTALL_HINT}")
    more = f", and through trimesh {', '.join(sorted(formats - set(SUFFIXES)))}" if formats else ""
    raise SceneError(path, f"unknown scene format {path.suffix!r} (known: {', '.join(SUFFIXES)}"
                           f"{more})")


def load_scene(path: str | Path, strict: bool = False, allow_outside_paths: bool = False, *,
               root: str | Path | None = None, variant: str | None = None) -> Scene:
    """Load a scene file of any supported format.

    Parameters
    ----------
    path : a .gltf, .glb, .obj, .comp5822mesh or .vkpbr file (suffix case-insensitive), or
        any other format trimesh reads (PLY, STL, OFF, ...) when trimesh is installed
        (`pip install 'vkpbr[trimesh]'`; vkpbr.scene.trimesh_import).
    strict : a missing texture file is an error. Otherwise the scene renders with default
        values in place of the missing textures, and one WARNING line on the
        "vkpbr.scene.textures" logger says how many are missing (never one per texture).
    allow_outside_paths : read files the scene names outside its folder tree too (the folder
        of `path` and its subfolders, symlinks and `..` resolved). Off by default: an outside
        buffer or mesh file is a SceneError, an outside texture is reported and replaced like
        a missing one. Only regular files are read either way (docs/security.md).
    root : the folder tree referenced files must lie in, default the folder of `path` (the
        bake cache passes the source scene's folder for its cached .vkpbr files).
    variant : a glTF KHR_materials_variants variant name, whose materials replace the
        primitives' (None: the file's defaults). Only glTF files have variants: another
        format with a variant is a SceneError, as is a name the file does not define.

    Returns
    -------
    Scene in which every Mesh has normals (N, 3) (flat ones generated where the file had
    none) and C-contiguous float32 attributes and uint32 indices.

    Raises
    ------
    SceneError : missing file, a directory, an unknown suffix (or one that needs trimesh when
        it is not installed: the message gives the install line), a file with no triangles,
        missing texture files with `strict` (one line: the file, how many, the first one), or
        anything the format loader rejects (BakeFormatError for a bad .vkpbr), a buffer or
        material library outside the scene's folder tree (ResourceRefused), or an OSError
        while reading (the message names `path` and the file involved).
    """
    path = Path(path)
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise SceneError(path, "no such file") from None
    except (OSError, ValueError) as exc:
        raise SceneError(path, f"cannot read: {getattr(exc, 'strerror', None) or exc}") from None
    if stat.S_ISDIR(mode):
        raise SceneError(path, "is a directory, not a scene file")
    if not stat.S_ISREG(mode):
        raise SceneError(path, "is not a regular file (a FIFO or device?); vkpbr reads only "
                               "regular files")
    load = _loader(path.suffix.lower()) or _fallback(path)
    policy = ResourcePolicy(path, allow_outside=allow_outside_paths,
                            root=Path(root) if root is not None else None)
    if variant is not None and load.__name__ != "load_gltf":
        raise SceneError(path, f"material variant {variant!r}: only glTF files have variants "
                               "(KHR_materials_variants)")
    try:
        scene = load(path, policy=policy, **({} if variant is None else {"variant": variant}))
    except OSError as exc:
        # Anything an OS call reports while reading the scene or the files it names: the
        # user's scene file first, then the file involved and the OS's reason.
        what = exc.filename if exc.filename not in (None, os.fspath(path)) else None
        raise SceneError(path, f"cannot read{f' {what}' if what else ''}: "
                               f"{exc.strerror or exc}; check the file and its permissions") from exc
    except (KeyError, TypeError, ValueError, IndexError, AttributeError, OverflowError) as exc:
        # A reader met a structure it does not expect (hostile or broken input): one line
        # naming the file, never a traceback. Readers raise SceneError for what they check.
        what = f"missing {exc}" if isinstance(exc, KeyError) else str(exc) or type(exc).__name__
        raise SceneError(path, f"malformed file: {what}") from None
    try:
        scene.meshes = [normalize_mesh_arrays(ensure_normals(m)) for m in scene.meshes]
    except (TypeError, ValueError, IndexError, AttributeError) as exc:
        raise SceneError(path, f"malformed mesh arrays ({exc})") from None
    validate_scene(scene, path)  # every field of the Scene, whatever the format
    check_texture_files(scene, path, strict=strict)
    if scene.triangle_count == 0:
        raise SceneError(path, "contains no triangles to render")
    return apply_presets(scene)
