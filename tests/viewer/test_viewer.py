# The interactive viewer under Xvfb on lavapipe, validation on: a replayed script drives the
# camera (both schemes) and every switch, resizes and minimises the window, takes a
# screenshot; the screenshot must equal Renderer.render of the same camera, light, size and
# modes exactly (tolerance 0: the same pipelines write the same sRGB bytes).
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from vkpbr.app.script import parse_script
from vkpbr.render.options import RenderOptions

SIZE = (160, 120)


def _key(t: float, key: str, action: str = "tap", mods: tuple[str, ...] = ()) -> dict:
    return {"t": t, "type": "key", "key": key, "action": action, "mods": list(mods)}


def _every_switch(t0: float) -> list[dict]:
    """Every mode key once (views by digit, Shift+digit, Ctrl+digit and cycling)."""
    events = [_key(t0, str(d)) for d in "1234567890"]
    events += [_key(t0, str(d), mods=("shift",)) for d in "1234567890"]
    events += [_key(t0, "1", mods=("ctrl",)), _key(t0, "v"), _key(t0, "v", mods=("shift",))]
    events += [_key(t0, k) for k in ("b", "t", "m", "n", "o", "x", "equal", "minus", "h", "f2", "f2",
                                     "right_bracket", "right_bracket", "left_bracket")]
    return events


def _script(shot: Path) -> dict:
    ev = [
        _key(0.0, "w", "press"), _key(0.15, "w", "release"),  # course scheme: fly
        _key(0.15, "left_shift", "press"), _key(0.15, "d", "press"),
        _key(0.25, "d", "release"), _key(0.25, "left_shift", "release"),
        _key(0.25, "e", "press"), _key(0.3, "e", "release"),
        {"t": 0.3, "type": "mouse_move", "x": 80, "y": 60},  # report scheme: left drag looks
        {"t": 0.3, "type": "mouse_button", "button": "left", "action": "press"},
        {"t": 0.35, "type": "mouse_move", "x": 90, "y": 58},
        {"t": 0.35, "type": "mouse_button", "button": "left", "action": "release"},
        {"t": 0.4, "type": "mouse_button", "button": "right", "action": "press"},  # pan
        {"t": 0.45, "type": "mouse_move", "x": 84, "y": 62},
        {"t": 0.45, "type": "mouse_button", "button": "right", "action": "release"},
        {"t": 0.5, "type": "scroll", "dy": -1.0},
        {"t": 0.5, "type": "mouse_button", "button": "middle", "action": "press"},
        {"t": 0.5, "type": "mouse_button", "button": "middle", "action": "release"},
        {"t": 0.55, "type": "mouse_move", "x": 86, "y": 62},  # cursor hidden: mouse looks
        {"t": 0.55, "type": "mouse_button", "button": "middle", "action": "press"},
        {"t": 0.55, "type": "mouse_button", "button": "middle", "action": "release"},
        *_every_switch(0.6),
        _key(0.65, "space"), _key(0.65, "up", "press"), _key(0.75, "up", "release"),
        _key(0.75, "page_up", "press"), _key(0.8, "page_up", "release"),
        {"t": 0.8, "type": "resize", "width": 176, "height": 132},
        {"t": 1.0, "type": "minimize"},
        {"t": 1.2, "type": "restore"},
        {"t": 1.2, "type": "print_camera"},
        _key(1.25, "2"),  # end in a non-default state: view D (with Blinn-Phong from above)
        {"t": 1.35, "type": "screenshot", "path": str(shot)},
        {"t": 1.45, "type": "quit"},
    ]
    return {"fixed_dt": 0.05, "events": ev}


