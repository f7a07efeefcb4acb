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

from vkpbr.errors import UsageError
from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.device import Device
from vkpbr.render.deform import DeformLayout
from vkpbr.render.frames import Bounds
from vkpbr.scene.state import SceneState
from vkpbr.scene.types import MeshBox, Scene, mesh_box

__all__ = ["GpuSceneState", "LiveBounds", "base_factors", "scene_state"]

RECORD_BYTES = 2 * 64  # model + normal matrix


def scene_state(scene: Scene, draws: list[Any], deform: DeformLayout | None = None,
                box: MeshBox | None = None) -> SceneState:
    """The state of `scene` whose draw records (render/gpu_scene.py) are `draws`; `deform`:
    the deformed records' layout (their models are the frames they are posed in); `box`:
    each mesh's (min, max) (GpuScene.mesh_box; None: computed)."""
    box = mesh_box(scene) if box is None else box
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
        if d.deformed and not d.unbounded:  # posed within its frame's unit sphere (deform.py)
            boxes[i, 0], boxes[i, 1] = -1.0, 1.0
        elif len(p):
            boxes[i] = box(d.mesh)
    rest = np.array([d.model for d in draws], np.float64).reshape(-1, 4, 4)
    state = SceneState(tree, draw_tree, local, boxes, rest, np.array([d.skinned for d in draws], bool))
    state.scene = scene
    state.deformed = np.array([d.deformed for d in draws], bool)  # (the motion table's)
    if deform is not None:
        at = {(d.node, d.instance): i for i, d in enumerate(draws)}
        state.attach_deform(deform, np.array([at[(r.node, r.instance)] for r in deform.records],
                                             np.int64))
    return state


def with_times(state: SceneState, cameras: Iterable[Any], times: Iterable[float] | None,
               animation: Any) -> Iterator[Any]:
    """`cameras`, each taken after posing `state` at its time (render_many's per-frame
    times: each frame slot copies the state when its frame is drawn); `times` None: as is.
    One-line UsageErrors for what is not a list, and for as many times as cameras."""
    for name, given in (("cameras", cameras), ("times", times)):
        if isinstance(given, (str, bytes)) or not isinstance(given, Iterable | None) or (
                isinstance(given, np.ndarray) and given.ndim == 0):
            raise UsageError(f"{name}: expected one a frame (a list), got {type(given).__name__}")
    if times is None:
        yield from cameras
        return
    if hasattr(cameras, "__len__") and hasattr(times, "__len__") and len(cameras) != len(times):
        raise UsageError(f"times: {len(times)} for {len(cameras)} cameras (one a camera)")
    left = iter(times)
    for camera in cameras:
        t = next(left, _NO_TIME)
        if t is _NO_TIME:
            raise UsageError("times: fewer than the cameras (one a camera)")
        state.set_time(t, animation)
        yield camera
    if next(left, _NO_TIME) is not _NO_TIME:
        raise UsageError("times: more than the cameras (one a camera)")


_NO_TIME = object()  # (with_times: the times ran out)


