"""Each world's own shadow maps in a batch of worlds (docs/batch.md "Worlds", issue 32).

A batch of worlds whose poses move a shadow caster draws, once per WORLD (not per view),
every shadowed light's maps from that world's draw records: spot lights one map, point
lights a cube's six faces, directional lights one scene-wide map (the batch's rule for
views, made per world: its fit is the scene's bounds as the renderer's state has them).
All worlds' maps are drawn by shadow_raster.comp in the same dispatches (a dispatch's z is
(world, layer): render/shadow_raster.py world_steps), into one buffer of every world's
texels, which the shading reads by hand (shaders/shadow_sampling.glsl compare_2d /
compare_cube) at its view's world (views[].shadow_base = 1 + world). The compute
rasteriser draws them on every device (the raster units' passes are not used for worlds:
a layered image could hold at most maxImageArrayLayers, 2,048 on NVIDIA, of the worlds'
layers).

Memory: W x (2D layers x r^2 + 6 x cubes x (r / 2)^2) x 4 bytes, r =
RenderOptions.world_shadow_resolution (default 256): a point light 384 KiB a world (375
MiB per 1,000 worlds), a spot or directional light 256 KiB (250 MiB per 1,000), all of it in
one storage binding (at most the device's maxStorageBufferRange and the free device memory:
a one-line error past either, before any GPU work).

Worlds that move no caster (their slot nodes carry no shadow-casting draw; worlds that only
set materials or lights) keep the renderer's state's maps, shared: nothing differs.

Casters the worlds do not move (a table, the floor: draws under no world slot, whose record
is the state's in every world) are drawn once into a kept map of one world's layout
(`WorldShadows.prepare_kept`, a submission of its own, again only when the light, the
state's poses of those casters, the alpha mask or the set of moved casters change), which
every world's maps copy (the move kernel's CLIP_COPY rows: ShadowMaps.write_world_rows)
before the casters its poses move are drawn over it: per world only its own casters' texels,
not the floor's under every world. Bit for bit the maps of one pass over every caster
(tests/gpu/test_world_shadows.py); `WorldShadows.keep_still = False` draws them that way.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.graph import record_steps
from vkpbr.render.passes import classify
from vkpbr.render.shadow_raster import WorldJob, big_list_bytes
from vkpbr.render.shadows import ShadowEntry, ShadowPlan

__all__ = ["WorldShadows", "world_plan", "world_layout", "casters"]


def world_plan(plan: ShadowPlan) -> ShadowPlan:
    """`plan` with one layer a directional light (its scene-wide map), the 2D layers and
    cubes packed in order: what a world's maps hold."""
    entries, layers, cubes = [], 0, 0
    for e in plan.entries:
        if e.kind == "point":
            entries.append(ShadowEntry(e.light, e.kind, cubes, 6))
            cubes += 1
        else:
            entries.append(ShadowEntry(e.light, e.kind, layers, 1))
            layers += 1
    return ShadowPlan(tuple(entries), layers, cubes, plan.dropped)


