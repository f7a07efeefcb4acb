"""What `render` and `view` do alike with their parsed arguments: load the scene (through the
bake cache with --cache, strictly with --strict), and resolve --camera / --camera-index /
--fov and --light (repeatable) / --light-color / --light-intensity / --falloff against the scene.
"""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import logging
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from vkpbr.config import BATCH_VIEWS, default_cache_dir
from vkpbr.errors import UsageError

if TYPE_CHECKING:
    from vkpbr.scene.types import Camera, Light, Scene

# BATCH_VIEWS and default_cache_dir are vkpbr.config's, named here too for older imports.
__all__ = ["BATCH_VIEWS", "default_cache_dir", "load_scene_arg", "load_scene_ahead", "camera_from_args",
           "lights_from_args"]

log = logging.getLogger(__name__)


def load_scene_arg(args: argparse.Namespace) -> Scene | None:
    """The scene named on the command line (None: the built-in one), through the bake cache
    when --cache was given (a hit skips parsing and tangent generation), reading files
    outside the scene's folder only with --allow-outside-paths, with the glTF material
    variant of --variant."""
    if not args.scene:
        log.info("scene: the built-in PBR chart")
        return None
    from vkpbr.scene.loader import load_scene

    t0 = time.perf_counter()
    path = Path(args.scene)
    allow = bool(getattr(args, "allow_outside_paths", False))
    variant = getattr(args, "variant", None)
    root = None  # the folder tree files named by the scene must lie in: the scene's own
    if getattr(args, "cache", None) is not None and path.suffix.lower() != ".vkpbr":
        from vkpbr.bake.bake import cached_bake

        cache_dir = Path(args.cache) if args.cache else default_cache_dir()
        root = path.parent  # the cached bake's textures lie beside the source, not the cache
        path = cached_bake(path, cache_dir, allow_outside_paths=allow, variant=variant)
        variant = None  # baked in
        log.info("scene cache: %s (%.2f s)", path, time.perf_counter() - t0)
    if getattr(args, "strict", False):
        # `strict` is new in load_scene: fail clearly where this loader predates it.
        if "strict" not in inspect.signature(load_scene).parameters:
            raise UsageError("--strict: this version's scene loader has no strict mode")
        scene = load_scene(path, strict=True, allow_outside_paths=allow, root=root,
                           variant=variant)
    else:
        scene = load_scene(path, allow_outside_paths=allow, root=root, variant=variant)
    log.info("scene %s: %d meshes, %d triangles, %d images, loaded in %.2f s", path,
             len(scene.meshes), scene.triangle_count, len(scene.images), time.perf_counter() - t0)
    return scene


def load_scene_ahead(args: argparse.Namespace) -> Any:
    """`load_scene_arg(args)` on a thread, its images decoded there too (vkpbr.bake.ahead):
    a Future a Renderer takes as its scene, loading while the Renderer makes its device."""
    from vkpbr.bake.ahead import scene_ahead

    return scene_ahead(lambda: load_scene_arg(args))


def camera_from_args(args: argparse.Namespace, renderer: Any) -> Camera:
    """The start camera: --camera-index N (else the renderer's default camera for the
    scene), then --camera and --fov over it."""
    from vkpbr.render.camera import parse_camera, validate_camera

    scene = renderer.scene
    if args.camera_index is not None:
        # A file without cameras gets an automatic one (or a known scene's preset): it is
        # not the file's, so say what the file has.
        own = [c for c in scene.cameras if c.name != "auto" and not c.name.startswith("vkpbr:")]
        if not own:
            raise UsageError(f"--camera-index {args.camera_index}: the scene file has no "
                             "cameras (--camera-index N picks the file's camera N, counting "
                             "from 0); leave it out for the automatic camera, or give --camera")
        if not 0 <= args.camera_index < len(scene.cameras):
            raise UsageError(f"--camera-index {args.camera_index}: the scene file has "
                             f"{len(own)} camera(s): give 0..{len(own) - 1} (counting from 0)")
        camera = scene.cameras[args.camera_index]
    else:
        camera = renderer.default_camera()
    if args.camera:
        camera = parse_camera(args.camera, base=camera)
    if args.fov is not None:  # a calibrated camera's K gives way to the new field of view
        camera = dataclasses.replace(camera, yfov_deg=args.fov, pixel_intrinsics=None)
    validate_camera(camera)
    return camera


def lights_from_args(args: argparse.Namespace, renderer: Any, options: Any) -> tuple[Light, ...]:
    """The frame's lights: every --light (none given: the renderer's default for the scene
    and the lighting mode), then --light-color / --light-intensity / --falloff over each,
    resolved for `options`' lighting mode by `renderer.frame_lights`.
    (--light-color is already an (r, g, b) tuple: `vec3_arg` parsed it.)"""
    import math

    lights: list[Light] | None = None
    for parsed in args.light or ():  # each parsed by parsing.light_arg
        if isinstance(parsed, tuple):  # the course's bare X,Y,Z: move the default light there
            parsed = [dataclasses.replace(renderer.default_light(), position=parsed)]
        lights = (lights or []) + list(parsed)
    overrides: dict[str, Any] = {}
    if args.light_color is not None:
        overrides["color"] = args.light_color
    if args.light_intensity is not None:
        if not math.isfinite(args.light_intensity) or args.light_intensity < 0:
            raise UsageError("--light-intensity must be a finite number >= 0")
        overrides["intensity"] = args.light_intensity
    if args.falloff:
        overrides["falloff"] = args.falloff.replace("-", "_")
    if overrides:
        base = lights if lights is not None else renderer.frame_lights(options)
        lights = [dataclasses.replace(li, **overrides) for li in base]
    return renderer.frame_lights(options, lights)
