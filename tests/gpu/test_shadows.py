"""Shadows through the whole frame path (Renderer.render, the SHADOW debug view): an occluder
and an alpha-masked card with a hole over a ground, lit by each light type, against a NumPy
ray cast (tests/shadow_scenes.py). A pixel's shadow factor (> 0.5: lit) must agree with
"does the segment to the light hit an occluder" outside a penumbra band of 4 shadow-map
texels around the occluders' and the hole's borders: at most 0.5% of the judged pixels
wrong. Also: a lone plane is lit everywhere (no acne); light through the card's hole (the
masked caster is cut out); shadows off, course lighting and Light.shadows False draw no
shadow; lights without shadows before a shadowed one keep its factor and add linearly."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from shadow_scenes import BLOCK, CAMERA, GROUND, LIGHTS, rect_scene, reference

from vkpbr.render import shadow_math as SM

SIZE = (128, 96)
RES = 256  # small maps: the band is 4 texels, and lavapipe draws them fast
# A larger card and hole than test_shadow_factor's: enough ground lit through the hole
# outside the band at this image size.
CARD = (0.8, 1.0, 2.6, -0.9, 0.7, (0.2, 0.8))
RECTS = (GROUND, BLOCK, CARD)
OPTS = {"shadow_resolution": RES, "env": "none"}  # punctual light only: sums add up


@pytest.fixture(scope="module")
def renderers():
    """One validated renderer of the occluder scene and one of the lone ground."""
    from vkpbr import Renderer

    made = {"occluded": Renderer(rect_scene(RECTS), validation=True, sync_validation=True),
            "lone": Renderer(rect_scene((GROUND,)), validation=True, sync_validation=True)}
    yield made
    for r in made.values():
        instance = r.device.instance
        r.close()
        assert instance.errors == [], instance.errors[:3]


def _shadow_view(r, lights, **opts) -> np.ndarray:  # noqa: ANN001
    image = r.render(CAMERA, lights, size=SIZE, view="shadow", linear=True, **{**OPTS, **opts})
    return image[..., 0]


def _spot_texel(light) -> float:  # noqa: ANN001
    """A spot map's texel at unit distance along its axis: the map spans its half angle."""
    return 2.0 * math.tan(SM.spot_half_angle(light.outer_cone)) / RES


@pytest.mark.parametrize("kind", ["directional", "spot", "point"])
def test_shadow_view_matches_a_ray_cast(kind, renderers) -> None:
    light = LIGHTS[kind]
    factor = _shadow_view(renderers["occluded"], light)
    ref = reference(RECTS, light, SIZE, RES, _spot_texel(light))
    judged = (ref["rid"] >= 0) & ~ref["band"] & ref["facing"]
    assert judged.mean() > 0.5
    wrong = (factor > 0.5) != ref["lit"]
    assert wrong[judged].mean() <= 0.005, (kind, wrong[judged].mean())
    # Both sides are well represented: the block's shadow, and ground lit through the hole.
    assert (~ref["lit"] & judged).sum() > 100 and (ref["lit"] & judged).sum() > 200
    hole = ref["hole"] & judged & (ref["rid"] == 0)
    assert hole.sum() >= 25, hole.sum()
    # The masked card is cut out: where light passes its hole, the ground is lit (an opaque
    # card would shadow all of these).
    assert (factor[hole] > 0.5).mean() >= 0.98, (kind, (factor[hole] > 0.5).mean())


@pytest.mark.parametrize("kind", ["directional", "spot", "point"])
def test_a_lone_plane_is_lit_everywhere(kind, renderers) -> None:
    """Nothing over the ground: every pixel of it facing the light is fully lit (no acne)."""
    light = LIGHTS[kind]
    factor = _shadow_view(renderers["lone"], light)
    ref = reference((GROUND,), light, SIZE, RES, _spot_texel(light))
    ground = (ref["rid"] == 0) & ref["facing"]
    assert ground.mean() > 0.4
    assert np.all(factor[ground] > 0.999), (kind, factor[ground].min())


def test_no_shadows_when_off_in_course_mode_or_per_light(renderers) -> None:
    """--shadows off, --lighting course and Light.shadows False: the SHADOW view is 1 on
    every drawn pixel, and the shaded image is the unshadowed one."""
    r = renderers["occluded"]
    light = LIGHTS["directional"]
    drawn = reference(RECTS, light, SIZE, RES, 0.0)["rid"] >= 0
    shadowed = _shadow_view(r, light)
    assert (shadowed[drawn] < 0.5).sum() > 100  # the same frame with shadows has some
    no_cast = dataclasses.replace(light, shadows=False)
    for lights, opts in ((light, {"shadows": False}), (light, {"lighting": "course"}),
                         (no_cast, {})):
        factor = _shadow_view(r, lights, **opts)
        assert np.all(factor[drawn] == 1.0), opts
    off = r.render(CAMERA, light, size=SIZE, linear=True, shadows=False, **OPTS)
    per_light = r.render(CAMERA, no_cast, size=SIZE, linear=True, **OPTS)
    on = r.render(CAMERA, light, size=SIZE, linear=True, **OPTS)
    assert np.array_equal(off, per_light)
    assert (on[..., :3].sum(-1) < off[..., :3].sum(-1) - 1e-3).sum() > 100
    # Course mode ignores the shadow options: its image is the same either way.
    course = [r.render(CAMERA, light, size=SIZE, lighting="course", shadows=s, **OPTS)
              for s in (True, False)]
    assert np.array_equal(*course)


def test_unshadowed_lights_before_a_shadowed_one(renderers) -> None:
    """Lights [A (no shadows), B]: the SHADOW view is B's factor (the first shadowed
    light's), and the linear image is image(A) + image(B) (each light's own shadow)."""
    r = renderers["occluded"]
    a = dataclasses.replace(LIGHTS["point"], shadows=False, intensity=2.0)
    b = LIGHTS["spot"]
    assert np.array_equal(_shadow_view(r, [a, b]), _shadow_view(r, b))
    both, only_a, only_b = (r.render(CAMERA, lights, size=SIZE, linear=True, **OPTS)[..., :3]
                            for lights in ([a, b], a, b))
    np.testing.assert_allclose(both, only_a + only_b, rtol=1e-5, atol=1e-6)
    assert (only_b.sum(-1) == 0).sum() > 100  # B's shadow is in the sum


def test_frames_in_flight_keep_their_own_cascades(renderers) -> None:
    """render_many with a moving camera (cascades refitted per frame slot, skipped when a
    slot's inputs repeat) gives each frame what render gives for its camera alone."""
    r = renderers["occluded"]
    light = LIGHTS["directional"]
    cameras = [dataclasses.replace(CAMERA, eye=(x, 5.0, 6.0)) for x in (-1.0, 0.0, 1.0, 0.0)]
    batch = list(r.render_many(cameras, light, size=SIZE, view="shadow", linear=True, **OPTS))
    for camera, image in zip(cameras, batch, strict=True):
        alone = r.render(camera, light, size=SIZE, view="shadow", linear=True, **OPTS)
        assert np.array_equal(image, alone)
    assert not np.array_equal(batch[0], batch[2])