def base_factors(gpu_scene: Any, state: Any) -> np.ndarray:
    """(M, 3, 4) each material's factors as the renderer's state has them (the file's, with
    set_material's overrides): base colour; emissive, metallic; roughness (WorldFactors).
    The blocks' columns at once; only the overridden materials (a few) one by one."""
    blocks = gpu_scene.material_blocks
    table = np.array(blocks, dtype=blocks[0].dtype) if blocks else None
    out = np.zeros((len(blocks), 3, 4))
    if table is None:
        return out
    out[:, 0] = table["base_color_factor"]
    out[:, 1, :3] = table["emissive_factor"]
    out[:, 1, 3] = table["metallic_factor"]
    out[:, 2, 0] = table["roughness_factor"]
    rows = {"base_color_factor": (0, slice(0, 4)), "emissive_factor": (1, slice(0, 3)),
            "metallic_factor": (1, slice(3, 4)), "roughness_factor": (2, slice(0, 1))}
    for i, fields in state.materials.items():
        if i >= len(out):  # (not a block of the table)
            continue
        for field, value in fields.items():
            row, cols = rows[field]
            out[i, row, cols] = np.asarray(value, np.float64).reshape(-1)[:cols.stop - cols.start]
    return out


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
        draws = len(state.draw_tree)
        self.motion_at = (self.deform_at + self.deform_size + align - 1) // align * align
        self.motion_size = 4 * (20 + 20 * max(draws, 1))
        self.stride = (self.motion_at + self.motion_size + align - 1) // align * align
        # The motion table's constant part: which draws are deformed (their previous
        # positions are in PrevPositions, from the first posed vertex on).
        self._deformed = np.zeros((max(draws, 1), 4), np.uint32)
        if scene is not None and deform is not None:
            flags = getattr(state, "deformed", None)
            if flags is not None:
                self._deformed[:draws, 0] = flags
        self.first_posed = 0
        self._prev: tuple[Any, Any, int] | None = None  # previous frame's (VP, models, version)
        self.buffer = Buffer(device, self.stride * count, "storage", host_visible=True,
                             device_local=True, name="scene state")
        # Each slot's Instances records as a (D, 32) float32 view of the mapped memory.
        self._rows = [self.buffer.array(np.float32, 32 * draws, slot * self.stride).reshape(draws, 32)
                      for slot in range(count)]
        self._written = [-1] * count
        self._values: tuple[int, np.ndarray] | None = None  # (version, deform floats)
        self._materials_written = [0] * count  # the slots hold the file's factors at first
        self.gpu_scene: Any = None  # whose material blocks set_material overrides
        # (material version, the alpha factor of each masked or blended draw: 0 for others)
        self._alphas: tuple[int, np.ndarray | None] = (-1, None)
        self._draws_key: tuple[tuple, Any] = ((), None)  # (_draw_materials)
        for slot in range(count):  # every slot holds the rest pose from the start
            self.write(slot)

    def region(self, slot: int) -> tuple[Buffer, int, int]:
        """(buffer, offset, size) of frame slot `slot`'s copy: what its sets bind."""
        return self.buffer, slot * self.stride, self.size

    def motion_region(self, slot: int) -> tuple[Buffer, int, int]:
        """(buffer, offset, size) of slot `slot`'s motion table (layouts.STORAGE "Motion")."""
        return self.buffer, slot * self.stride + self.motion_at, self.motion_size

    def write_motion(self, slot: int, vp: tuple[float, ...], table: bool) -> None:
        """After each frame's view: remember its VP and draw matrices as the next frame's
        previous ones; with `table` (a frame with dataset outputs) first write the slot's
        motion table from the previous frame's (valid 0 on a renderer's first frame: motion
        0, as for a still scene)."""
        state = self.state
        if self._prev is not None and self._prev[2] == state.version and self._prev[0] is vp \
                and not table:
            return  # a still frame: the previous frame's are this one's
        models = state.draw_models().copy()  # (the state updates its own in place)
        if table:
            out = self.buffer.array(np.float32, self.motion_size // 4, slot * self.stride + self.motion_at)
            head = out[:20]
            head[:] = 0.0
            rows = out[20:].reshape(-1, 20)
            if self._prev is not None:
                head[:16] = self._prev[0]
                head.view(np.uint32)[16:18] = (1, self.first_posed)
                prev = self._prev[1]
                rows[:len(prev), :16] = np.swapaxes(prev, -1, -2).reshape(len(prev), 16)
            rows.view(np.uint32)[:, 16:] = self._deformed
        self._prev = (vp, models, state.version)

    def deform_region(self, slot: int) -> tuple[Buffer, int, int]:
        """(buffer, offset, size) of slot `slot`'s joint matrices and morph weights."""
        return self.buffer, slot * self.stride + self.deform_at, self.deform_size

    def write(self, slot: int, slots: Any = None) -> Any:
        """Bring slot `slot`'s copy up to the state (after the slot's fence: its previous
        frame has finished reading it); nothing when it already holds this version.
        Returns `slots[slot]` (the frame slot, for the caller) when `slots` is given."""
        if self._alphas[0] != self.state.material_version:
            self._touch_alpha_changes()
        version = self.state.version
        last = self._written[slot]
        if last == version:
            return None if slots is None else slots[slot]
        records = self.state.draw_matrices().reshape(-1, 32)
        rows = self._rows[slot]
        if len(records):  # the draws changed since the slot's copy; all when most did
            changed = np.flatnonzero(self.state.draw_versions > last) if last >= 0 else None
            if changed is None or 2 * len(changed) > len(records):
                rows[:] = records
            elif len(changed):
                rows[changed] = records[changed]
        if self._materials_written[slot] != self.state.material_version:
            self._write_materials(slot)
        if self.deform is not None:
            values = self._deform_values()
            self.buffer.array(np.float32, values.size, slot * self.stride + self.deform_at)[:] = values
        self._written[slot] = version
        return None if slots is None else slots[slot]

    def _touch_alpha_changes(self) -> None:
        """Masked and blended draws whose material's alpha factor changed (set_material, an
        animation pointer) are touched in the state (SceneState.touch_draws): the alpha
        cutoff shapes their shadows, so the maps' caches, which follow the draws' versions,
        must redraw them. Other factors only shade: they change no map. (Once per material
        change, vectorised: a dataset loop sets materials every frame.)"""
        gs = self.gpu_scene
        if gs is None:
            return
        material, cut = self._draw_materials(gs)
        alphas = np.where(cut, base_factors(gs, self.state)[material, 0, 3], 0.0)
        last = self._alphas[1]
        if last is not None and len(last) == len(alphas):
            changed = np.flatnonzero(alphas != last)
            if len(changed):
                self.state.touch_draws(changed)
        self._alphas = (self.state.material_version, alphas)

    def _draw_materials(self, gs: Any) -> tuple[np.ndarray, np.ndarray]:
        """Each draw's material and whether its alpha cuts (masked or blended), made again
        only when the draws or the materials grew (new instances, a node's own material)."""
        key = (len(gs.draws), len(gs.material_blocks))
        if self._draws_key[0] != key:
            self._draws_key = (key, (np.array([d.material for d in gs.draws], np.int64),
                                     np.array([d.alpha_mode in ("mask", "blend") for d in gs.draws], bool)))
        return self._draws_key[1]

    def _write_materials(self, slot: int) -> None:
        """Slot `slot`'s material blocks: the file's, with the state's overrides."""
        gs = self.gpu_scene
        if gs is None:
            return
        blocks = [b.copy() for b in gs.material_blocks]
        for i, fields in self.state.materials.items():
            for field, value in fields.items():
                blocks[i][field] = value if len(value) > 1 else value[0]
        gs.write_materials(slot, blocks)
        self._materials_written[slot] = self.state.material_version

    def _deform_values(self) -> np.ndarray:
        """The deform floats of the state's version (made once for all the slots)."""
        assert self.deform is not None
        if self._values is None or self._values[0] != self.state.version:
            self._values = (self.state.version,
                            self.deform.values(self.state.world(), self.state.weights))
        return self._values[1]

    def destroy(self) -> None:
        self.buffer.destroy()


class LiveBounds:
    """The scene's world bounds as `Bounds` gives them (corners, radius), following the
    state: remade when its version changed. `version` keys what depends on them."""

    def __init__(self, state: SceneState, initial: Bounds) -> None:
        self.state = state
        self._bounds, self._version = initial, 0
        # The bounds' radius as the scene was loaded: for a scale that must not follow the
        # state frame by frame (render/ao.py prepare_ao's automatic radius).
        self.rest_radius = initial.radius

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