@pytest.mark.parametrize("offscreen", [False, True], ids=["window", "offscreen"])
def test_scripted_session_matches_headless(offscreen: bool, request, tmp_path: Path,
                                           capsys) -> None:
    """The whole script in a window under Xvfb, and again with --offscreen (no window: the
    loop that measures the viewer on a GPU server must behave the same)."""
    from vkpbr.app.viewer import Viewer, ViewerConfig

    if not offscreen:
        request.getfixturevalue("display")
    shot = tmp_path / "shot.png"
    # The course's lighting: its BRDF and tone-map cycles start from ggx and none.
    config = ViewerConfig(size=SIZE, validation=True, vsync=True, offscreen=offscreen,
                          script=parse_script(_script(shot)),
                          options=RenderOptions(lighting="course"))
    viewer = Viewer(None, config)
    instance = viewer.renderer.device.instance
    try:
        start = viewer.camera()
        assert viewer.run() == 0
        assert shot.is_file() and viewer.shots_written == [shot]
        assert viewer.resizes >= 1  # the resize recreated the target
        assert viewer.target.extent == (176, 132)
        assert viewer.minimized_waits >= 3  # no frames while minimised
        assert viewer.camera().eye != start.eye
        assert viewer.camera().yfov_deg == start.yfov_deg + 5.0  # ] ] [
        assert viewer.animate_light
        o = viewer.options
        assert tuple(map(str, (o.view, o.brdf, o.tbn, o.tonemap))) == ("d", "blinn-phong", "quat", "reinhard")
        assert (o.alpha_mask, o.normal_mapping, o.occlusion, o.exposure) == (False, False, False, 0.0)
        assert "vkpbr render" in capsys.readouterr().out  # the print-camera event
        image, camera, light, options, size = viewer.last_screenshot
        if not offscreen:  # (a window's frames take the fragment path, whatever auto takes)
            options = dataclasses.replace(options, pipeline="forward")
        headless = viewer.renderer.render(camera, light, size, options)
        assert image.shape == headless.shape == (132, 176, 4)
        diff = np.abs(image.astype(int) - headless.astype(int))
        assert diff.max() == 0, f"max diff {diff.max()}, {np.count_nonzero(diff)} values"
        from PIL import Image

        assert np.array_equal(np.asarray(Image.open(shot)), image)
        assert (viewer.present_mode == "offscreen") == offscreen
    finally:
        viewer.close()
    assert instance.errors == [], instance.errors[:3]


def test_cli_frames_screenshot_matches_render(display: str, tmp_path: Path) -> None:
    from PIL import Image

    from vkpbr.app.cli import main

    cam = "0.8,2.9,7.5,0.3,2.0,0.0"
    # The final image with GTAO (render/ao.py): the window draws it through its own depth
    # pre-pass (paths.py forward_ao), `render` through its visibility pass: the same pixels
    # (both the fragment path: a window's frames take it, whatever auto takes offscreen).
    modes = ["--tbn", "packed", "--no-occlusion", "--ao", "gtao"]
    assert main(["view", "--size", "96x72", "--camera", cam, "--frames", "3", "--no-vsync",
                 "--screenshot", str(tmp_path / "v.png"), "--validation", *modes]) == 0
    assert main(["render", "--size", "96x72", "--camera", cam, "--out", str(tmp_path / "r.png"),
                 "--validation", "--pipeline", "forward", *modes]) == 0
    v = np.asarray(Image.open(tmp_path / "v.png"))
    r = np.asarray(Image.open(tmp_path / "r.png"))
    assert np.array_equal(v, r)


def test_window_with_bloom_matches_render(display: str, tmp_path: Path) -> None:
    """A window's frame with a post step: the HDR image encoded by a fragment pass into the
    swapchain image (render/post_stage.py), against `render`'s compute encode: within 1/255
    (the attachment's sRGB encoding against the kernel's)."""
    from PIL import Image

    from vkpbr.app.cli import main

    cam = "0.8,2.9,7.5,0.3,2.0,0.0"
    assert main(["view", "--size", "96x72", "--camera", cam, "--frames", "3", "--no-vsync",
                 "--screenshot", str(tmp_path / "v.png"), "--validation", "--bloom", "0.4"]) == 0
    assert main(["render", "--size", "96x72", "--camera", cam, "--out", str(tmp_path / "r.png"),
                 "--validation", "--bloom", "0.4"]) == 0
    plain = tmp_path / "p.png"
    assert main(["render", "--size", "96x72", "--camera", cam, "--out", str(plain)]) == 0
    v = np.asarray(Image.open(tmp_path / "v.png")).astype(int)
    r = np.asarray(Image.open(tmp_path / "r.png")).astype(int)
    assert np.abs(v - r).max() <= 1
    assert np.abs(v - np.asarray(Image.open(plain)).astype(int)).max() > 1  # it did bloom


