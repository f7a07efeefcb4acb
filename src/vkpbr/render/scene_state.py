"""The scene state on the GPU: each frame slot's copy of the draws' matrices.

`SceneState` (vkpbr.scene.state) says where every draw is; `GpuSceneState` keeps one copy
of its Instances records (model + normal matrix a draw, layouts.STORAGE) per frame slot, in
host-visible memory (device-local where the GPU has such memory: the frames read it every
vertex and triangle). A frame writes its slot's copy when the state changed since the slot
last held it, after the slot's fence (frames in flight keep reading their own), so moving
a node costs one copy of D x 128 bytes and re-records nothing: the recordings name the
slot's region, never the matrices. The state's version also keys what follows the scene:
the bounds (LiveBounds), the blended draws' centres and the shadow maps' casters.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.device import Device
from vkpbr.render.deform import DeformLayout
from vkpbr.render.frames import Bounds
from vkpbr.scene.state import SceneState
from vkpbr.scene.types import Scene

__all__ = ["GpuSceneState", "LiveBounds", "scene_state"]

RECORD_BYTES = 2 * 64  # model + normal matrix


def scene_state(scene: Scene, draws: list[Any]) -> SceneState:
    """The state of `scene` whose draw records (render/gpu_scene.py) are `draws`."""
    tree = scene.node_tree()
    nodes = scene.nodes
    draw_tree = np.array([nodes[d.node].tree for d in draws], np.int64)
    local = np.tile(np.eye(4), (len(draws), 1, 1))
    for i, d in enumerate(draws):  # once, at set-up: EXT_mesh_gpu_instancing's matrices
        inst = nodes[d.node].instances
        if d.instance >= 0 and inst is not None:
            local[i] = inst[d.instance]
    boxes = np.zeros((len(draws), 2, 3))
    for i, d in enumerate(draws):
        p = scene.meshes[d.mesh].positions
        if len(p):
            boxes[i] = p.min(axis=0), p.max(axis=0)
    rest = np.array([d.model for d in draws], np.float64).reshape(-1, 4, 4)
    state = SceneState(tree, draw_tree, local, boxes, rest, np.array([d.skinned for d in draws], bool))
    state.scene = scene
    return state


def with_times(state: SceneState, cameras: Iterable[Any], times: Iterable[float] | None,
               animation: Any) -> Iterator[Any]:
    """`cameras`, each taken after posing `state` at its time (render_many's per-frame
    times: each frame slot copies the state when its frame is drawn); `times` None: as is."""
    if times is None:
        yield from cameras
        return
    for camera, t in zip(cameras, times, strict=True):
        state.set_time(t, animation)
        yield camera


class GpuSceneState:
    """`state`'s Instances records, a copy per frame slot (`count` of them), and where the
    scene has skins or morph targets (`deform`: render/deform.py's DeformLayout) the deform
    step's joint matrices and weights after them."""

    def __init__(self, device: Device, state: SceneState, count: int, scene: Scene | None = None,
                 deform: DeformLayout | None = None) -> None:
        self.state, self.scene, self.deform = state, scene, deform
        align = int(device.limits.minStorageBufferOffsetAlignment)
        self.size = max(len(state.draw_tree), 1) * RECORD_BYTES
        self.deform_at = (self.size + align - 1) // align * align
        self.deform_size = 4 * max(deform.floats, 1) if deform is not None else 0
        total = self.deform_at + self.deform_size if deform is not None else self.size
        self.stride = (total + align - 1) // align * align
        self.buffer = Buffer(device, self.stride * count, "storage", host_visible=True,
                             device_local=True, name="scene state")
        self._written = [-1] * count

    def region(self, slot: int) -> tuple[Buffer, int, int]:
        """(buffer, offset, size) of frame slot `slot`'s copy: what its sets bind."""
        return self.buffer, slot * self.stride, self.size

    def deform_region(self, slot: int) -> tuple[Buffer, int, int]:
        """(buffer, offset, size) of slot `slot`'s joint matrices and morph weights."""
        return self.buffer, slot * self.stride + self.deform_at, self.deform_size

    def write(self, slot: int) -> None:
        """Bring slot `slot`'s copy up to the state (after the slot's fence: its previous
        frame has finished reading it); nothing when it already holds this version."""
        version = self.state.version
        if self._written[slot] == version:
            return
        records = self.state.draw_matrices()
        if records.size:
            self.buffer.array(np.float32, records.size, slot * self.stride)[:] = records.ravel()
        if self.deform is not None and self.scene is not None:
            values = self._deform_values()
            self.buffer.array(np.float32, values.size, slot * self.stride + self.deform_at)[:] = values
        self._written[slot] = version

    def _deform_values(self) -> np.ndarray:
        cached = getattr(self, "_values", None)
        if cached is None or cached[0] != self.state.version:
            assert self.deform is not None and self.scene is not None
            cached = (self.state.version,
                      self.deform.values(self.scene, self.state.world(), self.state.weights))
            self._values = cached
        return cached[1]

    def destroy(self) -> None:
        self.buffer.destroy()


class LiveBounds:
    """The scene's world bounds as `Bounds` gives them (corners, radius), following the
    state: remade when its version changed. `version` keys what depends on them."""

    def __init__(self, state: SceneState, initial: Bounds) -> None:
        self.state = state
        self._bounds, self._version = initial, 0

    @property
    def version(self) -> int:
        return self._current()[1]

    def _current(self) -> tuple[Bounds, int]:
        if self.state.version != self._version:
            lo, hi = self.state.bounds()
            fresh = Bounds.of(lo, hi)
            self._version = self.state.version
            if fresh != self._bounds:
                self._bounds = fresh
        return self._bounds, self._version

    @property
    def corners(self) -> tuple[tuple[float, float, float], ...]:
        return self._current()[0].corners

    @property
    def radius(self) -> float:
        return self._current()[0].radius
