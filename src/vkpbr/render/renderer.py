"""The headless PBR renderer: Scene in, NumPy image out.

Per frame, Python does a handful of things: write three small uniform blocks into
persistently mapped memory, submit a command buffer recorded once for this target and mode
set, wait on its fence, and copy the mapped readback into NumPy. Debug view, BRDF, exposure,
tone mapping, light and camera are uniforms: changing them re-records nothing. The TBN path,
alpha masking and the image size select among pre-recorded command buffers.
"""

from __future__ import annotations

import collections
import dataclasses
import time
from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.gpu.descriptors import BindingSpec, DescriptorSetLayout
from vkpbr.gpu.device import Device
from vkpbr.gpu.pipeline import Pipeline, PipelineLayout, PipelineSpec, VertexStream
from vkpbr.gpu.target import RenderTarget
from vkpbr.gpu.vk import check_result
from vkpbr.render import layouts as L
from vkpbr.render.camera import forward, validate_camera, view_projection_columns
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.frames import FrameSlot, FrameStats, create_slots
from vkpbr.render.gpu_scene import GpuScene
from vkpbr.render.options import RenderOptions
from vkpbr.scene.types import Camera, Light, Scene

__all__ = ["Renderer", "RenderOptions", "FrameStats"]

_TBN_STREAMS = {
    L.TbnMode.VECTORS: (("normals", "vec3"), ("tangents", "vec4")),
    L.TbnMode.QUAT: (("qtangents", "vec4"),),
    L.TbnMode.PACKED: (("packed_frames", "uint"),),
}
# Vertex inputs before the tangent frame: location = binding, one stream each (pbr.vert).
# "texcoords1" is the TEXCOORD_0 buffer again in scenes without TEXCOORD_1 (GpuScene).
# "colors" (COLOR_0) is one white value read with stride 0 in scenes without vertex colours.
_BASE_STREAMS = (("positions", "vec3"), ("texcoords", "vec2"), ("texcoords1", "vec2"),
               ("colors", "unorm16x4"))
_PASS_ORDER = ("opaque", "opaque_double", "mask", "blend")
FRAMES_IN_FLIGHT = 3


def _camera_key(c: Camera) -> tuple:
    return (*c.eye, *c.target, *c.up, c.yfov_deg, c.znear, c.zfar)


def _light_key(li: Light) -> tuple:
    return (*li.position, *li.color, li.intensity, li.falloff, li.range)


class _Recorded:
    """A command buffer recorded once for (target, TBN path, alpha masking), with the C
    structs its submission needs, built once so a frame's submit is one raw call."""

    def __init__(self, vk: Any, cmd: Any, fence: Any) -> None:
        self.cmd, self.fence = cmd, fence
        ffi = vk.ffi
        self._cmds = ffi.new("VkCommandBuffer[1]", [cmd])  # referenced: submit points into it
        self.submit = ffi.new("VkSubmitInfo*", {
            "sType": vk.VK_STRUCTURE_TYPE_SUBMIT_INFO, "commandBufferCount": 1,
            "pCommandBuffers": self._cmds})
        self.fences = ffi.new("VkFence[1]", [fence])
        self.blend_order: tuple[int, ...] = ()


