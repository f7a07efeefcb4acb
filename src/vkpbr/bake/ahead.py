"""A scene loaded on a thread while the caller makes the Vulkan device (issue 32: file to first
frame).

`load_ahead(path)` returns at once a `SceneAhead`, a Future of the loaded Scene; hand it to
`Renderer(...)` (or `set_scene`) in place of the Scene. What overlaps:

- on the loading thread: the bake cache's look-up (`cache_dir`), the parse or the baked
  file's read, then the decode of the scene's images (Pillow on up to 16 threads);
- on the caller's: the Vulkan instance and device (the driver's work, 0.3-0.4 s on the H200;
  the binding releases the GIL in every call), then the geometry's upload while the decode
  finishes.

The decode ahead is the one `GpuScene` would make, made before the device is known, so it is
used only where the device could not change it (`decoded_for`): no KTX2 image (the device
decides BC7 or RGBA8) and no image larger than the device's largest 2D image (which downscales
it); otherwise the GPU scene decodes again, exactly as without the thread. Errors (a bad file,
a texture budget) are raised where the Scene is asked for, as `load_scene` raises them.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from concurrent.futures import Future
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import VkpbrError
from ..scene.types import Scene

__all__ = ["SceneAhead", "load_ahead", "scene_ahead", "may_hold_ktx2"]


class SceneAhead(Future):
    """A Future of a Scene being loaded on a thread, and of its images' RGBA8 (`decoded`)."""

    def __init__(self) -> None:
        super().__init__()
        self.decoded: Future | None = None  # list of (H, W, 4) uint8 | None, per image

    def decoded_for(self, max_size: int) -> list[np.ndarray | None] | None:
        """The images decoded ahead where a device whose largest 2D image is `max_size`
        decodes them the same (see the module's docstring), else None; handed over once (not
        kept here: Sponza's are 280 MB)."""
        if self.decoded is None:
            return None
        try:
            pixels, self.decoded = self.decoded.result(), None
        except VkpbrError:  # (the texture budget, say): decoded again for the device, which
            return None  # raises it again if the device's limits do not change it
        if pixels is None or any(p is not None and max(p.shape[:2]) > max_size for p in pixels):
            return None
        return pixels


def may_hold_ktx2(scene: Scene) -> bool:
    """Whether some image may be KTX2 (by its type, its file's name or its bytes): its BC7
    levels are the device's choice, made on upload, so nothing is decoded ahead."""
    from ..scene.gltf_codecs import KTX2_MAGIC

    return any((img.mime_type or "").lower() == "image/ktx2"
               or str(img.path or "").lower().endswith(".ktx2")
               or (img.data is not None and bytes(img.data[:12]) == KTX2_MAGIC)
               for img in scene.images)


def _decode(scene: Scene) -> list[np.ndarray | None] | None:
    from ..scene.textures import decode_images

    if not scene.images or all(img.pixels is not None for img in scene.images) or may_hold_ktx2(scene):
        return None  # nothing to decode, or the device decides how (BC7)
    return decode_images(scene)


def _load(path: Path, cache_dir: Path | None, kwargs: dict[str, Any]) -> Scene:
    from ..scene.loader import load_scene

    if cache_dir is not None and path.suffix.lower() != ".vkpbr":
        from .bake import cached_bake

        allow = bool(kwargs.get("allow_outside_paths", False))
        baked = cached_bake(path, cache_dir, allow_outside_paths=allow,
                            variant=kwargs.pop("variant", None))
        return load_scene(baked, root=path.parent, **kwargs)  # textures beside the source
    return load_scene(path, **kwargs)


def load_ahead(path: str | os.PathLike[str], cache_dir: str | os.PathLike[str] | None = None,
               decode: bool = True, **load_kwargs: Any) -> SceneAhead:
    """Start loading `path` (through the bake cache in `cache_dir` when given) on a thread, and
    then, with `decode`, decoding its images; `load_kwargs` go to `load_scene` (strict,
    allow_outside_paths, variant). Returns the SceneAhead at once."""
    cache = None if cache_dir is None else Path(cache_dir)
    return scene_ahead(lambda: _load(Path(path), cache, dict(load_kwargs)), decode)


def scene_ahead(load: Callable[[], Scene | None], decode: bool = True) -> SceneAhead:
    """`load()` run on a thread (then, with `decode`, its scene's images decoded there): the
    SceneAhead of its result, at once (a None result: the built-in scene, nothing decoded)."""
    ahead = SceneAhead()
    ahead.set_running_or_notify_cancel()
    if decode:
        ahead.decoded = Future()
        ahead.decoded.set_running_or_notify_cancel()

    def work() -> None:
        try:
            scene = load()
        except BaseException as exc:  # noqa: BLE001 - handed to whoever asks for the scene
            ahead.set_exception(exc)
            if ahead.decoded is not None:
                ahead.decoded.set_result(None)
            return
        ahead.set_result(scene)
        if ahead.decoded is not None:
            try:
                ahead.decoded.set_result(None if scene is None else _decode(scene))
            except BaseException as exc:  # noqa: BLE001 - raised where the pixels are used
                ahead.decoded.set_exception(exc)

    threading.Thread(target=work, name="vkpbr-load-ahead", daemon=True).start()
    return ahead
