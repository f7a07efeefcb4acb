"""Input for the viewer: GLFW callbacks and script replay share these handlers, so a
replayed script drives exactly the code a person does. A mixin of `Viewer` (app/viewer.py),
split out to keep each file short; the key map itself is app/keys.py.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path
from typing import Any

import glfw

from vkpbr.app import keys as K
from vkpbr.app.controls import FAST, FOV_STEP, SLOW
from vkpbr.app.script import Event, key_code, mods_bits
from vkpbr.scene.types import Light

__all__ = ["InputHandlers", "LIGHT_ORBIT_RAD_PER_S"]

LIGHT_ORBIT_RAD_PER_S = 0.6


class InputHandlers:
    """Key, mouse and script handlers; expects the Viewer's state attributes (fly, light,
    options, held, buttons, cursor, swapchain, ...)."""

    fly: Any
    light: Any
    options: Any
    swapchain: Any
    window: Any

    # --- input ------------------------------------------------------------------------------
    def _on_key(self, _w: Any, key: int, _scancode: int, action: int, mods: int) -> None:
        if action == glfw.RELEASE:
            self.held.discard(key)
            return
        if action == glfw.PRESS:
            self.held.add(key)
        shift, ctrl = bool(mods & glfw.MOD_SHIFT), bool(mods & glfw.MOD_CONTROL)
        o = self.options
        if key == glfw.KEY_ESCAPE:
            self.quit = True
        elif glfw.KEY_0 <= key <= glfw.KEY_9:
            view = K.view_for_digit(key - glfw.KEY_0, shift, ctrl)
            if view is not None:
                o = K.with_view(o, view)
        elif key == glfw.KEY_V:
            o = K.cycle(o, "view", -1 if shift else 1)
        elif key == glfw.KEY_B:
            o = K.cycle(o, "brdf")
        elif key == glfw.KEY_T:
            o = K.cycle(o, "tbn")
        elif key == glfw.KEY_X:
            o = K.cycle(o, "tonemap")
        elif key in (glfw.KEY_M, glfw.KEY_N, glfw.KEY_O):
            o = K.toggle(o, {glfw.KEY_M: "alpha_mask", glfw.KEY_N: "normal_mapping",
                             glfw.KEY_O: "occlusion"}[key])
        elif key in (glfw.KEY_EQUAL, glfw.KEY_KP_ADD, glfw.KEY_MINUS, glfw.KEY_KP_SUBTRACT):
            step = 0.5 if key in (glfw.KEY_EQUAL, glfw.KEY_KP_ADD) else -0.5
            o = dataclasses.replace(o, exposure=max(-16.0, min(16.0, o.exposure + step)))
        elif key in (glfw.KEY_LEFT_BRACKET, glfw.KEY_RIGHT_BRACKET):
            self.fly.zoom(FOV_STEP if key == glfw.KEY_RIGHT_BRACKET else -FOV_STEP)
            self._hud_dirty = True
        elif action != glfw.PRESS:
            return  # auto-repeat only for the keys above
        elif key == glfw.KEY_SPACE:
            self.animate_light = not self.animate_light
        elif key == glfw.KEY_L:
            self.light = dataclasses.replace(self.light, position=self.fly.eye)
        elif key == glfw.KEY_R:
            self.fly.reset()
            self.light = self.start_light
        elif key == glfw.KEY_C:
            self.print_camera()
        elif key in (glfw.KEY_P, glfw.KEY_F12):
            self.pending_shots.append(Path(time.strftime("vkpbr-%Y%m%d-%H%M%S")
                                           + f"-{self.frame_count}.png"))
        elif key in (glfw.KEY_H, glfw.KEY_F1):
            self.show_help = not self.show_help
        elif key == glfw.KEY_F2:
            self.show_hud = not self.show_hud
        self._hud_dirty = True
        self.options = o

    def _on_fb_size(self, _w: Any, width: int, height: int) -> None:
        self.fb_size = (width, height)

    def _on_iconify(self, _w: Any, iconified: int) -> None:
        self.iconified = bool(iconified)

    def _on_cursor(self, _w: Any, x: float, y: float) -> None:
        if self.cursor is not None:
            dx, dy = x - self.cursor[0], y - self.cursor[1]
            if self.captured or glfw.MOUSE_BUTTON_LEFT in self.buttons:
                self.fly.look(dx, dy)
            if glfw.MOUSE_BUTTON_RIGHT in self.buttons:
                self.fly.pan(dx, dy, self.swapchain.extent[1] or 1)
        self.cursor = (x, y)

    def _on_button(self, _w: Any, button: int, action: int, _mods: int) -> None:
        if action == glfw.PRESS:
            self.buttons.add(button)
            if button == glfw.MOUSE_BUTTON_MIDDLE:
                self.captured = not self.captured
                if self.window is not None:
                    glfw.set_input_mode(self.window, glfw.CURSOR,
                                        glfw.CURSOR_DISABLED if self.captured
                                        else glfw.CURSOR_NORMAL)
        else:
            self.buttons.discard(button)

    def _on_scroll(self, _w: Any, _dx: float, dy: float) -> None:
        self.fly.dolly(dy, self._speed_multiplier())

    def _speed_multiplier(self) -> float:
        h = self.held
        m = FAST if (glfw.KEY_LEFT_SHIFT in h or glfw.KEY_RIGHT_SHIFT in h) else 1.0
        return m * (SLOW if (glfw.KEY_LEFT_CONTROL in h or glfw.KEY_RIGHT_CONTROL in h) else 1.0)

    def _replay(self, event: Event) -> None:
        """Feed one script event through the same handlers as real input."""
        d, kind = event.data, event.type
        if kind == "key":
            code, mods = key_code(d["key"]), mods_bits(d["mods"])
            if d["action"] in ("press", "tap"):
                self._on_key(self.window, code, 0, glfw.PRESS, mods)
            if d["action"] in ("release", "tap"):
                self._on_key(self.window, code, 0, glfw.RELEASE, mods)
        elif kind == "mouse_move":
            self._on_cursor(self.window, float(d["x"]), float(d["y"]))
        elif kind == "mouse_button":
            button = getattr(glfw, f"MOUSE_BUTTON_{d['button'].upper()}")
            self._on_button(self.window, button,
                            glfw.PRESS if d["action"] == "press" else glfw.RELEASE, 0)
        elif kind == "scroll":
            self._on_scroll(self.window, 0.0, float(d["dy"]))
        elif kind == "resize":
            if self.window is None:  # offscreen: the "framebuffer" is what the script says
                self.fb_size = (int(d["width"]), int(d["height"]))
            else:
                glfw.set_window_size(self.window, d["width"], d["height"])
        elif kind == "minimize":
            # With no window manager (Xvfb) iconify does nothing; the flag makes the loop
            # behave as for a real zero-sized framebuffer.
            if self.window is not None:
                glfw.iconify_window(self.window)
            self.script_minimized = True
        elif kind == "restore":
            if self.window is not None:
                glfw.restore_window(self.window)
            self.script_minimized = False
        elif kind == "screenshot":
            self.pending_shots.append(Path(d["path"]))
        elif kind == "print_camera":
            self.print_camera()
        elif kind == "quit":
            self.quit = True

    def _update(self, dt: float) -> None:
        h, key = self.held, glfw
        axis = lambda pos, neg: float(pos in h) - float(neg in h)  # noqa: E731
        f, r, u = axis(key.KEY_W, key.KEY_S), axis(key.KEY_D, key.KEY_A), axis(key.KEY_E, key.KEY_Q)
        if f or r or u:
            self.fly.move(dt, f, r, u, self._speed_multiplier())
        lf, lr = axis(key.KEY_UP, key.KEY_DOWN), axis(key.KEY_RIGHT, key.KEY_LEFT)
        lu = axis(key.KEY_PAGE_UP, key.KEY_PAGE_DOWN)
        p = self.light.position
        if lf or lr or lu:
            step = self.fly.speed * self._speed_multiplier() * dt
            fw, rt, up = self.fly.forward(), self.fly.right(), self.fly.up
            flat = _normalize(tuple(fw[i] - up[i] * sum(fw[j] * up[j] for j in range(3))
                                    for i in range(3)))
            p = tuple(p[i] + step * (lf * flat[i] + lr * rt[i] + lu * up[i]) for i in range(3))
        if self.animate_light:
            p = _rotate_about(p, self.centre, self.fly.up, LIGHT_ORBIT_RAD_PER_S * dt)
        if p is not self.light.position:
            li = self.light  # positional construction: dataclasses.replace costs ~10x more
            self.light = Light((float(p[0]), float(p[1]), float(p[2])), li.color, li.intensity,
                               li.falloff, li.range)


def _normalize(v: tuple[float, ...]) -> tuple[float, ...]:
    n = math.sqrt(sum(x * x for x in v)) or 1.0
    return tuple(x / n for x in v)


def _rotate_about(p: tuple, centre: tuple, axis: tuple, angle: float) -> tuple:
    """Rodrigues' rotation of point p about the line through `centre` along unit `axis`."""
    v = [p[i] - centre[i] for i in range(3)]
    c, s = math.cos(angle), math.sin(angle)
    k = axis
    kxv = (k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0])
    kdv = sum(k[i] * v[i] for i in range(3))
    return tuple(centre[i] + v[i] * c + kxv[i] * s + k[i] * kdv * (1 - c) for i in range(3))
