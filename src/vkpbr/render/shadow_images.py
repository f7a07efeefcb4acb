"""Shadow map images a Renderer's scenes pass on to each other (render/parts.py DeviceParts).

A scene's `ShadowMaps` (render/shadows.py) takes its layered depth images from the device's
`ShadowImages` and gives them back when it lets them go (a new plan's sizes, or its scene's
end), so the next scene with the same map sizes draws into the same images instead of
allocating new ones. Only an exact match is taken (size, layers, cube, readable): a scene
gets the images a new Renderer would make, and draws every layer before reading it (its
ShadowMaps starts with nothing drawn). The images and their attachment views are the
device's (`Device.keeping`), outside a scene's count of device children; at most `KEEP`
unused ones are held (the oldest destroyed first).
"""

from __future__ import annotations

from vkpbr.gpu.device import Device
from vkpbr.gpu.layered import LayeredDepth

__all__ = ["ShadowImages", "KEEP"]

KEEP = 4  # unused images held: a scene's maps and cubes, and one size change of each


class ShadowImages:
    """The unused shadow images of one device (see the module's docstring)."""

    def __init__(self, device: Device) -> None:
        self.device = device
        self._free: list[tuple[tuple, LayeredDepth]] = []  # oldest first

    def take(self, size: int, layers: int, cube: bool, readable: bool, name: str) -> LayeredDepth:
        """An unused image of exactly this kind, else a new one (the device's)."""
        key = (int(size), int(layers), cube, readable, name)
        for i, (k, image) in enumerate(self._free):
            if k == key:
                del self._free[i]
                return image
        with self.device.keeping():
            image = LayeredDepth(self.device, size, layers, cube=cube, readable=readable,
                                 name=name)
        image.kept = True  # (its attachment views made later are the device's too)
        return image

    def give(self, image: LayeredDepth, readable: bool, name: str) -> None:
        """`image` (taken here) is unused again: held for the next taker of its kind."""
        self._free.append(((image.size, image.layers, image.cube, readable, name), image))
        while len(self._free) > KEEP:
            self._free.pop(0)[1].destroy()