class Renderer:
    """Renders a Scene (the built-in default scene when None) into NumPy arrays.

    Parameters
    ----------
    scene : the scene to draw; None renders the built-in PBR chart.
    device : device name substring or index (`vkpbr info` lists them); None picks the best.
    validation : enable the Khronos validation layer; any error raises ValidationError.
    msaa : 1 or 4 samples per pixel.
    """

    def __init__(
        self,
        scene: Scene | None = None,
        device: str | int | None = None,
        validation: bool = False,
        sync_validation: bool = False,
        msaa: int = 1,
        background: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ) -> None:
        t0 = time.perf_counter()
        if msaa not in (1, 4):
            raise UsageError(f"msaa {msaa}: choose 1 or 4")
        if scene is None:
            from vkpbr.scene.default import default_scene

            scene = default_scene()
        self.scene = scene
        self.msaa = msaa
        self.background = background
        self.device = Device(device, validation=validation, sync_validation=sync_validation)
        self._targets: dict[tuple, RenderTarget] = {}
        self._recorded: dict[tuple, _Recorded] = {}
        self._pipelines: dict[tuple, Pipeline] = {}
        try:
            self._create_layouts()
            self._create_frame_uniforms()
            self.gpu_scene = GpuScene(self.device, scene, self.set_layouts[1])
            blend = [d.center for d in self.gpu_scene.draws if d.kind == "blend"]
            self._blend_centers = np.array(blend, dtype=np.float64).reshape(-1, 3)
            self.last_stats = FrameStats()
            self.timings = {"setup": time.perf_counter() - t0, **self.gpu_scene.timings}
        except BaseException:
            self.close()
            raise

    # --- descriptors and uniforms -----------------------------------------------------------
    def _create_layouts(self) -> None:
        self.set_layouts = [
            DescriptorSetLayout(self.device, [BindingSpec(b, k, s, n) for b, k, s, n in rows])
            for _, rows in sorted(L.SETS.items())
        ]
        self.pipeline_layout = PipelineLayout(self.device, self.set_layouts, L.PUSH.size)

    def _create_frame_uniforms(self) -> None:
        vk = self.device.vk
        self.frame_ubo, self._frame_pool, self.slots = create_slots(
            self.device, self.set_layouts[0], self.set_layouts[2], FRAMES_IN_FLIGHT)
        if self.device.timestamps:
            self.query_pool = vk.vkCreateQueryPool(
                self.device.handle,
                vk.VkQueryPoolCreateInfo(queryType=vk.VK_QUERY_TYPE_TIMESTAMP,
                                         queryCount=2 * FRAMES_IN_FLIGHT),
                None)
        else:
            self.query_pool = None
        self._query_data = vk.ffi.new("uint64_t[2]")

    # Slot 0 serves single frames (render) and other frame loops (the viewer).
    @property
    def set0(self) -> Any:
        return self.slots[0].set0

    @property
    def set2(self) -> Any:
        return self.slots[0].set2

    # --- pipelines --------------------------------------------------------------------------
    def _pipeline(self, target: Any, tbn: L.TbnMode, kind: str) -> Pipeline:
        key = (target.color_format, target.depth_format, target.samples, tbn, kind)
        if key not in self._pipelines:
            inputs = _BASE_STREAMS + _TBN_STREAMS[tbn]
            gs = self.gpu_scene
            streams = [VertexStream(i, i, fmt, 0 if name == "colors" and not gs.has_colors else None)
                       for i, (name, fmt) in enumerate(inputs)]
            base = PipelineSpec(
                vertex_shader=f"pbr_{tbn.name.lower()}.vert.spv",
                fragment_shader="pbr_opaque.frag.spv",
                streams=tuple(streams),
                color_format=target.color_format,
                depth_format=target.depth_format,
                samples=target.samples,
            )
            spec = {
                "opaque": base,
                "opaque_double": dataclasses.replace(base, cull="none"),
                "mask": dataclasses.replace(base, cull="none", fragment_shader="pbr_mask.frag.spv"),
                "blend": dataclasses.replace(base, cull="none", blend=True, depth_write=False),
            }[kind]
            self._pipelines[key] = Pipeline(self.device, spec, self.pipeline_layout, SPV_DIR)
        return self._pipelines[key]

    def build_pipelines(self, target: Any) -> None:
        """Create every pipeline (all TBN paths and passes) for `target`'s formats now, so
        that no later mode switch waits for one."""
        for tbn in L.TbnMode:
            for kind in _PASS_ORDER:
                self._pipeline(target, tbn, kind)

    def prepare(self, size: tuple[int, int], tbn_modes: tuple[str, ...] = ("vectors", "quat", "packed"),
                linear: bool = False) -> None:
        """Build every pipeline and command buffer for `size` up front (the viewer does this
        so that no key press waits for a pipeline)."""
        target = self._target(size, linear)
        for name in tbn_modes:
            tbn = L.enum_by_name(L.TbnMode, name)
            for alpha_mask in (True, False):
                self._record(target, tbn, alpha_mask)  # type: ignore[arg-type]

    # --- targets and recording --------------------------------------------------------------
    def _target(self, size: tuple[int, int], linear: bool) -> RenderTarget:
        w, h = size
        limit = int(self.device.limits.maxImageDimension2D)
        if not (isinstance(w, int | np.integer) and isinstance(h, int | np.integer)) or w <= 0 or h <= 0:
            raise UsageError(f"image size {w}x{h}: width and height must be positive integers")
        if w > limit or h > limit:
            raise UsageError(f"image size {w}x{h} exceeds this device's limit of {limit}x{limit}")
        key = (int(w), int(h), linear)
        if key not in self._targets:
            bg = (*self.background, 1.0)
            if not linear:  # the clear colour of an sRGB target is linear
                bg = tuple(float(c) for c in bg)
            self._targets[key] = RenderTarget(
                self.device, int(w), int(h), "float" if linear else "srgb", self.msaa, bg)
        return self._targets[key]

    def blend_order(self, eye: Any) -> tuple[int, ...]:
        """Indices into the blended draws, farthest first from `eye` (painter's order)."""
        centers = self._blend_centers
        if len(centers) < 2:
            return tuple(range(len(centers)))
        d = np.sum((centers - np.asarray(eye, dtype=np.float64)) ** 2, axis=1)
        return tuple(np.argsort(-d, kind="stable").tolist())

    def _record(self, target: RenderTarget, tbn: L.TbnMode, alpha_mask: bool,
                blend_order: tuple[int, ...] = (), slot: FrameSlot | None = None) -> _Recorded:
        slot = slot or self.slots[0]
        key = (id(target), tbn, alpha_mask, slot.index)
        rec = self._recorded.get(key)
        if rec is not None and rec.blend_order == blend_order:
            return rec
        if rec is not None:  # the camera moved enough to reorder blended draws: re-record
            self._free_recorded(self._recorded.pop(key))
        vk = self.device.vk
        cmd = self.device.allocate_command_buffer()
        vk.vkBeginCommandBuffer(cmd, vk.VkCommandBufferBeginInfo())
        q = slot.query_base
        if self.query_pool is not None:
            vk.vkCmdResetQueryPool(cmd, self.query_pool, q, 2)
            vk.vkCmdWriteTimestamp2(cmd, vk.VK_PIPELINE_STAGE_2_NONE, self.query_pool, q)
        target.record_begin(cmd)
        self.record_draws(cmd, target, tbn, alpha_mask, slot, blend_order)
        target.record_end(cmd, slot.index)
        if self.query_pool is not None:
            vk.vkCmdWriteTimestamp2(cmd, vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, self.query_pool, q + 1)
        vk.vkEndCommandBuffer(cmd)
        fence = vk.vkCreateFence(self.device.handle, vk.VkFenceCreateInfo(), None)
        rec = _Recorded(vk, cmd, fence)
        rec.blend_order = blend_order
        self._recorded[key] = rec
        return rec

    def record_draws(self, cmd: Any, target: Any, tbn: L.TbnMode, alpha_mask: bool,
                     slot: FrameSlot | None = None, blend_order: tuple[int, ...] = ()) -> None:
        """Record every draw of the scene into `cmd`, inside dynamic rendering already begun on
        an attachment set described by `target` (anything with color_format, depth_format and
        samples: a RenderTarget, or the viewer's swapchain). `blend_order` (from
        `blend_order(eye)`) sorts the blended draws back to front."""
        vk = self.device.vk
        gs = self.gpu_scene
        slot = slot or self.slots[0]
        layout = self.pipeline_layout.handle
        names = [n for n, _ in _BASE_STREAMS + _TBN_STREAMS[tbn]]
        gs.ensure_streams(tuple(names))  # the quat / packed streams on first use
        buffers = [gs.streams[n].handle for n in names]
        vk.vkCmdBindIndexBuffer(cmd, gs.index_buffer.handle, 0, vk.VK_INDEX_TYPE_UINT32)
        for kind in _PASS_ORDER:
            draws = [d for d in gs.draws if self._pass_of(d.kind, alpha_mask) == kind]
            if kind == "blend" and len(blend_order) == len(draws):
                draws = [draws[i] for i in blend_order]
            if not draws:
                continue
            pipeline = self._pipeline(target, tbn, kind)
            vk.vkCmdBindPipeline(cmd, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline.handle)
            vk.vkCmdBindDescriptorSets(cmd, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, layout, 0, 1,
                                       [slot.set0], 0, None)
            vk.vkCmdBindDescriptorSets(cmd, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, layout, 2, 1,
                                       [slot.set2], 0, None)
            vk.vkCmdBindVertexBuffers(cmd, 0, len(buffers), buffers, [0] * len(buffers))
            bound = None
            for d in draws:
                if d.material != bound:
                    vk.vkCmdBindDescriptorSets(cmd, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, layout, 1, 1,
                                               [gs.material_sets[d.material]], 0, None)
                    bound = d.material
                vk.vkCmdPushConstants(
                    cmd, layout, vk.VK_SHADER_STAGE_VERTEX_BIT | vk.VK_SHADER_STAGE_FRAGMENT_BIT,
                    0, L.PUSH.size, vk.ffi.from_buffer(d.push))
                vk.vkCmdDrawIndexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0)

    @staticmethod
    def _pass_of(kind: str, alpha_mask: bool) -> str:
        if kind == "mask" and not alpha_mask:
            return "opaque_double"  # --no-alpha-mask: masked materials drawn as opaque
        return kind

    # --- per frame --------------------------------------------------------------------------
    def default_camera(self) -> Camera:
        if self.scene.cameras:
            return self.scene.cameras[0]
        from vkpbr.scene.geometry import auto_camera

        return auto_camera(self.scene)

    def default_light(self) -> Light:
        return self.scene.lights[0] if self.scene.lights else Light()

    def write_uniforms(self, camera: Camera, light: Light, size: tuple[int, int],
                       opts: RenderOptions, linear: bool, slot: FrameSlot | None = None) -> None:
        """Write the camera, settings and light blocks of `slot` (default: slot 0)."""
        slot = slot or self.slots[0]
        # Frames that repeat the slot's last inputs (a static scene re-rendered) skip the
        # uniform maths entirely; the key is cheap next to computing the matrices.
        key = (_camera_key(camera), _light_key(light), size, opts, linear)
        if key == slot.uniform_key:
            return
        slot.uniform_key = key
        w, h = size
        c0, c1, c2, c3 = view_projection_columns(camera, w / h)
        L.CAMERA.packer.pack_into(slot.m_camera, 0, *c0, *c1, *c2, *c3)
        flags = L.SETTINGS_NORMAL_MAPPING if opts.normal_mapping else 0
        flags |= L.SETTINGS_OCCLUSION if opts.occlusion else 0
        flags |= 0 if linear else L.SETTINGS_SRGB_TARGET
        # One struct pack per block (in the order of layouts.SETTINGS / LIGHT's fields).
        L.SETTINGS.packer.pack_into(
            slot.m_settings, 0, *forward(camera), 0.0, opts.view, opts.brdf, opts.tonemap, flags,
            2.0 ** opts.exposure, camera.znear, camera.zfar, 0.0)
        L.LIGHT.packer.pack_into(
            slot.m_light, 0, *light.position, 1.0, *light.color, light.intensity, *camera.eye, 1.0,
            0 if light.falloff == "none" else 1, light.range)

    def render(
        self,
        camera: Camera | None = None,
        light: Light | None = None,
        size: tuple[int, int] = (640, 480),
        options: RenderOptions | None = None,
        linear: bool = False,
        depth: bool = False,
        **option_overrides: Any,
    ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        """Render one frame.

        Returns (H, W, 4) uint8 sRGB-encoded colour, or (H, W, 4) float32 linear colour when
        `linear`; with `depth`, a tuple (colour, depth) where depth is (H, W) float32 linear
        view-space distance along the camera axis (inf where nothing was drawn).
        Keyword overrides (view="d", brdf="blinn-phong", ...) update `options`.
        """
        camera = camera or self.default_camera()
        frames = self.render_many([camera], light, size, options, linear, depth, **option_overrides)
        return next(iter(frames))

    def render_many(
        self,
        cameras: Iterable[Camera],
        light: Light | None = None,
        size: tuple[int, int] = (640, 480),
        options: RenderOptions | None = None,
        linear: bool = False,
        depth: bool = False,
        readback: bool = True,
        **option_overrides: Any,
    ) -> Iterator[np.ndarray | tuple[np.ndarray, np.ndarray] | None]:
        """Render one frame per camera, yielding what `render` returns, in order.

        Up to FRAMES_IN_FLIGHT frames are queued on the GPU: while frame i renders, Python
        writes frame i+1's uniforms and submits it, and copies frame i-1 out of its own
        persistently mapped readback buffer. Nothing is allocated per frame but the returned
        arrays. Each frame is bit-for-bit what `render` gives for its camera.
        `readback=False` yields None per finished frame instead (benchmarks: render only).
        """
        opts = dataclasses.replace(options or RenderOptions(), **option_overrides)
        tbn = opts.tbn
        light = light or self.default_light()
        target = self._target(size, linear)
        lib = self.device.vk.lib
        pending: collections.deque[tuple[FrameSlot, _Recorded, Camera]] = collections.deque()
        try:
            for i, camera in enumerate(cameras):
                validate_camera(camera)
                if len(pending) == len(self.slots):
                    yield self._collect(*pending.popleft(), target, depth, readback)
                slot = self.slots[i % len(self.slots)]
                rec = self._record(target, tbn, opts.alpha_mask, self.blend_order(camera.eye), slot)
                t0 = time.perf_counter()
                self.write_uniforms(camera, light, size, opts, linear, slot)
                check_result(lib.vkQueueSubmit(self.device.queue, 1, rec.submit, rec.fence),
                             "vkQueueSubmit")
                slot.stats.cpu_ms = (time.perf_counter() - t0) * 1e3
                pending.append((slot, rec, camera))
            while pending:
                yield self._collect(*pending.popleft(), target, depth, readback)
        finally:
            # An abandoned generator leaves frames queued: finish them so fences are reusable.
            for _slot, rec, _cam in pending:
                self._wait(rec)

    def _wait(self, rec: _Recorded) -> None:
        lib = self.device.vk.lib
        check_result(lib.vkWaitForFences(self.device.handle, 1, rec.fences, 1, 2**63 - 1),
                     "vkWaitForFences")
        check_result(lib.vkResetFences(self.device.handle, 1, rec.fences), "vkResetFences")

    def _collect(self, slot: FrameSlot, rec: _Recorded, camera: Camera, target: RenderTarget,
                 depth: bool, readback: bool = True) -> np.ndarray | tuple[np.ndarray, np.ndarray] | None:
        stats = slot.stats
        t0 = time.perf_counter()
        self._wait(rec)
        t1 = time.perf_counter()
        stats.wait_ms = (t1 - t0) * 1e3
        stats.gpu_ms = self._gpu_ms(slot)
        if not readback:
            self.last_stats = dataclasses.replace(stats, readback_ms=0.0)
            return None
        color = target.read_color(slot.index)
        out_depth = self._linear_depth(target.read_depth(slot.index), camera) if depth else None
        stats.readback_ms = (time.perf_counter() - t1) * 1e3
        self.last_stats = dataclasses.replace(stats)
        self.device.check_validation()
        return (color, out_depth) if depth else color

    def _gpu_ms(self, slot: FrameSlot) -> float:
        if self.query_pool is None:
            return float("nan")
        vk = self.device.vk
        data = self._query_data
        check_result(vk.lib.vkGetQueryPoolResults(
            self.device.handle, self.query_pool, slot.query_base, 2, 16, data, 8,
            vk.VK_QUERY_RESULT_64_BIT | vk.VK_QUERY_RESULT_WAIT_BIT), "vkGetQueryPoolResults")
        return (data[1] - data[0]) * float(self.device.limits.timestampPeriod) * 1e-6

    @staticmethod
    def _linear_depth(d: np.ndarray, camera: Camera) -> np.ndarray:
        """Window depth in [0, 1] -> view-space distance along the axis (inf = background)."""
        n, f = camera.znear, camera.zfar
        with np.errstate(divide="ignore"):
            z = (n * f) / (f - d.astype(np.float64) * (f - n))
        z[d >= 1.0] = np.inf
        return z.astype(np.float32)

    # --- lifetime ---------------------------------------------------------------------------
    def _free_recorded(self, rec: _Recorded) -> None:
        self.device.vk.vkDestroyFence(self.device.handle, rec.fence, None)
        self.device.free_command_buffer(rec.cmd)

    def close(self) -> None:
        """Destroy everything (idempotent). The Renderer is unusable afterwards."""
        dev = getattr(self, "device", None)
        if dev is None or dev.handle is None:
            return
        vk = dev.vk
        dev.wait_idle()
        for rec in self._recorded.values():
            self._free_recorded(rec)
        self._recorded.clear()
        if getattr(self, "query_pool", None) is not None:
            vk.vkDestroyQueryPool(dev.handle, self.query_pool, None)
            self.query_pool = None
        dev.close()

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
