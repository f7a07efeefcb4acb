"""`vkpbr view`: the interactive viewer. Window and input, a clock, the HUD text, and one
`Renderer.draw` per frame.

The scene goes through the renderer's one frame path (render/renderer.py) into a window's
swapchain, or into an offscreen target of the same formats for `--offscreen` (GPU servers
without a display), with the HUD as an overlay pass; a screenshot without the HUD is
`Renderer.render` of the same camera, light, size and modes, so it equals a headless render
by construction. Keys: app/keys.py (BINDINGS). Scripts: app/script.py. Options: app/view_cmd.py.
Docs: docs/viewer.md.
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
from vkpbr.app.log import say
from vkpbr.app.options import option_flags
from vkpbr.app.playback import Playback
from vkpbr.app.script import Script
from vkpbr.app.viewer_input import InputHandlers
from vkpbr.errors import VkpbrError
from vkpbr.io import write_image_atomic
from vkpbr.render.camera import format_camera
from vkpbr.render.layouts import PipelinePath
from vkpbr.render.options import RenderOptions
from vkpbr.render.renderer import COPY_COLOR, Renderer
from vkpbr.scene.lights import light_spec
from vkpbr.scene.types import Camera, Light, Scene

__all__ = ["Viewer", "ViewerConfig"]

_HUD_REFRESH_S = 0.25  # how often the HUD's fps / CPU / GPU numbers change


@dataclass
class ViewerConfig:
    """What `vkpbr view` was asked for (see view_cmd.py for the options)."""

    size: tuple[int, int] = (1280, 720)
    camera: Camera | None = None  # None: the scene's camera (or the automatic one)
    lights: tuple[Light, ...] | None = None  # None: the renderer's default for the scene
    # Called with the Renderer once the scene is loaded: the start camera and lights (the
    # command line's --camera / --light resolve against the scene this way).
    pose: Callable[[Renderer], tuple[Camera, tuple[Light, ...]]] | None = None
    options: RenderOptions = field(default_factory=RenderOptions)
    vsync: bool = True
    frames: int | None = None  # stop after N frames
    screenshot: Path | None = None  # with frames: write the last frame here
    script: Script | None = None
    validation: bool = False
    device: str | int | None = None
    title: str = "vkpbr"
    offscreen: bool = False  # no window: draw into an offscreen target of `size`
    scene_label: str = ""  # how `C` names the scene in the printed command


class Clock:
    """Frame time: the wall clock, or the script's fixed step; and the script's due events."""

    def __init__(self, script: Script | None) -> None:
        self.events = list(script.events) if script else []
        self.fixed_dt = script.fixed_dt if script else None
        self.start = self.last = time.perf_counter()
        self.now, self.dt = 0.0, 0.0

    def tick(self) -> None:
        t = time.perf_counter()
        self.dt = self.fixed_dt if self.fixed_dt is not None else t - self.last
        self.now = self.now + self.fixed_dt if self.fixed_dt is not None else t - self.start
        self.last = t

    def due(self) -> list[Any]:
        out = []
        while self.events and self.events[0].t <= self.now + 1e-9:
            out.append(self.events.pop(0))
        return out


class FrameMeter:
    """Python's CPU time per frame (thread time, minus the driver's work inside acquire and
    submit, so lavapipe rasterising on the other cores does not count) and the HUD's
    averages, refreshed every _HUD_REFRESH_S."""

    def __init__(self) -> None:
        self.python_ms: list[float] = []
        self.fps, self.cpu, self.gpu = 0.0, 0.0, float("nan")
        self._t0, self._n, self._sum = time.perf_counter(), 0, 0.0
        self.first_end: float | None = None

    def add(self, cpu_ms: float) -> bool:
        """Record a frame; True when the HUD's averages were refreshed."""
        t = time.perf_counter()
        if self.first_end is None:
            self.first_end = t
        self.python_ms.append(cpu_ms)
        self._n, self._sum = self._n + 1, self._sum + cpu_ms
        if t - self._t0 < _HUD_REFRESH_S:
            return False
        self.fps, self.cpu = self._n / (t - self._t0), self._sum / self._n
        self._t0, self._n, self._sum = t, 0, 0.0
        return True

    def loop_fps(self, frames: int) -> float:
        """Frames per second over the run, after the first frame (which records buffers)."""
        if frames < 2 or self.first_end is None:
            return float("nan")
        return (frames - 1) / max(time.perf_counter() - self.first_end, 1e-9)

    def median_ms(self) -> float:
        ms = self.python_ms[1:] or self.python_ms
        return statistics.median(ms) if ms else float("nan")