def test_hud_is_drawn_and_fits(display: str, tmp_path: Path) -> None:
    from vkpbr.app.viewer import Viewer, ViewerConfig

    config = ViewerConfig(size=(320, 200), validation=True, frames=2, vsync=False,
                          screenshot=tmp_path / "hud.png")
    with Viewer(None, config) as viewer:
        viewer.shot_hud = True
        viewer.run()
        with_hud = viewer.last_screenshot[0]
        _, camera, light, options, size = viewer.last_screenshot
        plain = viewer.renderer.render(camera, light, size, options)
        assert viewer.renderer.device.instance.errors == []
    changed = np.any(with_hud != plain, axis=2)
    ys, xs = np.nonzero(changed)
    assert changed.mean() > 0.02  # text and its panel
    assert ys.min() < 20 and xs.min() < 20  # the stats block sits top-left


def test_script_file_and_errors(display: str, tmp_path: Path) -> None:
    from vkpbr.app.cli import main

    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps([{"t": 0, "type": "key", "key": "no-such-key"}]))
    assert main(["view", "--script", str(bad)]) == 2
    good = tmp_path / "s.json"
    good.write_text(json.dumps({"fixed_dt": 0.1, "events": [
        _key(0.0, "t"), {"t": 0.1, "type": "quit"}]}))
    assert main(["view", "--size", "64x48", "--script", str(good), "--validation"]) == 0


def test_offscreen_cli(tmp_path: Path, capsys) -> None:
    """`vkpbr view --offscreen` needs no display: it runs N frames, writes the screenshot and
    reports the frame rate; without --frames or --script it refuses to start."""
    from vkpbr.app.cli import main

    shot = tmp_path / "off.png"
    assert main(["view", "--offscreen", "--frames", "4", "--size", "64x48",
                 "--screenshot", str(shot), "--validation"]) == 0
    out = capsys.readouterr().out
    assert shot.is_file() and "4 frames" in out and "fps (64x48, offscreen)" in out
    assert main(["view", "--offscreen"]) == 2
    assert "--offscreen needs --frames" in capsys.readouterr().err


def test_speed_scales_with_scene() -> None:
    from vkpbr.app.controls import BASE_SPEED, SPONZA_RADIUS, FlyCamera
    from vkpbr.scene.types import Camera

    cam = Camera(eye=(0.0, 1.0, 5.0), target=(0.0, 1.0, 0.0))
    fly = FlyCamera(cam, SPONZA_RADIUS)
    assert fly.speed == pytest.approx(BASE_SPEED)
    assert fly.camera().target == pytest.approx(cam.target)
    fly.move(1.0, 1.0, 0.0, 0.0, 5.0)  # Shift: five times faster, along the view
    assert fly.eye == pytest.approx((0.0, 1.0, 5.0 - 5 * BASE_SPEED))
    fly.reset()
    fly.look(10, 0)  # 10 px right: turn right by 0.1 rad
    f = fly.forward()
    assert f[0] == pytest.approx(np.sin(0.1)) and f[2] == pytest.approx(-np.cos(0.1))
    small = FlyCamera(dataclasses.replace(cam), SPONZA_RADIUS / 10)
    assert small.speed == pytest.approx(BASE_SPEED / 10)


def test_environment_keys(tmp_path: Path) -> None:
    """I cycles sky -> none -> sky, `.` turns the environment and the automatic sun with it;
    the HUD names the environment; the screenshot equals Renderer.render of the same state."""
    from vkpbr.app.viewer import Viewer, ViewerConfig

    shot = tmp_path / "env.png"
    events = [_key(0.0, "i"), _key(0.05, "i"), _key(0.1, "i", mods=("shift",)),
              _key(0.15, "i"), _key(0.2, "period"), _key(0.2, "period"), _key(0.25, "comma"),
              _key(0.25, "period"), {"t": 0.3, "type": "screenshot", "path": str(shot)},
              {"t": 0.35, "type": "quit"}]
    config = ViewerConfig(size=(64, 48), validation=True, offscreen=True,
                          script=parse_script({"fixed_dt": 0.05, "events": events}))
    from vkpbr.scene.default import default_scene

    scene = default_scene()
    scene.lights = []  # the automatic sun lights it
    viewer = Viewer(scene, config)
    instance = viewer.renderer.device.instance
    try:
        assert viewer.run() == 0
        o = viewer.options
        assert (o.env, o.env_rotation) == ("sky", 30.0)
        assert viewer.lights == (viewer.renderer.automatic_sun(30.0),)
        hud = "\n".join(line for b in viewer._hud_blocks() for line in b.lines)
        assert "env sky +30 deg" in hud
        image, camera, lights, options, size = viewer.last_screenshot
        headless = viewer.renderer.render(camera, lights, size, options)
        assert np.array_equal(image, headless)
    finally:
        viewer.close()
    assert instance.errors == [], instance.errors[:3]


