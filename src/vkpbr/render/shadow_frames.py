"""The shadow maps' work per frame: which lights get maps, the maps' images, the matrices.

`ShadowFrames` keeps the plan of the frames' lights (render/shadows.py plan_shadows: remade
only when the lights or the option change), makes the maps' images hold it (new images:
the recorded command buffers name the old ones, so they are dropped), and writes each frame
slot's shadow matrices, skipping the maths when the slot's inputs repeat. Directional
lights' cascades follow a frame's camera; a batch's views share one map over the whole scene.

It also chooses who draws the maps (`choose_raster`: the raster units into the images, or
the compute kernels into the buffer the shading reads, render/shadow_raster.py): a switch
forgets which layers are drawn (neither side holds the other's), and the compute side's
buffers are fitted here, before the frame asks which layers are stale.
"""

from __future__ import annotations

import collections
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.render import layouts as L
from vkpbr.render.frames import FrameSlot
from vkpbr.render.options import RenderOptions
from vkpbr.render.recorder import FrameRecorder
from vkpbr.render.shadow_raster import wants_compute
from vkpbr.render.shadows import ShadowMaps, ShadowPlan, plan_shadows
from vkpbr.scene.types import Camera, Light

__all__ = ["ShadowFrames", "SETTLED_FRAMES", "MAX_SPLITS"]

# A caster that has not moved for this many frames counts as still again
# (ShadowFrames.split): its shadow joins the kept maps.
SETTLED_FRAMES = 120
# Sets of moved casters a renderer keeps maps apart for (each has its caster tables and
# descriptor sets on the GPU); past them its maps are drawn in one pass, as before: a scene
# whose moving casters keep changing gains little from the split and must not grow.
MAX_SPLITS = 16
# On a CPU "auto" draws the maps by the raster units (lavapipe rasterises a whole map ~5x
# faster than it runs the compute kernels), but by the kernels while the casters that move
# hold under this share of the casters' triangles: their maps are then the kept maps' copy
# and the moving casters alone (an animated model in a still scene).
CPU_COMPUTE_SHARE = 0.1


