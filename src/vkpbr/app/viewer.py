"""`vkpbr view`: the interactive viewer. GLFW window and input, the frame loop, the HUD text.

The scene is drawn by the headless Renderer's own pipelines and `record_draws` into sRGB
swapchain images (render/window.py), so a screenshot equals `Renderer.render` for the same
camera, light, size and modes. Per frame, Python polls events, moves the camera, writes the
uniforms, picks a pre-recorded command buffer and submits; everything else (pipelines,
command buffers, HUD geometry) is built ahead or only when something changes.
Keys: app/keys.py (HELP). Scripts: app/script.py. Docs: docs/viewer.md.
"""

from __future__ import annotations

import dataclasses
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import glfw
import numpy as np

from vkpbr.app import keys as K
from vkpbr.app.controls import FlyCamera
from vkpbr.app.hud import FontAtlas, TextBlock, layout_blocks
from vkpbr.app.script import Script
from vkpbr.app.viewer_input import InputHandlers
from vkpbr.errors import VkpbrError
from vkpbr.gpu.device import DeviceRequest
from vkpbr.gpu.offscreen_swapchain import OffscreenSwapchain
from vkpbr.gpu.swapchain import Surface, Swapchain
from vkpbr.gpu.text_overlay import QuadOverlay
from vkpbr.render.camera import format_camera
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.options import RenderOptions
from vkpbr.render.renderer import Renderer
from vkpbr.render.window import WindowRenderer
from vkpbr.scene.types import Camera, Light, Scene

__all__ = ["Viewer", "ViewerConfig"]


@dataclass
class ViewerConfig:
    """What `vkpbr view` was asked for (see viewer_cmd.py for the options)."""

    size: tuple[int, int] = (1280, 720)
    camera: Camera | None = None  # None: the scene's camera (or the automatic one)
    light: Light | None = None
    # Called with the Renderer once the scene is loaded: the start camera and light (the
    # command line's --camera / --light resolve against the scene this way).
    pose: Callable[[Renderer], tuple[Camera, Light]] | None = None
    options: RenderOptions = field(default_factory=RenderOptions)
    vsync: bool = True
    frames: int | None = None  # stop after N frames
    screenshot: Path | None = None  # with frames: write the last frame here
    script: Script | None = None
    validation: bool = False
    device: str | int | None = None
    title: str = "vkpbr"
    offscreen: bool = False  # no window: draw into offscreen images (gpu/offscreen_swapchain.py)
    scene_label: str = ""  # how `C` names the scene in the printed command