def test_pipeline_key_takes_the_compute_path_offscreen(tmp_path: Path) -> None:
    """U cycles auto -> forward -> compute; the offscreen viewer then draws through the compute
    path (the HUD says so) and its screenshot equals Renderer.render with that path."""
    from vkpbr.app.viewer import Viewer, ViewerConfig

    shot = tmp_path / "compute.png"
    events = [_key(0.0, "u"), _key(0.05, "u"), {"t": 0.1, "type": "screenshot", "path": str(shot)},
              {"t": 0.15, "type": "quit"}]
    config = ViewerConfig(size=(64, 48), validation=True, offscreen=True,
                          script=parse_script({"fixed_dt": 0.05, "events": events}))
    viewer = Viewer(None, config)
    instance = viewer.renderer.device.instance
    try:
        if not viewer.renderer.device.compute_path:
            pytest.skip(f"{viewer.renderer.device.info.name} lacks the compute path's features")
        assert viewer.run() == 0
        assert str(viewer.options.pipeline) == "compute"
        hud = "\n".join(line for b in viewer._hud_blocks() for line in b.lines)
        assert "path compute" in hud
        image, camera, lights, options, size = viewer.last_screenshot
        assert np.array_equal(image, viewer.renderer.render(camera, lights, size, options))
    finally:
        viewer.close()
    assert instance.errors == [], instance.errors[:3]


def test_animation_playback_keys(tmp_path: Path, assets: Path) -> None:
    """The viewer plays a glTF animation: J pauses it, ' doubles the speed, Y picks one by
    name, a script's "time" event seeks; the screenshot equals Renderer.render at the time
    the HUD shows."""
    from vkpbr.app.viewer import Viewer, ViewerConfig
    from vkpbr.scene.loader import load_scene

    path = assets / "BoxAnimated" / "glTF" / "BoxAnimated.gltf"
    if not path.is_file():
        pytest.skip(f"{path} not in the assets")
    shot = tmp_path / "anim.png"
    events = [_key(0.2, "apostrophe"), _key(0.4, "j"), _key(0.45, "y"),
              {"t": 0.5, "type": "time", "seconds": 2.0},
              {"t": 0.6, "type": "screenshot", "path": str(shot)}, {"t": 0.65, "type": "quit"}]
    from vkpbr.scene.types import Camera

    config = ViewerConfig(size=(64, 48), validation=True, offscreen=True,
                          camera=Camera(eye=(2.0, 3.0, 9.0), target=(0.0, 1.2, 0.0)),
                          script=parse_script({"fixed_dt": 0.05, "events": events}))
    viewer = Viewer(load_scene(path), config)
    instance = viewer.renderer.device.instance
    try:
        assert viewer.run() == 0
        pb = viewer.playback
        assert (pb.playing, pb.speed, pb.index, pb.time) == (False, 2.0, 0, 2.0)
        hud = "\n".join(line for b in viewer._hud_blocks() for line in b.lines)
        assert "2.00 /" in hud and "paused" in hud and "x2" in hud
        image, camera, lights, options, size = viewer.last_screenshot
        headless = viewer.renderer.render(camera, lights, size, options, time=2.0, animation=0)
        assert np.array_equal(image, headless)
        still = viewer.renderer.render(camera, lights, size, options, time=0.0)
        assert not np.array_equal(image, still)
    finally:
        viewer.close()
    assert instance.errors == [], instance.errors[:3]
