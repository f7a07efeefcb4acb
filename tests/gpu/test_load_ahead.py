"""A scene loaded on a thread while the device is made (vkpbr.bake.ahead, issue 32's load
time): it renders what the same file loaded first renders, bit for bit, through the bake cache
too (a cold cache, a warm one, a broken cache file baked again); its decoded images are used
(decoded once); a load that fails is the loader's one-line error, with nothing left behind."""

from __future__ import annotations

from concurrent.futures import Future
from pathlib import Path

import numpy as np
import pytest

from vkpbr.bake.ahead import load_ahead
from vkpbr.errors import VkpbrError
from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene

SIZE = (48, 32)


@pytest.fixture
def model(assets: Path) -> Path:
    path = assets / "TextureCoordinateTest" / "glTF" / "TextureCoordinateTest.gltf"
    if not path.is_file():
        pytest.skip(f"{path} not in the assets")
    return path


def test_loaded_ahead_renders_what_loaded_first_renders(make_renderer, model: Path,  # noqa: ANN001
                                                        tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    import vkpbr.scene.textures as textures

    decodes = []
    decode = textures.decode_images
    monkeypatch.setattr(textures, "decode_images", lambda *a, **k: decodes.append(1) or decode(*a, **k))
    ahead = load_ahead(model)
    renderer = make_renderer(ahead)
    got = renderer.render(size=SIZE)
    assert len(decodes) == 1 and ahead.decoded is None  # decoded once, ahead; not kept
    assert renderer.timings["load_wait"] >= 0.0
    first = Future()  # any Future of a Scene is taken (loaded first here: decoded at upload)
    first.set_result(load_scene(model))
    renderer.set_scene(first)
    np.testing.assert_array_equal(got, renderer.render(size=SIZE))
    assert len(decodes) == 2
    cache = tmp_path / "cache"
    frames = []
    for _ in range(3):  # the bake (a cold cache), a warm cache, a broken cache file
        renderer.set_scene(load_ahead(model, cache))
        frames.append(renderer.render(size=SIZE))
        baked = next(cache.glob("*.vkpbr"))
        baked.write_bytes(baked.read_bytes()[:-64])
    for frame in frames[1:]:
        np.testing.assert_array_equal(frames[0], frame)
    assert len(list(cache.glob("*.vkpbr"))) == 1


def test_a_load_that_fails_is_the_loaders_error(tmp_path: Path) -> None:
    missing = tmp_path / "missing.gltf"
    with pytest.raises(VkpbrError) as ahead:
        Renderer(load_ahead(missing))
    with pytest.raises(VkpbrError) as first:
        load_scene(missing)
    assert str(ahead.value) == str(first.value) and "\n" not in str(ahead.value)