class Viewer(InputHandlers):
    """Owns the window, the Renderer, the swapchain and the input state. `run()` loops until
    Esc / close / the script's quit / `frames`; `close()` releases everything."""

    def __init__(self, scene: Scene | None, config: ViewerConfig) -> None:
        self.config = config
        self.window: Any = None
        self._glfw = False
        if not config.offscreen:
            if not glfw.init():
                raise VkpbrError("cannot open a window: GLFW failed to initialise (no display?); "
                                 "use xvfb-run, or --offscreen to run without one")
            self._glfw = True
        self.renderer: Renderer | None = None
        try:
            self._open(scene)
        except BaseException:
            self.close()
            raise

    # --- set-up -----------------------------------------------------------------------------
    def _open(self, scene: Scene | None) -> None:
        cfg = self.config
        self.surface: Surface | None = None
        if cfg.offscreen:
            self.renderer = r = Renderer(scene, device=cfg.device, validation=cfg.validation)
            self.swapchain: Swapchain = OffscreenSwapchain(r.device, cfg.size)
        else:
            r = self._open_window(scene, cfg)
        self.font = FontAtlas()
        self.overlay = QuadOverlay(r.device, self.font.pixels, self.swapchain.color_format,
                                   self.swapchain.depth_format, SPV_DIR)
        self.frames = WindowRenderer(r, self.swapchain, self.overlay)
        lo, hi = r.scene.bounds()
        ok = np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))
        self.centre = tuple(float(x) for x in (lo + hi) / 2) if ok else (0.0, 0.0, 0.0)
        radius = float(np.linalg.norm(hi - lo)) / 2 if ok else 1.0
        start, light = cfg.pose(r) if cfg.pose else (cfg.camera, cfg.light)
        start = start or r.default_camera()
        if not r.scene.cameras:
            # The automatic camera's near/far hug the scene from outside; flying inside needs
            # a near plane close to the eye.
            start = dataclasses.replace(start, znear=radius * 2e-3, zfar=radius * 8)
        self.fly = FlyCamera(start, radius)
        self.start_light = light or r.default_light()
        self.light = self.start_light
        self.options = cfg.options
        self.animate_light = False
        # The help panel starts open where it leaves room for the picture.
        self.show_help, self.show_hud = cfg.size[0] >= 1200 and cfg.size[1] >= 600, True
        self.held: set[int] = set()
        self.buttons: set[int] = set()
        self.cursor: tuple[float, float] | None = None
        self.captured = False
        self.quit = False
        self.script_minimized = False
        self.pending_shots: list[Path] = []
        self.shot_hud = False  # screenshots include the HUD (tests of the overlay)
        self.shots_written: list[Path] = []
        self.python_ms: list[float] = []
        self.frame_count = 0
        self.minimized_waits = 0  # loop iterations spent waiting while minimised
        self._hud_version = 0
        self._hud_written: dict[int, int] = {}
        self._hud_dirty = True
        self._hud_size = (0, 0)
        self._hud_vertices = np.zeros((0, 8), dtype=np.float32)
        self._stats = {"fps": 0.0, "cpu": 0.0, "gpu": float("nan")}
        self.fb_size = tuple(cfg.size)
        self.iconified = False
        self.loop_fps = float("nan")  # frames per second over the run, after the first frame
        self._want_gpu = True
        if self.window is not None:
            self._connect_callbacks()

    def _open_window(self, scene: Scene | None, cfg: ViewerConfig) -> Renderer:
        glfw.window_hint(glfw.CLIENT_API, glfw.NO_API)
        self.window = glfw.create_window(cfg.size[0], cfg.size[1], cfg.title, None, None)
        if not self.window:
            raise VkpbrError("cannot open a window (is a display available? try xvfb-run, "
                             "or --offscreen)")
        request = DeviceRequest(cfg.device, tuple(glfw.get_required_instance_extensions()),
                                ("VK_KHR_swapchain",))
        self.renderer = r = Renderer(scene, device=request, validation=cfg.validation)
        self.surface = Surface(r.device, self._create_surface)
        self.swapchain = Swapchain(r.device, self.surface, glfw.get_framebuffer_size(self.window),
                                   vsync=cfg.vsync)
        return r

    def _connect_callbacks(self) -> None:
        w = self.window
        glfw.set_key_callback(w, self._on_key)
        glfw.set_cursor_pos_callback(w, self._on_cursor)
        glfw.set_mouse_button_callback(w, self._on_button)
        glfw.set_scroll_callback(w, self._on_scroll)
        # Size and iconified state come from callbacks: querying X11 costs ~0.1 ms a call.
        self.fb_size = tuple(glfw.get_framebuffer_size(w))
        self.iconified = False
        glfw.set_framebuffer_size_callback(w, self._on_fb_size)
        glfw.set_window_iconify_callback(w, self._on_iconify)
        glfw.set_window_close_callback(w, lambda _w: setattr(self, "quit", True))

    def _create_surface(self, instance: Any) -> Any:
        vk = self.renderer.device.vk  # type: ignore[union-attr]
        out = vk.ffi.new("VkSurfaceKHR*")
        if glfw.create_window_surface(instance, self.window, None, out) != 0:
            raise VkpbrError("glfwCreateWindowSurface failed")
        return out[0]

    # --- per-frame state ---------------------------------------------------------------------
    def camera(self) -> Camera:
        return self.fly.camera()

    def print_camera(self) -> None:
        cam, o, (w, h) = self.camera(), self.options, self.swapchain.extent
        parts = ["vkpbr render", self.config.scene_label, f"--size {w}x{h}",
                 f"--camera {format_camera(cam)}", f"--fov {cam.yfov_deg:g}",
                 "--light " + ",".join(f"{x:.6g}" for x in self.light.position),
                 f"--view {o.view} --brdf {o.brdf} --tbn {o.tbn} --tonemap {o.tonemap}",
                 f"--exposure {o.exposure:g}"]
        parts += [flag for flag, on in (("--no-alpha-mask", not o.alpha_mask),
                                        ("--no-normal-maps", not o.normal_mapping),
                                        ("--no-occlusion", not o.occlusion)) if on]
        print(" ".join(p for p in parts if p), f"  # near {cam.znear:g}, far {cam.zfar:g}",
              flush=True)

    def _hud_blocks(self) -> list[TextBlock]:
        if not self.show_hud:
            return []
        s, o, (w, h) = self._stats, self.options, self.swapchain.extent
        onoff = lambda b: "on" if b else "off"  # noqa: E731
        lines = (
            f"{s['fps']:.1f} fps   CPU {s['cpu']:.2f} ms   GPU {s['gpu']:.2f} ms",
            f"view {o.view} [{o.view:d}]   D {o.brdf}   TBN {o.tbn}   fov {self.fly.yfov_deg:g}",
            f"tonemap {o.tonemap}   exposure {o.exposure:+.1f} EV",
            f"alpha mask {onoff(o.alpha_mask)}   normal maps {onoff(o.normal_mapping)}   "
            f"occlusion {onoff(o.occlusion)}",
            f"light anim {onoff(self.animate_light)}   {w}x{h} {self.swapchain.present_mode_name}",
            "H: key help" if not self.show_help else "",
        )
        blocks = [TextBlock(lines, "top-left")]
        if self.show_help:
            help_lines = tuple(f"{k}\t{v}" for k, v in K.HELP)
            blocks.append(TextBlock(help_lines, "top-right", (0.85, 0.9, 1.0, 1.0)))
        return blocks

    # --- the frame loop ---------------------------------------------------------------------
    def _minimized(self) -> bool:
        return self.script_minimized or self.iconified or 0 in self.fb_size

    def run(self) -> int:
        """Loop until quit; returns the exit status (0)."""
        cfg, sc, frames = self.config, self.swapchain, self.frames
        script = list(cfg.script.events) if cfg.script else []
        fixed_dt = cfg.script.fixed_dt if cfg.script else None
        clock = 0.0
        start = last = t_hud = time.perf_counter()
        hud_frames, hud_cpu = 0, 0.0
        t_first = start
        while not self.quit:
            t0, c0 = time.perf_counter(), time.thread_time()
            if self.window is not None:
                glfw.poll_events()
            dt = fixed_dt if fixed_dt is not None else t0 - last
            last = t0
            clock = clock + fixed_dt if fixed_dt is not None else t0 - start
            while script and script[0].t <= clock + 1e-9:
                self._replay(script.pop(0))
            if self.quit:
                break
            if self._minimized():
                self.minimized_waits += 1
                if self.window is not None:
                    glfw.wait_events_timeout(0.02 if script else 0.1)
                elif fixed_dt is None:
                    time.sleep(0.005)  # offscreen "minimised" until the script restores it
                continue
            fb = self.fb_size
            if (sc.handle is None or fb != sc.extent) and not sc.recreate(fb):
                continue
            frames.sync()
            self._update(dt)
            cb = time.thread_time()
            index = sc.acquire()
            blocked = time.thread_time() - cb
            if index is None:
                sc.recreate(self.fb_size)
                continue
            if self._want_gpu:  # read back only when the HUD's numbers are refreshed
                gpu = frames.gpu_ms(index)
                if gpu == gpu:
                    self._stats["gpu"] = gpu
                    self._want_gpu = False
            camera, o = self.camera(), self.options
            r = self.renderer
            frames.write_uniforms(index, camera, self.light, o)
            self._write_hud(index)
            tbn = o.tbn
            order = r.blend_order(camera.eye)  # type: ignore[union-attr]
            last_frame = cfg.frames is not None and self.frame_count + 1 >= cfg.frames
            if last_frame and cfg.screenshot is not None:
                self.pending_shots.append(cfg.screenshot)
            shot = self.pending_shots.pop(0) if self.pending_shots else None
            if shot is not None and not sc.can_copy:  # no TRANSFER_SRC swapchain: headless
                self._save(shot, r.render(camera, self.light, sc.extent, o), camera)  # type: ignore[union-attr]
                shot = None
            if shot is None:
                cmd, buffer = frames.command_buffer(index, tbn, o.alpha_mask, order), None
            else:
                buffer = frames.screenshot_buffer()
                cmd = frames.record(index, tbn, o.alpha_mask, order, buffer, self.shot_hud)
            slot = sc.slot
            cb = time.thread_time()
            ok = sc.submit_and_present(cmd, index)
            blocked += time.thread_time() - cb
            t_end = time.perf_counter()
            if shot is not None:
                self._finish_screenshot(slot, cmd, buffer, shot, camera)
                t_end = time.perf_counter()
                blocked += time.thread_time() - cb  # screenshots are not per-frame work
            elif not ok:
                sc.recreate(self.fb_size)
            self.frame_count += 1
            # Python's own CPU time for the frame: thread CPU time, so that the driver's
            # threads (lavapipe rasterises on the other cores) do not inflate it, minus the
            # driver's work inside acquire / submit / present.
            cpu_ms = (time.thread_time() - c0 - blocked) * 1e3
            self.python_ms.append(cpu_ms)
            hud_frames, hud_cpu = hud_frames + 1, hud_cpu + cpu_ms
            if t_end - t_hud >= 0.25:
                self._stats["fps"] = hud_frames / (t_end - t_hud)
                self._stats["cpu"] = hud_cpu / hud_frames
                t_hud, hud_frames, hud_cpu = t_end, 0, 0.0
                self._hud_dirty = self._want_gpu = True
            if self.frame_count == 1:
                t_first = t_end
            if last_frame:
                break
        self.renderer.device.wait_idle()  # type: ignore[union-attr]
        if self.frame_count > 1:  # frames after the first (which records command buffers)
            self.loop_fps = (self.frame_count - 1) / max(time.perf_counter() - t_first, 1e-9)
        self.renderer.device.check_validation()  # type: ignore[union-attr]
        return 0

    def _write_hud(self, index: int) -> None:
        """Lay the HUD out again when it changed (4 times a second for the timings), and
        copy it into image `index`'s overlay slot when that slot is out of date."""
        size = self.swapchain.extent
        if self._hud_dirty or size != self._hud_size:
            self._hud_vertices = layout_blocks(self.font, self._hud_blocks(), size)
            self._hud_version += 1
            self._hud_dirty, self._hud_size = False, size
            self._hud_written.clear()
        if self._hud_written.get(index) != self._hud_version:
            self.overlay.write(index, self._hud_vertices)
            self._hud_written[index] = self._hud_version

    def _finish_screenshot(self, slot: int, cmd: Any, buffer: Any, path: Path,
                           camera: Camera) -> None:
        self.swapchain.wait_frame(slot)
        image = self.frames.read_screenshot(buffer)
        self.renderer.device.free_command_buffer(cmd)  # type: ignore[union-attr]
        buffer.destroy()
        self._save(path, image, camera)

    def _save(self, path: Path, image: np.ndarray, camera: Camera) -> None:
        from vkpbr.app.cli import write_image_atomic

        # What the shot shows, for tests: compare with Renderer.render of the same inputs.
        self.last_screenshot = (image, camera, self.light, self.options, self.swapchain.extent)
        write_image_atomic(path, image)
        self.shots_written.append(path)
        print(f"wrote {path} ({image.shape[1]}x{image.shape[0]})", flush=True)

    def summary(self) -> str:
        ms = self.python_ms[1:] or self.python_ms
        med = statistics.median(ms) if ms else float("nan")
        return (f"{self.frame_count} frames, Python per frame {med:.3f} ms (median), "
                f"GPU {self._stats['gpu']:.2f} ms, {self.loop_fps:.1f} fps "
                f"({self.swapchain.extent[0]}x{self.swapchain.extent[1]}, "
                f"{self.swapchain.present_mode_name})")

    # --- lifetime ---------------------------------------------------------------------------
    def close(self) -> None:
        """Release the GPU objects, the device and the window (idempotent)."""
        r, self.renderer = self.renderer, None
        if r is not None:
            for name in ("frames", "overlay", "swapchain", "surface"):
                obj = getattr(self, name, None)
                if obj is not None:
                    obj.destroy()
                    setattr(self, name, None)
            r.close()
        if self.window is not None:
            glfw.destroy_window(self.window)
            self.window = None
        if self._glfw:
            glfw.terminate()
            self._glfw = False

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use `vkpbr view`")