def _glfw_init() -> tuple[bool, str]:
    """glfw.init(), with what GLFW said on failure as plain text: the glfw package reports
    errors as Python warnings holding a bytes repr ("(65550) b'X11: ...'"), which would be
    a second, raw line before the one error line."""
    import re
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ok = bool(glfw.init())
    said = []
    for w in caught:
        text = str(w.message)
        m = re.fullmatch(r"\(\d+\) b(['\"])(.*)\1", text, re.S)
        said.append(m.group(2) if m else text)
    if ok:
        for text in said:  # not fatal: keep them as the warnings they were
            warnings.warn(text, stacklevel=2)
    return ok, "; ".join(t.strip().rstrip(".") for t in said if t.strip())


class Viewer(InputHandlers):
    """Owns the window, the Renderer, the frame target and the input state. `run()` loops
    until Esc / close / the script's quit / `frames`; `close()` releases everything."""

    def __init__(self, scene: Scene | None, config: ViewerConfig) -> None:
        self.config = config
        self.window: Any = None
        self._glfw = False
        self.renderer: Renderer | None = None
        self.target: Any = None
        self.hud: Any = None
        try:
            if not config.offscreen:
                ok, why = _glfw_init()
                if not ok:
                    raise VkpbrError(f"cannot open a window: {why or 'GLFW failed to initialise'}"
                                     "; use xvfb-run, or --offscreen to run without one")
                self._glfw = True
            self._open(scene)
        except BaseException:
            self.close()
            raise

    # --- set-up -----------------------------------------------------------------------------
    def _open(self, scene: Scene | None) -> None:
        cfg = self.config
        if cfg.offscreen:
            self.renderer = r = Renderer(scene, device=cfg.device, validation=cfg.validation)
            self.target = r.offscreen_target(cfg.size)
            self.present_mode = "offscreen"
        else:
            r = self._open_window(scene, cfg)
        self.font = FontAtlas()
        self.hud = r.text_overlay(self.font.pixels, self.target)
        r.build_pipelines(self.target)  # every TBN path and pass, before any key press
        lo, hi = r.scene.bounds()
        ok = np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))
        self.centre = tuple(float(x) for x in (lo + hi) / 2) if ok else (0.0, 0.0, 0.0)
        radius = float(np.linalg.norm(hi - lo)) / 2 if ok else 1.0
        start, lights = cfg.pose(r) if cfg.pose else (cfg.camera, cfg.lights)
        self.fly = FlyCamera(start or r.default_camera(), radius)
        self.options = cfg.options
        # The frame's lights; the keys move the first (`light`).
        self.start_lights = self.lights = r.frame_lights(self.options, lights)
        self.env_choices = K.env_choices(self.options)  # what K cycles through
        self.animate_light = False
        self.playback = Playback(r.scene)  # the scene's glTF animations (app/playback.py)
        # The help panel starts open where it leaves room for the picture.
        self.show_help, self.show_hud = cfg.size[0] >= 1200 and cfg.size[1] >= 600, True
        self.held: set[int] = set()
        self.buttons: set[int] = set()
        self.cursor: tuple[float, float] | None = None
        self.captured = self.quit = self.script_minimized = False
        self.pending_shots: list[Path] = []
        self.shot_hud = False  # screenshots include the HUD (tests of the overlay)
        self.shots_written: list[Path] = []
        self.frame_count = self.resizes = 0
        self.minimized_waits = 0  # loop iterations spent waiting while minimised
        self.meter = FrameMeter()
        self._hud_dirty, self._hud_size = True, (0, 0)
        self.fb_size = tuple(cfg.size)
        self.iconified = False
        self.loop_fps = float("nan")
        self._want_gpu = True
        if self.window is not None:
            self._connect_callbacks()

    def _open_window(self, scene: Scene | None, cfg: ViewerConfig) -> Renderer:
        glfw.window_hint(glfw.CLIENT_API, glfw.NO_API)
        self.window = glfw.create_window(cfg.size[0], cfg.size[1], cfg.title, None, None)
        if not self.window:
            raise VkpbrError("cannot open a window (is a display available? try xvfb-run, "
                             "or --offscreen)")
        self.renderer = r = Renderer(scene, device=cfg.device, validation=cfg.validation,
                                     window_extensions=tuple(glfw.get_required_instance_extensions()))
        self.target = r.window_target(
            lambda instance, out: glfw.create_window_surface(instance, self.window, None, out),
            glfw.get_framebuffer_size(self.window), vsync=cfg.vsync)
        self.present_mode = self.target.present_mode_name
        return r

    def _connect_callbacks(self) -> None:
        w = self.window
        glfw.set_key_callback(w, self._on_key)
        glfw.set_cursor_pos_callback(w, self._on_cursor)
        glfw.set_mouse_button_callback(w, self._on_button)
        glfw.set_scroll_callback(w, self._on_scroll)
        # Size and iconified state come from callbacks: querying X11 costs ~0.1 ms a call.
        self.fb_size = tuple(glfw.get_framebuffer_size(w))
        glfw.set_framebuffer_size_callback(w, self._on_fb_size)
        glfw.set_window_iconify_callback(w, self._on_iconify)
        glfw.set_window_close_callback(w, lambda _w: setattr(self, "quit", True))

    # --- state ------------------------------------------------------------------------------
    def camera(self) -> Camera:
        return self.fly.camera()

    def print_camera(self) -> None:
        cam, o, (w, h) = self.camera(), self.options, self.target.extent
        parts = ["vkpbr render", self.config.scene_label, f"--size {w}x{h}",
                 f"--camera {format_camera(cam)}", f"--fov {cam.yfov_deg:g}",
                 *(f"--light {light_spec(li)}" for li in self.lights),
                 *option_flags(o)]
        say(" ".join(p for p in parts if p))

    def _hud_blocks(self) -> list[TextBlock]:
        if not self.show_hud:
            return []
        m, o, (w, h) = self.meter, self.options, self.target.extent
        onoff = lambda b: "on" if b else "off"  # noqa: E731
        lines = (
            f"{m.fps:.1f} fps   CPU {m.cpu:.2f} ms   GPU {m.gpu:.2f} ms",
            f"view {o.view} [{o.view:d}]   lighting {o.lighting}   BRDF {o.shading_brdf}   "
            f"TBN {o.tbn}   fov {self.fly.yfov_deg:g}",
            f"tonemap {o.shading_tonemap}   exposure {o.exposure:+.1f} EV   "
            f"{len(self.lights)} light{'s' if len(self.lights) != 1 else ''}   "
            f"env {Path(o.env).name if o.has_environment else 'none'}"
            + (f" {o.env_rotation:+g} deg" if o.has_environment else ""),
            f"alpha mask {onoff(o.alpha_mask)}   normal maps {onoff(o.normal_mapping)}   "
            f"occlusion {onoff(o.occlusion)}   shadows {onoff(o.shadows)}",
            f"light anim {onoff(self.animate_light)}   {w}x{h} {self.present_mode}   "
            f"path {o.pipeline}"
            + (f" ({'compute' if self.renderer.uses_compute(self.target, o) else 'forward'})"
               if o.pipeline == PipelinePath.AUTO else ""),
            self.playback.label() if self.playback.names else "",
            "H: key help" if not self.show_help else "",
        )
        blocks = [TextBlock(lines, "top-left")]
        if self.show_help:
            help_lines = tuple(f"{k}\t{v}" for k, v in K.HELP)
            blocks.append(TextBlock(help_lines, "top-right", (0.85, 0.9, 1.0, 1.0)))
        return blocks

    def _refresh_hud(self) -> None:
        """Lay the HUD out again when it changed (4 times a second for the timings)."""
        size = self.target.extent
        if self._hud_dirty or size != self._hud_size:
            self.hud.set_vertices(layout_blocks(self.font, self._hud_blocks(), size))
            self._hud_dirty, self._hud_size = False, size

    # --- the frame loop ---------------------------------------------------------------------
    def _minimized(self) -> bool:
        return self.script_minimized or self.iconified or 0 in self.fb_size

    def _wait_while_minimized(self, scripted: bool) -> None:
        self.minimized_waits += 1
        if self.window is not None:
            glfw.wait_events_timeout(0.02 if scripted else 0.1)
        elif not scripted:
            time.sleep(0.005)  # offscreen "minimised" until the script restores it

    def _target_ready(self) -> bool:
        """Match the target to the framebuffer size: False while there is nothing to draw to."""
        fb, t = self.fb_size, self.target
        if self.window is None:
            if fb != t.extent:  # a scripted resize: an offscreen target of the new size
                self.target, self.resizes = self.renderer.offscreen_target(fb), self.resizes + 1  # type: ignore[union-attr]
            return True
        if t.handle is not None and fb == t.extent:
            return True
        self.resizes += 1
        return t.recreate(fb)

    def run(self) -> int:
        """Loop until quit; returns the exit status (0)."""
        cfg, clock = self.config, Clock(self.config.script)
        while not self.quit:
            c0 = time.thread_time()
            clock.tick()
            if self.window is not None:
                glfw.poll_events()
            for event in clock.due():
                self._replay(event)
            if self.quit:
                break
            if self._minimized():
                self._wait_while_minimized(bool(clock.events) or clock.fixed_dt is not None)
                continue
            if not self._target_ready():
                continue
            self._update(clock.dt)
            last = cfg.frames is not None and self.frame_count + 1 >= cfg.frames
            if last and cfg.screenshot is not None:
                self.pending_shots.append(cfg.screenshot)
            blocked = self._frame(self.pending_shots.pop(0) if self.pending_shots else None)
            self.frame_count += 1
            if self.meter.add((time.thread_time() - c0 - blocked) * 1e3):
                self._hud_dirty = self._want_gpu = True
            if last:
                break
        self.renderer.wait_idle()  # type: ignore[union-attr]
        self.loop_fps = self.meter.loop_fps(self.frame_count)
        self.renderer.check_validation()  # type: ignore[union-attr]
        return 0

    def _frame(self, shot: Path | None) -> float:
        """Draw one frame (and write `shot`); returns the CPU seconds spent outside Python's
        own per-frame work (the driver's waits, acquire and submit; screenshots)."""
        r, camera = self.renderer, self.camera()
        self._refresh_hud()
        # A screenshot frame is copied out of the target after drawing: without the HUD
        # (that one frame is shown without it) unless the HUD was asked for.
        copy = shot is not None and getattr(self.target, "can_copy", True)
        if (self.options.pipeline == PipelinePath.COMPUTE
                and r.compute_unavailable(self.target) is not None):  # type: ignore[union-attr]
            # A window presents through the fragment path: the cycle goes on to auto.
            self.options = dataclasses.replace(self.options, pipeline=PipelinePath.AUTO)
            self._hud_dirty = True
        r.choose_paths(self.target, self.options)  # type: ignore[union-attr] - auto: before drawing
        sub = r.draw(self.target, camera, self.lights, self.options,  # type: ignore[union-attr]
                     overlay=self.hud if shot is None or self.shot_hud else None,
                     copy=(COPY_COLOR,) if copy else (), timings=self._want_gpu,
                     driver_time=True)
        stats = r.frame_stats(sub.frame) if sub.frame is not None else None  # type: ignore[union-attr]
        if self._want_gpu and stats is not None and stats.gpu_ms == stats.gpu_ms:
            self.meter.gpu, self._want_gpu = stats.gpu_ms, False
        blocked = stats.driver_ms * 1e-3 if stats is not None else 0.0
        if not sub.ok:
            self.resizes += 1
            if self.window is not None:
                self.target.recreate(self.fb_size)
        if shot is not None:
            c = time.thread_time()
            if copy and sub.frame is not None:
                image = r.read_color(self.target, sub)  # type: ignore[union-attr]
            else:  # no copyable image: the same pixels from a headless render of this view
                image = r.render(camera, self.lights, self.target.extent, self.options)  # type: ignore[union-attr]
            self._save(shot, image, camera)
            blocked += time.thread_time() - c  # screenshots are not per-frame work
        return blocked

    def _save(self, path: Path, image: np.ndarray, camera: Camera) -> None:
        # What the shot shows, for tests: compare with Renderer.render of the same inputs.
        self.last_screenshot = (image, camera, self.lights, self.options, self.target.extent)
        write_image_atomic(path, image)
        self.shots_written.append(path)
        say(f"wrote {path} ({image.shape[1]}x{image.shape[0]})")

    def summary(self) -> str:
        w, h = self.target.extent
        return (f"{self.frame_count} frames, Python per frame {self.meter.median_ms():.3f} ms "
                f"(median), GPU {self.meter.gpu:.2f} ms, {self.loop_fps:.1f} fps "
                f"({w}x{h}, {self.present_mode})")

    # --- lifetime ---------------------------------------------------------------------------
    def close(self) -> None:
        """Release the GPU objects, the device and the window (idempotent)."""
        r, self.renderer = self.renderer, None
        if r is not None:
            r.wait_idle()
            for obj in (self.hud, self.target if self.window is not None else None):
                if obj is not None:
                    obj.destroy()
            self.hud = self.target = None
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
