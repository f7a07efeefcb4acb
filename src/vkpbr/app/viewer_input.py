"""Input for the viewer: GLFW callbacks and script replay share these handlers, so a
replayed script drives exactly the code a person does. A mixin of `Viewer` (app/viewer.py),
split out to keep each file short. The key bindings are the table in app/keys.py: `_on_key`
dispatches press actions from it to the `_act_<action>` methods below, `_update` and
`_speed_multiplier` read its held actions (fly, move_light, speed).
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path
from typing import Any

import glfw

from vkpbr.app import keys as K
from vkpbr.app.script import Event, key_code, mods_bits
from vkpbr.scene.types import Light

__all__ = ["InputHandlers", "LIGHT_ORBIT_RAD_PER_S", "key_map"]

LIGHT_ORBIT_RAD_PER_S = 0.6

# key code -> {(shift, ctrl): (action, arg, repeat)}; built on first use (GLFW codes)
_KEY_MAP: dict[int, dict[tuple[bool, bool], tuple[str, Any, bool]]] = {}
_HELD: dict[str, tuple[tuple[int, Any], ...]] = {}


def key_map() -> dict[int, dict[tuple[bool, bool], tuple[str, Any, bool]]]:
    """The press actions of app/keys.py by GLFW key code and (shift, ctrl); a chord bound
    twice is an error in the table."""
    if not _KEY_MAP:
        table: dict[int, dict[tuple[bool, bool], tuple[str, Any, bool]]] = {}
        for c in K.chords(K.PRESS_ACTIONS):
            entry = table.setdefault(key_code(c.name, f"keys.py: {c.key}"), {})
            if (c.shift, c.ctrl) in entry:
                raise ValueError(f"keys.py: {c.key} is bound twice")
            entry[(c.shift, c.ctrl)] = (c.action, c.arg, c.repeat)
        for action in K.HELD_ACTIONS:
            _HELD[action] = tuple((key_code(c.name), c.arg) for c in K.chords((action,)))
        _KEY_MAP.update(table)
    return _KEY_MAP


def _held() -> dict[str, tuple[tuple[int, Any], ...]]:
    """Held actions: action -> ((key code, arg), ...)."""
    if not _HELD:
        key_map()
    return _HELD


def _lookup(key: int, mods: int) -> tuple[str, Any, bool] | None:
    entry = key_map().get(key)
    if entry is None:
        return None
    if len(entry) == 1 and (False, False) in entry:  # a plain key: modifiers do not matter
        return entry[(False, False)]
    return entry.get((bool(mods & glfw.MOD_SHIFT), bool(mods & glfw.MOD_CONTROL)))


class InputHandlers:
    """Key, mouse and script handlers; expects the Viewer's state attributes (fly, light,
    options, held, buttons, cursor, target, ...)."""

    fly: Any
    light: Any
    options: Any
    target: Any  # the frame target drawn into (its extent)
    window: Any
    renderer: Any  # the Viewer's Renderer (automatic_sun)
    env_choices: tuple[str, ...]  # what K cycles through

    # --- input ------------------------------------------------------------------------------
    def _on_key(self, _w: Any, key: int, _scancode: int, action: int, mods: int) -> None:
        if action == glfw.RELEASE:
            self.held.discard(key)
            return
        if action == glfw.PRESS:
            self.held.add(key)
        hit = _lookup(key, mods)
        if hit is None:
            return
        name, arg, repeat = hit
        if action != glfw.PRESS and not repeat:
            return  # auto-repeat only for the mode switches
        getattr(self, f"_act_{name}")(arg)
        self._hud_dirty = True

    # --- press actions (app/keys.py PRESS_ACTIONS) ------------------------------------------
    def _act_quit(self, _arg: None) -> None:
        self.quit = True

    def _act_view(self, index: int) -> None:
        view = K.view_at(index)
        if view is not None:
            self.options = K.with_view(self.options, view)

    def _act_cycle(self, arg: tuple[str, int]) -> None:
        self.options = K.cycle(self.options, *arg)

    def _act_toggle(self, field: str) -> None:
        self.options = K.toggle(self.options, field)

    def _act_exposure(self, step: float) -> None:
        lo, hi = K.EXPOSURE_RANGE
        o = self.options
        self.options = dataclasses.replace(o, exposure=max(lo, min(hi, o.exposure + step)))

    def _act_environment(self, step: int) -> None:
        self.options = K.next_env(self.options, self.env_choices, step)

    def _act_env_rotation(self, degrees: float) -> None:
        old = self.options
        self.options = K.turn_env(old, degrees)
        sun = self.renderer.automatic_sun  # the automatic sun turns with the sky
        if self.lights == (sun(old.env_rotation),):
            self.lights = (sun(self.options.env_rotation),)

    def _act_fov(self, step: float) -> None:
        self.fly.zoom(step)

    def _act_animate_light(self, _arg: None) -> None:
        self.animate_light = not self.animate_light

    def _act_play(self, _arg: None) -> None:
        self.playback.toggle()

    def _act_next_animation(self, step: int) -> None:
        self.playback.next(step)

    def _act_animation_speed(self, step: int) -> None:
        self.playback.faster(step)

    @property
    def light(self) -> Light | None:
        """The light the keys move: the first of the frame's lights (None without any)."""
        return self.lights[0] if self.lights else None

    @light.setter
    def light(self, value: Light) -> None:
        self.lights = (value, *self.lights[1:]) if self.lights else ()

    def _act_light_to_camera(self, _arg: None) -> None:
        if self.light is not None:
            self.light = dataclasses.replace(self.light, position=self.fly.eye)

    def _act_reset(self, _arg: None) -> None:
        self.fly.reset()
        self.lights = self.start_lights

    def _act_print_camera(self, _arg: None) -> None:
        self.print_camera()

    def _act_screenshot(self, _arg: None) -> None:
        self.pending_shots.append(Path(time.strftime("vkpbr-%Y%m%d-%H%M%S")
                                       + f"-{self.frame_count}.png"))

    def _act_toggle_help(self, _arg: None) -> None:
        self.show_help = not self.show_help

    def _act_toggle_hud(self, _arg: None) -> None:
        self.show_hud = not self.show_hud

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
                self.fly.pan(dx, dy, self.target.extent[1] or 1)
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
        h, m = self.held, 1.0
        seen: set[float] = set()
        for code, factor in _held()["speed"]:  # left and right Shift held: still x5 once
            if code in h and factor not in seen:
                seen.add(factor)
                m *= factor
        return m

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
        elif kind == "time":  # the animation's time (docs/viewer.md)
            self.playback.seek(float(d["seconds"]))
            if "play" in d:
                self.playback.playing = bool(d["play"]) and bool(self.playback.names)
        elif kind == "quit":
            self.quit = True

    def _update(self, dt: float) -> None:
        posed = self.playback.advance(dt)
        if posed is not None:
            self.renderer.set_time(posed, self.playback.animation)
            self._hud_dirty = True
        h = self.held
        fly, lm = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]  # (forward, right, up) from held keys
        if h:
            held = _held()
            for code, (axis, sign) in held["fly"]:
                if code in h:
                    fly[axis] += sign
            for code, (axis, sign) in held["move_light"]:
                if code in h:
                    lm[axis] += sign
        f, r, u = fly
        if f or r or u:
            self.fly.move(dt, f, r, u, self._speed_multiplier())
        lf, lr, lu = lm
        if self.light is None:
            return
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
            self.light = dataclasses.replace(self.light, position=(float(p[0]), float(p[1]), float(p[2])))


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
