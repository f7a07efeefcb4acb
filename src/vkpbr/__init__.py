"""vkpbr: physically based real-time rendering in Python on Vulkan.

The public API, importable from the package itself::

    from vkpbr import Renderer, load_scene, Scene, Camera, Light, RenderOptions, show

    with Renderer(load_scene("scene.gltf")) as r:   # Renderer() renders the built-in scene
        rgba = r.render(size=(640, 480))            # (480, 640, 4) uint8, sRGB
    show(rgba)                                      # inline in a notebook (Jupyter)

The names are imported on first use (module `__getattr__`), so `import vkpbr` stays fast
and works on a machine without a Vulkan loader; only `Renderer` needs one.
"""

from __future__ import annotations

import importlib

# Not `from typing import TYPE_CHECKING`: typing alone would triple the import time. Type
# checkers treat a name TYPE_CHECKING as True wherever it comes from.
TYPE_CHECKING = False

__version__ = "0.1.0"

__all__ = ["Renderer", "load_scene", "Scene", "Camera", "Light", "RenderOptions", "show",
           "__version__"]

# public name -> module that defines it
_EXPORTS = {
    "Renderer": "vkpbr.render.renderer",
    "load_scene": "vkpbr.scene.loader",
    "Scene": "vkpbr.scene.types",
    "Camera": "vkpbr.scene.types",
    "Light": "vkpbr.scene.types",
    "RenderOptions": "vkpbr.render.options",
    "show": "vkpbr.display",
}

if TYPE_CHECKING:  # static checkers and IDEs see the real objects
    from vkpbr.display import show
    from vkpbr.render.options import RenderOptions
    from vkpbr.render.renderer import Renderer
    from vkpbr.scene.loader import load_scene
    from vkpbr.scene.types import Camera, Light, Scene


def __getattr__(name: str) -> object:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'vkpbr' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
