"""A text overlay drawn over frames: the viewer's HUD as an optional last pass.

The GPU half (gpu/text_overlay.py QuadOverlay) keeps one vertex slot per frame of the ring;
this keeps the current quads and which frame slots hold them, so new text is copied into a
slot only when that frame comes round (its previous use has finished) and only once per
change: a frame with unchanged text copies nothing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vkpbr.gpu.commands import Commands
from vkpbr.gpu.device import Device
from vkpbr.gpu.text_overlay import VERTEX_FLOATS, QuadOverlay
from vkpbr.render.codegen import SPV_DIR

__all__ = ["TextOverlay", "VERTEX_FLOATS"]


class TextOverlay:
    """Quads of (x, y, u, v, r, g, b, a) vertices over `atlas`, for frames of `target`."""

    def __init__(self, device: Device, atlas: np.ndarray, target: Any, frames: int) -> None:
        self.quads = QuadOverlay(device, atlas, target.color_format, target.depth_format, SPV_DIR)
        self.quads.ensure_slots(frames)
        self._vertices = np.zeros((0, VERTEX_FLOATS), dtype=np.float32)
        self._version = 0
        self._written: dict[int, int] = {}

    def set_vertices(self, vertices: np.ndarray) -> None:
        """Show these (N, 8) float32 vertices from the next frames on."""
        self._vertices = vertices
        self._version += 1

    def prepare(self, frame_index: int) -> None:
        """Copy the current quads into frame `frame_index`'s slot if it holds older ones."""
        if self._written.get(frame_index) != self._version:
            self.quads.write(frame_index, self._vertices)
            self._written[frame_index] = self._version

    def record(self, cmd: Commands, frame_index: int, extent: tuple[int, int]) -> None:
        self.quads.record(cmd, frame_index, extent)

    def destroy(self) -> None:
        self.quads.destroy()
