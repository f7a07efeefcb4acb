# trimesh interop: `load_scene`'s reader for the formats vkpbr does not parse itself (PLY, STL,
# OFF, ...), through trimesh as an optional extra (`pip install 'vkpbr[trimesh]'`), and
# `from_trimesh`, the module-level name of `Scene.from_trimesh`. NumPy only; trimesh is
# imported only when a trimesh object or file is met, never when vkpbr is imported.
#
# The conversion itself is trimesh_parts.py's (plain arrays, below types.py) and types.py's
# (`Scene.from_trimesh` assembles the dataclasses): this module sits above both, so no import
# points back at it.

from __future__ import annotations

import io
import warnings
from pathlib import Path
from typing import Any

from vkpbr.errors import SceneError, UsageError
from vkpbr.scene.resources import ResourcePolicy, ResourceRefused, read_resource
from vkpbr.scene.trimesh_parts import INSTALL_HINT
from vkpbr.scene.types import Scene

__all__ = ["INSTALL_HINT", "TRIMESH_SUFFIXES", "from_trimesh", "load_trimesh", "trimesh_formats"]

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


def from_trimesh(scene_or_mesh: Any, name: str | None = None) -> Scene:
    """A vkpbr Scene from a `trimesh.Trimesh` or `trimesh.Scene`: `Scene.from_trimesh`,
    which documents the conversion."""
    return Scene.from_trimesh(scene_or_mesh, name=name)


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
