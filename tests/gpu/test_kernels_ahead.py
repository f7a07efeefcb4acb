"""A GPU's first frame's kernels are compiled while the scene uploads (render/kernels_ahead.py,
issue 32's cold start): what is made ahead is exactly what a first frame of the compute path
with its rasteriser and compute-drawn shadow maps binds (the compute path's, the shadow
rasteriser's and GTAO's kernels, each shading specialisation), so that frame compiles none
of them itself and nothing made ahead is wasted. On lavapipe it is off unless
VKPBR_KERNELS_AHEAD=1 (auto takes the forward path on CPUs); the tests turn it on."""

from __future__ import annotations

import collections

import numpy as np
import pytest

from vkpbr.render.options import RenderOptions

SIZE = (48, 40)
COMPUTE = dict(pipeline="compute", raster="compute", shadow_raster="compute")
# The kernel families made ahead (the sky's five are made apart, at once, with the environment)
FAMILIES = ("raster_", "classify_", "shade_", "background_", "shadow_", "ao_")


def _builds(renderer, start: int = 0) -> list[tuple[str, str]]:  # noqa: ANN001
    """(shaders, thread) of the pipelines the renderer's device built from build `start` on."""
    return [(name, thread) for name, _, _, _, thread
            in renderer.device.pipeline_cache.stats.builds[start:]]


def _frame_kernels(renderer) -> collections.Counter:  # noqa: ANN001
    """The SPIR-V names of the kernels the frames so far bound from FAMILIES (one a
    specialisation), from their owners: the compute scene, the shadow rasteriser, GTAO."""
    parts = renderer.parts
    names = [f"{name}.comp.spv" for name, _ in parts.compute.made._pipelines]
    raster = parts.shadow_frames.maps._raster
    names += [f"shadow_{name}.comp.spv" for name in (raster._pipelines if raster else {})]
    names += [f"{name}.comp.spv" for name in parts.ao._kernels]
    return collections.Counter(n for n in names if n.startswith(FAMILIES))


@pytest.mark.parametrize("scene", ["chart", "AlphaBlendModeTest", "DamagedHelmet", "CesiumMan"])
def test_the_kernels_made_ahead_are_the_first_frames(monkeypatch, make_renderer, sample_scene,  # noqa: ANN001
                                                     scene: str) -> None:
    monkeypatch.setenv("VKPBR_KERNELS_AHEAD", "1")
    r = make_renderer(None if scene == "chart" else sample_scene(scene))
    r.device.wait_background()
    built = _builds(r)  # (the set-up's own: a skinned scene's deform kernel)
    made = collections.Counter(name for name, t in built if t.startswith("vkpbr-ahead"))
    assert made["shade_vectors.comp.spv"] >= 1 and made["raster_small.comp.spv"] == 1, made
    masked = any(m.alpha_mode == "mask" for m in r.scene.materials)
    assert made["raster_masked.comp.spv"] == made["shadow_masked.comp.spv"] == masked, made
    start = len(built)
    r.environments.get(RenderOptions())  # (the sky's kernels: not guessed ahead)
    image = np.asarray(r.render(size=SIZE, **COMPUTE))
    assert image.std() > 0
    own = [name for name, _ in _builds(r, start) if name.startswith(FAMILIES)]
    assert own == [], f"the first frame compiled kernels the guess missed: {own}"
    assert _frame_kernels(r) == made, "made ahead, never bound (or bound, never made ahead)"


def test_a_renderer_closed_while_its_kernels_compile(monkeypatch, make_renderer) -> None:  # noqa: ANN001
    """Closing waits for the kernels in flight (none is in a Vulkan call when the device
    goes) and drops those not begun; the validation layer reports nothing."""
    monkeypatch.setenv("VKPBR_KERNELS_AHEAD", "1")
    r = make_renderer(wait_ahead=False)
    r.close()
    assert r.device.instance.errors == []


def test_a_scene_made_with_kernels_ahead_counts_as_one_made_without(monkeypatch,  # noqa: ANN001
                                                                     make_renderer) -> None:
    """What the guess makes is the device's (kept), not the scene's: the first scene's
    children are as many as the same scene's made again (set_scene, nothing ahead)."""
    monkeypatch.setenv("VKPBR_KERNELS_AHEAD", "1")
    r = make_renderer()
    first = r.device.live_children
    r.set_scene(None)
    assert r.device.live_children == first


@pytest.mark.parametrize("mode", [None, "0", "msaa"])
def test_nothing_is_made_ahead_on_a_cpu_or_when_turned_off(monkeypatch, make_renderer,  # noqa: ANN001
                                                           mode: str | None) -> None:
    """Not on CPUs (auto's forward path), not when turned off, not where frames cannot take
    the compute path (MSAA; a window's device)."""
    if mode is None:
        monkeypatch.delenv("VKPBR_KERNELS_AHEAD", raising=False)
    else:
        monkeypatch.setenv("VKPBR_KERNELS_AHEAD", "0" if mode == "0" else "1")
    r = make_renderer(msaa=4) if mode == "msaa" else make_renderer()
    if mode is None and r.device.info.kind != "cpu":
        pytest.skip("a GPU makes them ahead by default (the test above)")
    r.device.wait_background()
    assert _builds(r) == []