class ShadowFrames:
    """The per-frame side of `maps` for a scene of `bounds`, whose recordings `recorder` keeps."""

    def __init__(self, maps: ShadowMaps, bounds: Any, recorder: FrameRecorder,
                 state: Any = None, casters: np.ndarray | None = None, paths: Any = None) -> None:
        # bounds: Bounds or render/scene_state.py's LiveBounds; state (vkpbr.scene.state) and
        # `casters` (a bool per draw): a map is redrawn when one of its casters moved.
        self.maps, self.bounds, self.recorder = maps, bounds, recorder
        self.state, self.casters = state, casters
        self.paths = paths  # render/path_choice.py FramePaths: shadow_raster auto follows its choice
        self._plan: tuple[tuple, ShadowPlan] = ((), ShadowPlan())
        self._rows: dict[int, tuple[tuple, np.ndarray | None]] = {}  # by slot: (key, rows)
        # `_moving`'s answer for a state version, a settled version and the casters; `split`'s
        # casters that moved (their bytes and the casters: a new set is a new id), its id.
        self._moving_mask: tuple[tuple, np.ndarray | None] = ((), None)
        self._moved: tuple[tuple, int, np.ndarray | None] = ((), 0, None)
        self._versions: collections.deque[int] = collections.deque(maxlen=SETTLED_FRAMES)
        self._triangles: tuple[Any, np.ndarray] = (None, np.zeros(0, np.int64))  # per draw

    def plan(self, lights: tuple[Light, ...], options: RenderOptions) -> ShadowPlan:
        """Which of the frame's lights get shadow maps (none in course mode or with shadows
        off); remade only when the lights or the option change."""
        enabled = options.shadows and options.lighting == L.Lighting.PBR
        key = (lights, enabled)
        if key != self._plan[0]:
            self._plan = (key, plan_shadows(lights, enabled, self.maps.cubes_supported))
        return self._plan[1]

    def prepare(self, lights: tuple[Light, ...], options: RenderOptions) -> ShadowPlan:
        """The frame's plan, with maps of `options`' resolution that hold it."""
        plan = self.plan(lights, options)
        self.ensure(plan, options)
        self.choose_raster(options)
        # The compute kernels' buffers for these images, before the frame asks which layers
        # are stale: new ones forget them all (nothing is drawn in a new buffer).
        if self.maps.compute and plan.entries and self.maps.compute_raster(
                self.recorder.gpu_scene).fit():
            self.recorder.free()  # (set 3 rebound: the recordings that bound it are stale)
        return plan

    def choose_raster(self, options: RenderOptions) -> None:
        """Draw the maps by compute shaders or the raster units, as `options` say
        (shadow_raster.wants_compute); a change drops the recordings made the other way."""
        choice = getattr(self.paths, "choice", None)
        if options.shadow_raster.name.lower() == "auto" and self.maps.device.info.kind == "cpu":
            compute = self._few_moving()
        else:
            compute = wants_compute(options.shadow_raster, self.maps.device,
                                    None if choice is None else choice.compute_raster)
        limit = int(self.maps.device.limits.maxStorageBufferRange)
        if compute and self.maps.compute_bytes() > limit:  # every layer in one binding
            if options.shadow_raster.name.lower() == "compute":
                raise UsageError(f"--shadow-raster compute: the shadow maps' "
                                 f"{self.maps.compute_bytes() >> 20} MiB of depths exceed one "
                                 f"storage binding here ({limit >> 20} MiB); lower "
                                 "--shadow-resolution or use --shadow-raster hardware")
            compute = False
        if compute != self.maps.compute:
            self.maps.device.wait_idle()  # recordings in flight are freed
            self.maps.compute = compute
            self.recorder.free()
            self.maps.forget()  # the other side's layers hold none of what was drawn
            self._rows.clear()  # ShadowData's header says which side the shading reads

    def _moving(self) -> np.ndarray | None:
        """The casters that moved in the last SETTLED_FRAMES frames (a bool per draw) where
        others did not; None where none moved or all did (or there is no state)."""
        if self.state is None or self.casters is None or not self.state.version:
            return None
        settled = self._versions[0] if len(self._versions) == self._versions.maxlen else 0
        key = (self.state.version, settled, id(self.casters), len(self.casters))
        if self._moving_mask[0] != key:
            moving = self.casters & (self.state.draw_versions > settled)  # (a draw's last change)
            some = 0 < int(moving.sum()) < int(self.casters.sum())
            self._moving_mask = (key, moving if some else None)
        return self._moving_mask[1]

    def _few_moving(self) -> bool:
        """Whether some casters moved lately and others did not (`_moving`), and the moving
        ones hold under CPU_COMPUTE_SHARE of the casters' triangles."""
        moving = self._moving()
        if moving is None:
            return False
        if self._triangles[0] is not self.casters:
            draws = self.recorder.gpu_scene.draws
            self._triangles = (self.casters, np.array([d.index_count // 3 for d in draws], np.int64))
        triangles = self._triangles[1]
        return int(triangles[moving].sum()) < CPU_COMPUTE_SHARE * int(triangles[self.casters].sum())

    def ensure(self, plan: ShadowPlan, options: RenderOptions | None = None) -> None:
        """Maps that hold `plan` (of `options`' resolution, where given)."""
        if options is not None and options.shadow_resolution != self.maps.resolution:
            self.maps.set_resolution(options.shadow_resolution)
        if self.maps.ensure(plan):  # new images: the recorded buffers name the old ones
            self.recorder.free()
            self._rows.clear()

    def forget(self) -> None:
        """Write every slot's ShadowData whole on its next frame and redraw every map (what
        a renderer new to these frames would do; tests compare the two)."""
        self._rows.clear()
        self.maps.forget()

    def stale(self, slot: int, plan: ShadowPlan, alpha_mask: bool) -> tuple[range, ...]:
        """ShadowMaps.stale for frame `slot`, with the version of the state that last moved a
        caster: a map whose matrices and casters are unchanged is kept."""
        moved = 0 if self.state is None else self.state.changed_since(self.casters)
        return self.maps.stale(slot, plan, alpha_mask, moved, self.split(moved))

    def split(self, moved: int) -> tuple[int, np.ndarray] | None:
        """The casters that moved in the last SETTLED_FRAMES frames, as (an id, a bool per
        draw), where compute kernels draw the maps and other casters did not move: the maps
        keep those apart (ShadowMaps.stale), so that an animated character in a still scene
        redraws its own shadow, not the scene's. None where none moved or all did (one
        pass, as before), and past MAX_SPLITS sets. A new set of moved casters is a new id
        (the kept maps then hold other casters: they are redrawn)."""
        if self.state is not None:
            self._versions.append(self.state.version)  # (a frame's: SETTLED_FRAMES ago first)
        if not moved or not self.maps.compute or self._moved[1] >= MAX_SPLITS:
            return None
        moving = self._moving()
        if moving is None:
            return None
        which = (moving.tobytes(), id(self.casters), len(self.casters))  # (new casters: a new set)
        if which != self._moved[0]:
            self._moved = (which, self._moved[1] + 1, moving)
        return self._moved[1], self._moved[2]

    def write(self, slot: FrameSlot, plan: ShadowPlan, lights: tuple[Light, ...],
              camera: Camera, size: tuple[int, int]) -> np.ndarray | None:
        """The slot's shadow matrices for this frame (skipped when its inputs repeat) and the
        lights' LightRecord.shadow rows; None without shadow maps. The cascades take the
        frame's planes from its view record: write_frame_view comes first."""
        if not plan.entries:
            return None
        sm = self.maps
        c = camera  # mutable: its values are the key
        # Only directional lights' cascades follow the camera: spot and point lights' maps
        # are the same for every view, so a moving camera does not remake them.
        view = ((c.eye, c.target, c.up, c.yfov_deg, c.znear, c.zfar, c.pixel_intrinsics, tuple(size))
                if plan.follows_camera else None)
        key = (view, plan, lights, sm.resolution, sm.compute, getattr(self.bounds, "version", 0))
        last = self._rows.get(slot.index)
        if last is not None and last[0] == key:
            return last[1]
        if view is not None and last is not None and type(last[0][0]) is tuple and last[0][1:] == key[1:]:
            # Only the view changed since `write` filled the slot for a frame (a moving
            # camera; not write_scene's or write_worlds' keys, whose first item is a str): the
            # cascades alone follow it; the lights' rows and the rest of ShadowData stay.
            sm.write_cascades(slot.index, plan, lights, camera, size, slot.znear, slot.zfar,
                              self.bounds.corners[0], self.bounds.corners[-1])
            self._rows[slot.index] = (key, last[1])
            return last[1]
        rows = sm.write(slot.index, plan, lights, camera, size, slot.znear, slot.zfar,
                        self.bounds.corners[0], self.bounds.corners[-1])
        self._rows[slot.index] = (key, rows)
        return rows

    def write_worlds(self, slot: FrameSlot, plan: ShadowPlan, lights: tuple[Light, ...],
                     resolution: int, layout: tuple[int, int]) -> np.ndarray | None:
        """A batch of worlds' own maps in `slot` (render/world_shadows.py: `plan` its world
        plan, maps of `resolution`, `layout` (texels a world, its cubes' start)): the
        matrices every world's maps share (directional lights over the whole scene) and the
        lights' LightRecord.shadow rows; None without maps."""
        if not plan.entries:
            return None
        key = ("worlds", plan, lights, resolution, layout, getattr(self.bounds, "version", 0))
        last = self._rows.get(slot.index)
        if last is not None and last[0] == key:
            return last[1]
        rows = self.maps.write(slot.index, plan, lights, None, (1, 1), 0.0, 0.0,
                               self.bounds.corners[0], self.bounds.corners[-1], resolution, layout)
        self._rows[slot.index] = (key, rows)
        return rows

    def write_scene(self, slot: FrameSlot, plan: ShadowPlan, lights: tuple[Light, ...],
                    options: RenderOptions | None = None) -> np.ndarray | None:
        """A batch's shadow maps in `slot`: the camera-independent fits (directional lights
        over the whole scene) and the lights' LightRecord.shadow rows; None without maps.
        `options`: first make maps of their resolution that hold `plan` (`ensure`)."""
        if options is not None:
            self.ensure(plan, options)
        if not plan.entries:
            return None
        # Skipped when the slot holds these already (a loop of batches: the fits are the
        # scene's, the same every step); a frame's cascades in between change the key.
        key = ("scene", plan, lights, self.maps.resolution, self.maps.compute,
               getattr(self.bounds, "version", 0))
        last = self._rows.get(slot.index)
        if last is not None and last[0] == key:
            return last[1]
        rows = self.maps.write(slot.index, plan, lights, None, (1, 1), 0.0, 0.0,
                               self.bounds.corners[0], self.bounds.corners[-1])
        self._rows[slot.index] = (key, rows)
        return rows
