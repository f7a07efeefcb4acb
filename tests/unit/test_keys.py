"""The viewer's one key table: the handlers dispatch from it, the help panel and
docs/viewer.md come from it (no window: the handlers run on a stub viewer)."""

from __future__ import annotations

import math
from pathlib import Path

import glfw
import pytest

from vkpbr.app import keys as K
from vkpbr.app.controls import FAST, FlyCamera
from vkpbr.app.playback import Playback
from vkpbr.app.viewer_input import InputHandlers, key_map
from vkpbr.render.layouts import Brdf, Tonemap, View
from vkpbr.render.options import RenderOptions
from vkpbr.scene.types import Camera, Light

DOCS = Path(__file__).resolve().parents[2] / "docs" / "viewer.md"


def test_docs_key_table_is_generated_from_the_table() -> None:
    text = DOCS.read_text()
    assert K.update_markdown(text) == text, (
        "docs/viewer.md's key table is stale: run `python -m vkpbr.app.keys --update docs/viewer.md`")


def test_help_panel_is_the_table() -> None:
    assert tuple((b.label, b.help) for b in K.BINDINGS) == K.HELP
    assert all(b.label and b.help for b in K.BINDINGS)
    assert "| Esc | quit |" in K.markdown_table()


def test_every_chord_has_a_handler_and_a_key() -> None:
    table = key_map()  # also raises on a chord bound twice and on unknown key names
    for chord in K.chords(K.PRESS_ACTIONS + K.HELD_ACTIONS):
        assert chord.action in K.PRESS_ACTIONS + K.HELD_ACTIONS
        if chord.action in K.PRESS_ACTIONS:
            assert callable(getattr(InputHandlers, f"_act_{chord.action}", None)), chord
    assert {c.action for c in K.chords(K.PRESS_ACTIONS)} == set(K.PRESS_ACTIONS)
    n_press = len(K.chords(K.PRESS_ACTIONS))
    assert sum(len(entry) for entry in table.values()) == n_press


def test_every_view_has_a_key() -> None:
    views = {K.view_at(c.arg) for c in K.chords(("view",))}
    assert views == set(View)


class Stub(InputHandlers):
    """The attributes the handlers use, as Viewer sets them."""

    def __init__(self) -> None:
        self.options = RenderOptions(lighting="course")  # brdf ggx, tonemap none
        self.fly = FlyCamera(Camera(eye=(0.0, 1.0, 5.0), target=(0.0, 1.0, 0.0)), 18.5)
        self.start_lights = self.lights = (Light(position=(0.0, 2.0, 0.0)),)
        self.held: set[int] = set()
        self.quit = self.animate_light = False
        self.show_help = self.show_hud = True
        self.pending_shots: list[Path] = []
        self.frame_count = 0
        self.printed = 0
        self.centre = (0.0, 0.0, 0.0)
        self._hud_dirty = False
        self.playback = Playback(None)  # a scene without animations: nothing to play

    def print_camera(self) -> None:
        self.printed += 1

    def press(self, key: int, mods: int = 0, action: int = glfw.PRESS) -> None:
        self._on_key(None, key, 0, action, mods)


@pytest.mark.parametrize("digit", range(10))
def test_digits_select_views(digit: int) -> None:
    s = Stub()
    index = (digit - 1) % 10  # 1 -> 0 (final), ..., 0 -> 9
    s.press(glfw.KEY_0 + digit)
    assert s.options.view == View(index) and s._hud_dirty
    s.press(glfw.KEY_0 + digit, glfw.MOD_SHIFT)
    assert s.options.view == View(10 + index)
    s.press(glfw.KEY_0 + digit, glfw.MOD_CONTROL)
    last = max(View)  # Ctrl+digit: views 20.., where there are that many
    assert s.options.view == (View(20 + index) if 20 + index <= last else View(10 + index))


def test_modes_and_modifiers() -> None:
    s = Stub()
    s.press(glfw.KEY_V)
    assert s.options.view == View.D
    s.press(glfw.KEY_V, glfw.MOD_SHIFT)
    s.press(glfw.KEY_V, glfw.MOD_SHIFT)
    assert s.options.view == max(View)  # previous, wrapping round
    s.press(glfw.KEY_B, glfw.MOD_SHIFT)  # a plain key ignores Shift
    assert s.options.brdf == Brdf.BLINN_PHONG
    s.press(glfw.KEY_X)
    assert s.options.tonemap == Tonemap.REINHARD
    for _ in range(40):  # = with auto-repeat: +0.5 EV each, clamped
        s.press(glfw.KEY_EQUAL, action=glfw.REPEAT)
    assert s.options.exposure == K.EXPOSURE_RANGE[1]
    s.press(glfw.KEY_KP_SUBTRACT)
    assert s.options.exposure == K.EXPOSURE_RANGE[1] - 0.5
    s.press(glfw.KEY_M)
    s.press(glfw.KEY_O)
    assert (s.options.alpha_mask, s.options.normal_mapping, s.options.occlusion) == (False, True, False)
    s.press(glfw.KEY_K)
    assert s.options.shadows is False
    fov = s.fly.yfov_deg
    s.press(glfw.KEY_RIGHT_BRACKET)
    assert s.fly.yfov_deg == fov + 5.0


def test_toggles_do_not_auto_repeat() -> None:
    s = Stub()
    s.press(glfw.KEY_SPACE)
    s.press(glfw.KEY_SPACE, action=glfw.REPEAT)
    s.press(glfw.KEY_C)
    s.press(glfw.KEY_C, action=glfw.REPEAT)
    s.press(glfw.KEY_F12)
    s.press(glfw.KEY_H)
    s.press(glfw.KEY_F2)
    assert s.animate_light and s.printed == 1 and len(s.pending_shots) == 1
    assert not s.show_help and not s.show_hud
    s.press(glfw.KEY_ESCAPE)
    assert s.quit


def test_held_keys_fly_and_move_the_light() -> None:
    s = Stub()
    s.press(glfw.KEY_W)
    s.press(glfw.KEY_LEFT_SHIFT)
    s.press(glfw.KEY_RIGHT_SHIFT)  # both Shifts: still x5 once
    s._update(0.5)
    speed = s.fly.speed
    assert s.fly.eye == pytest.approx((0.0, 1.0, 5.0 - 0.5 * speed * FAST))
    s.press(glfw.KEY_W, action=glfw.RELEASE)
    s.press(glfw.KEY_LEFT_SHIFT, action=glfw.RELEASE)
    s.press(glfw.KEY_RIGHT_SHIFT, action=glfw.RELEASE)
    s.press(glfw.KEY_PAGE_UP)
    s.press(glfw.KEY_RIGHT)
    s._update(1.0)
    x, y, z = s.light.position
    assert (x, y, z) == pytest.approx((speed, 2.0 + speed, 0.0))  # right = +x, up = +y
    assert math.isclose(s.fly.eye[2], 5.0 - 0.5 * speed * FAST)  # the camera stayed put
    s.press(glfw.KEY_R)
    assert s.lights is s.start_lights and s.fly.eye == (0.0, 1.0, 5.0)
