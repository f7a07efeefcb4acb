"""The painter's order of a scene's blended draws: farthest first from the eye.

Blended draws are drawn after the opaque scene in the order of their centres' distance from
the eye; an order is part of what a recording depends on (render/steps.py FrameSpec), so a
frame that keeps the order re-records nothing. A batch orders every view at once.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["BlendOrder"]


class BlendOrder:
    """The blended draws of `draws` (render/gpu_scene.py's, each with `alpha_mode` and
    `center`), in the order the frame path draws them."""

    def __init__(self, draws: Sequence[Any], state: Any = None) -> None:
        # `state` (vkpbr.scene.state.SceneState): the centres follow it; None: as loaded.
        self.blended = np.array([d.alpha_mode == "blend" for d in draws], bool)
        self.state = state
        blend = [d.center for d in draws if d.alpha_mode == "blend"]
        self._centers = np.array(blend, dtype=np.float64).reshape(-1, 3)
        self._version = 0

    def __len__(self) -> int:
        return len(self._centers)

    @property
    def centers(self) -> np.ndarray:
        """(blended draws, 3) world centres, as the scene state places them now."""
        if self.state is not None and self.state.version != self._version and len(self._centers):
            self._centers = self.state.draw_centers()[self.blended]
            self._version = self.state.version
        return self._centers

    def order(self, eye: Any) -> tuple[int, ...]:
        """Indices into the blended draws, farthest first from `eye` (painter's order)."""
        if len(self.centers) < 2:  # no order to find: the frame path's usual case
            return tuple(range(len(self.centers)))
        return tuple(self.orders(np.asarray(eye, dtype=np.float64)[None])[0].tolist())

    def orders(self, eyes: np.ndarray) -> np.ndarray:
        """For each of (B, 3) eyes, indices into the blended draws farthest first (painter's
        order): (B, blended draws) int. `order` is one row of it."""
        centers = self.centers
        if len(centers) < 2:
            return np.broadcast_to(np.arange(len(centers)), (len(eyes), len(centers)))
        d = np.sum((centers[None, :, :] - eyes[:, None, :]) ** 2, axis=2)
        return np.argsort(-d, axis=1, kind="stable")