def world_layout(plan: ShadowPlan, resolution: int) -> tuple[int, int, int]:
    """(texels a world, where its cubes start, cube face size) for a world plan."""
    cube = max(resolution // 2, 16)
    base = plan.layers * resolution * resolution
    return base + 6 * plan.cubes * cube * cube, base, cube


def casters(draws: Any) -> np.ndarray:
    """(D,) bool: the draws that cast shadows (shadow_raster's caster table's)."""
    return np.array([getattr(d, "casts_shadows", True) and d.index_count >= 3 for d in draws],
                    bool)


def _fits(need: int, limit: int, what: str, worlds: int, stride: int, resolution: int) -> None:
    if need > limit:
        raise UsageError(
            f"world shadows: {worlds:,} worlds x {4 * stride >> 10} KiB of shadow maps "
            f"({need >> 20} MiB) exceed {what} ({limit >> 20} MiB); lower "
            f"world_shadow_resolution ({resolution}), render fewer worlds a call or give "
            "shadows=False")


class WorldShadows:
    """The buffers of a batch of worlds' maps (grown, never shrunk), bound as set 3's
    ShadowWorldDepths of the renderer's ShadowMaps `maps`."""

    def __init__(self, maps: Any) -> None:
        self.maps, self.device = maps, maps.device
        self.depths: Buffer | None = None
        self.big: Buffer | None = None
        self.bytes = 0
        self.big_capacity = 0
        self.generation = 0  # bumped when the buffers are remade (the raster's sets name them)
        self._casts: tuple[Any, np.ndarray] | None = None  # (draws, casters(draws))
        self.keep_still = True  # the casters the worlds do not move drawn once (the module's docstring)
        self.kept: Buffer | None = None  # their map (one world's layout)
        self._kept_key: tuple | None = None  # what `kept` holds

    def _caster_mask(self, draws: Any) -> np.ndarray:
        if self._casts is None or self._casts[0] is not draws:
            self._casts = (draws, casters(draws))
        return self._casts[1]

    def moved_casters(self, call: Any, draws: Any) -> np.ndarray | None:
        """The shadow casters a call's worlds (render/worlds.py WorldCall) move (a bool per
        draw), None where it is not known which (every caster is then each world's own).
        None of them: the state's maps, shared, are every world's (no shadow can change)."""
        moved = call.gpu.slots.anchor >= 0 if call.gpu is not None else call.moved
        if moved is None:
            return None
        casts = self._caster_mask(draws)
        out = np.zeros(len(casts), bool)
        n = min(len(casts), len(moved))
        out[:n] = np.asarray(moved, bool)[:n] & casts[:n]
        return out

    def with_kept(self, job: WorldJob, draws: Any, moved: np.ndarray | None) -> WorldJob:
        """`job` with the kept map where some casters are the worlds' own and others not."""
        casts = self._caster_mask(draws)
        if not self.keep_still or moved is None or not moved.any() or not (casts & ~moved).any():
            return job
        if self.kept is None or self.kept.size < 4 * job.stride:
            if self.kept is not None:
                self.device.wait_idle()
                self.kept.destroy()
            self.kept = Buffer(self.device, 4 * job.stride, "storage|transfer_dst",
                               name="world shadow kept map")
            self._kept_key = None
        return dataclasses.replace(job, kept=self.kept)

    def prepare_kept(self, parts: Any, set0: Any, frame_index: int, plan: ShadowPlan, job: WorldJob,
                     moved: np.ndarray, alpha_mask: bool) -> None:
        """The slot's rows that copy the kept map into every world's layers, and the kept
        map drawn (a submission of its own, waited for) where what it holds changed: the
        slot's matrices (written before), the casters' state, the alpha mask, the moved set."""
        maps = parts.shadow_frames.maps
        maps.write_world_rows(frame_index, plan, job.map_size, job.cube_size)
        still = self._caster_mask(parts.gpu_scene.draws) & ~moved
        key = (maps.matrices_bytes(frame_index), alpha_mask, still.tobytes(),
               parts.state.changed_since(still) if parts.state is not None else 0,
               id(self.kept), job.stride, job.map_size)
        if key == self._kept_key:
            return
        gs = parts.gpu_scene
        raster = maps.compute_raster(gs)
        classes = [classify(d.alpha_mode, d.double_sided, alpha_mask) for d in gs.draws]
        resources: dict[str, Any] = {}
        steps = raster.world_kept_steps(frame_index, plan, job, classes,
                                        gs.slot_material_sets[frame_index], set0, resources, moved)
        with self.device.one_time_commands() as handle:
            record_steps(Commands(self.device, handle), steps, resources, (1, 1))
        self._kept_key = key

    def job(self, plan: ShadowPlan, resolution: int, worlds: int, draws: int) -> tuple[WorldJob, bool]:
        """The maps of `worlds` worlds (`plan`: world_plan's) and whether the buffers were
        (re)made: set 3 was rewritten, the recordings that named the old ones are stale."""
        stride, cube_base, cube = world_layout(plan, resolution)
        need = 4 * worlds * stride
        limit = int(self.device.limits.maxStorageBufferRange)
        _fits(need, limit, "one storage binding here", worlds, stride, resolution)
        made = need > self.bytes
        if made:
            free = self.device.memory_available()[0] + self.bytes  # (ours are given back first)
            _fits(need, free, "the free device memory", worlds, stride, resolution)
            limit = min(limit, free)
            self.device.wait_idle()
            self._free()
            self.bytes = max(need, min(2 * self.bytes, limit))
            self.depths = Buffer(self.device, self.bytes, "storage|transfer_dst|transfer_src",
                                 name="world shadow depths")
            # Bands of big triangles (96 bytes each: a band and its triangle's set-up), one
            # for every 512 texels (~5% of the maps' bytes); the rest are drawn by the
            # invocation that finds them
            self.big_capacity = max(1 << 16, self.bytes // 4 // 512)
            self.big = Buffer(self.device, big_list_bytes(self.big_capacity),
                              "storage|transfer_dst|indirect", name="world shadow big triangles")
            self.maps.bind_world_depths(self.depths)
            self.generation += 1
        assert self.depths is not None and self.big is not None
        return WorldJob(self.depths, self.big, self.big_capacity, worlds, draws, stride,
                        cube_base, resolution, cube, self.generation), made

    def _free(self) -> None:
        if self.depths is not None:
            self.maps.bind_world_depths(None)
        for b in (self.depths, self.big, self.kept):
            if b is not None:
                b.destroy()
        self.depths = self.big = self.kept = None
        self._kept_key = None
        self.bytes = 0

    def destroy(self) -> None:
        self._free()
