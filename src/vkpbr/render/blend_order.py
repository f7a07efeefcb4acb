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
        return _farthest_first(centers[None, :, :], eyes)

    def world_orders(self, eyes: np.ndarray, records: np.ndarray, world_of_view: np.ndarray
                     ) -> np.ndarray:
        """`orders` for views that each see their own world: view b's blended draws placed
        by world `world_of_view[b]`'s draw records (`records`: (W * D, 2, 4, 4) float32,
        each world's D records as GLSL's column-major pairs, render/worlds.py), as `render`
        of that world alone orders them."""
        if len(self.centers) < 2 or self.state is None:
            return self.orders(eyes)
        draws = len(self.blended)
        # (transposed models: m[..., 3, :3] is the translation, m[..., :3, :3] M's transpose)
        m = records.reshape(-1, draws, 2, 4, 4)[:, self.blended, 0]
        local = self.state.mesh_boxes[: draws][self.blended].mean(axis=1)
        centers = np.einsum("wkji,kj->wki", m[..., :3, :3], local) + m[..., 3, :3]
        return _farthest_first(centers[world_of_view], eyes)


def _farthest_first(centers: np.ndarray, eyes: np.ndarray) -> np.ndarray:
    """(B, K) indices into the K centres of each view ((1 or B, K, 3)), farthest first from
    its eye ((B, 3)); equal distances keep the draws' order."""
    d = np.sum((centers - eyes[:, None, :]) ** 2, axis=2)
    return np.argsort(-d, axis=1, kind="stable")
