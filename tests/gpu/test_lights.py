"""Punctual lights of every kind against an independent NumPy evaluation, pixel by pixel.

Set-up (as test_reference.py): a large plane y = 0 of one material seen obliquely; each
pixel-centre ray is intersected with the plane in NumPy, so the point, n and v are known
exactly. The expected radiance sums, over the lights, the glTF BRDF (reference/brdf.py) times
the light's incident radiance computed here from KHR_lights_punctual's formulas (inverse
square, the range window, the spot cone), independently of reference/lights.py and of how
render/frames.py packs a light. Linear float32 output; tolerance: relative 2e-3 plus 2e-5
absolute per channel (float32 shading), plus how far the image moves over 1/64 pixel
(pinhole.raster_slack: where the rasterised surface is, at the windows' steep edges).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from pinhole import assert_close_on_raster, pixel_rays

from vkpbr.errors import UsageError
from vkpbr.reference import brdf as ref
from vkpbr.reference.lights import light_incident, spot_falloff
from vkpbr.render.layouts import Brdf
from vkpbr.scene.default import plane
from vkpbr.scene.types import Camera, Light, Material, Node, Scene
from vkpbr.shading import MAX_LIGHTS

W, H = 80, 56
CAMERA = Camera(eye=(0.0, 3.0, 3.5), target=(0.0, 0.0, 0.0), yfov_deg=60.0, znear=0.1, zfar=100.0)
MATERIAL = Material(base_color_factor=(0.7, 0.6, 0.5, 1), metallic_factor=0.3, roughness_factor=0.45)

def _unit(*v: float) -> tuple[float, float, float]:
    a = np.asarray(v, dtype=np.float64)
    return tuple(float(x) for x in a / np.linalg.norm(a))  # type: ignore[return-value]


POINT = Light(kind="point", position=(0.8, 1.2, 0.4), color=(1.0, 0.8, 0.6), intensity=4.0,
              falloff="inverse_square", range=2.5)
SPOT = Light(kind="spot", position=(-0.5, 2.0, -0.3), direction=_unit(0.2, -1.0, 0.1),
             color=(0.6, 0.8, 1.0), intensity=9.0, falloff="inverse_square",
             inner_cone=math.radians(12), outer_cone=math.radians(30))
SUN = Light(kind="directional", direction=_unit(0.4, -0.8, -0.45), color=(1.0, 1.0, 0.9),
            intensity=1.5)


def plane_scene() -> Scene:
    mesh = plane(60.0, 60.0)
    mesh.material = 0
    return Scene("plane", meshes=[mesh], materials=[MATERIAL], nodes=[Node(mesh=0)],
                 cameras=[CAMERA])


def plane_points() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World point, n, v per pixel (H, W, 3), from an independent pinhole ray cast."""
    d = pixel_rays(CAMERA, W, H)
    eye = np.asarray(CAMERA.eye, dtype=np.float64)
    p = eye + (-eye[1] / d[..., 1])[..., None] * d
    v = eye - p
    return p, np.broadcast_to([0.0, 1.0, 0.0], p.shape), v / np.linalg.norm(v, axis=-1, keepdims=True)


def spec_incident(light: Light, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """KHR_lights_punctual written out: radiance and l at points p, from the spec's text."""
    color = np.asarray(light.color) * light.intensity
    if light.kind == "directional":
        return np.broadcast_to(color, p.shape), np.broadcast_to(-np.asarray(light.direction), p.shape)
    to_light = np.asarray(light.position) - p
    d = np.linalg.norm(to_light, axis=-1)
    l = to_light / d[..., None]  # noqa: E741
    att = 1.0 / d**2
    if light.range > 0:
        att *= np.clip(1.0 - (d / light.range) ** 4, 0.0, 1.0)
    if light.kind == "spot":
        cd = np.sum(np.asarray(light.direction) * -l, axis=-1)
        cos_outer, cos_inner = math.cos(light.outer_cone), math.cos(light.inner_cone)
        t = np.clip((cd - cos_outer) / (cos_inner - cos_outer), 0.0, 1.0)
        att *= t * t
    return color * att[..., None], l


def expected(lights: list[Light]) -> np.ndarray:
    p, n, v = plane_points()
    c = np.broadcast_to(np.asarray(MATERIAL.base_color_factor[:3]), p.shape)
    m = np.full(p.shape[:2], MATERIAL.metallic_factor)
    r = np.full(p.shape[:2], MATERIAL.roughness_factor)
    total = np.zeros(p.shape)
    for light in lights:
        radiance, l = spec_incident(light, p)
        total += ref.shade(n, v, l, c, m, r, radiance, brdf=Brdf.GLTF, ambient=0.0)["final"]
    return total


def render(r, lights: list[Light], **options: object) -> np.ndarray:  # noqa: ANN001
    return r.render(lights=lights, size=(W, H), linear=True, lighting="pbr", env="none",
                    **options)[..., :3]


@pytest.mark.parametrize("lights", [[POINT], [SPOT], [SUN], [POINT, SPOT, SUN]],
                         ids=["point", "spot", "directional", "all"])
def test_each_kind_matches_the_spec(make_renderer, lights: list[Light]) -> None:
    r = make_renderer(plane_scene())
    got = render(r, lights)
    want = expected(lights)
    assert want.max() > 0.05  # the lights do reach the visible plane
    assert_close_on_raster(got, want, rtol=2e-3, atol=2e-5)


# A light at the eye (a headlight, a ring light around the lens): l = v at every pixel,
# where h.v of unit vectors rounds above 1 (Schlick's (1 - h.v)^5 of a negative base had
# made NaN pixels: a tenth of the default scene's).
HEADLIGHT = Light(kind="point", position=CAMERA.eye, color=(1.0, 0.9, 0.8), intensity=12.0,
                  falloff="inverse_square")


@pytest.mark.parametrize("pipeline", ["forward", "compute", "batch"])
def test_a_light_at_the_eye_matches_the_spec(make_renderer, pipeline: str) -> None:
    r = make_renderer(plane_scene())
    if pipeline == "batch":
        got = r.render_batch([CAMERA, CAMERA], (W, H), [HEADLIGHT], linear=True, env="none")[1, ..., :3]
    else:
        got = render(r, [HEADLIGHT], pipeline=pipeline)
    assert np.isfinite(got).all(), f"{np.count_nonzero(~np.isfinite(got).all(axis=-1))} NaN pixels"
    want = expected([HEADLIGHT])
    assert want.max() > 0.05
    assert_close_on_raster(got, want, rtol=2e-3, atol=2e-5)


def test_spot_cone_and_range_windows_are_visible(make_renderer) -> None:
    """The windows bite in the image: pixels beyond the spot's outer cone and the point
    light's range are black, pixels inside are lit (and the NumPy test above matches both)."""
    r = make_renderer(plane_scene())
    p, _, _ = plane_points()
    for light in (SPOT, POINT):
        got = render(r, [light]).max(axis=-1)
        radiance, _ = spec_incident(light, p)
        outside, inside = radiance.max(axis=-1) == 0.0, radiance.max(axis=-1) > 1e-3
        assert outside.sum() > 100 and inside.sum() > 100
        assert np.all(got[outside] <= 1e-6) and np.all(got[inside] > 0)


def test_lights_add_up(make_renderer) -> None:
    """Linear images are additive in the lights: image(A + B + C) = sum of the images."""
    r = make_renderer(plane_scene())
    parts = sum(render(r, [li]) for li in (POINT, SPOT, SUN))
    np.testing.assert_allclose(render(r, [POINT, SPOT, SUN]), parts, rtol=1e-5, atol=1e-6)


def test_no_light_is_black_and_max_lights_all_count(make_renderer) -> None:
    r = make_renderer(plane_scene())
    assert render(r, []).max() == 0.0  # `--light none`: no punctual light, not even the sun
    rng = np.random.default_rng(5)
    many = [Light(kind="point", position=(float(x), 0.6, float(z)), intensity=0.02,
                  color=tuple(float(c) for c in rng.uniform(0.2, 1.0, 3)), falloff="inverse_square")
            for x, z in rng.uniform(-3, 3, (MAX_LIGHTS, 2))]
    # Shadow maps hold 4 point lights; the rest are drawn unshadowed, with one warning.
    with pytest.warns(UserWarning, match="252 light\\(s\\) drawn without shadows"):
        got = render(r, many)
    np.testing.assert_allclose(got, expected(many), rtol=3e-3, atol=5e-5)
    with pytest.raises(UsageError, match=f"at most {MAX_LIGHTS}"):
        render(r, many + [POINT])


def test_reference_spot_falloff_is_the_specs() -> None:
    """reference/lights.py's mirror agrees with the formulas written out above."""
    p, _, _ = plane_points()
    for light in (POINT, SPOT, SUN):
        a, la = light_incident(light, p)
        b, lb = spec_incident(light, p)
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(la, lb, rtol=1e-12)
    axis = np.asarray(SPOT.direction)
    assert spot_falloff(SPOT, -axis) == 1.0  # on the axis: full
    edge = np.array([math.sin(SPOT.outer_cone), -math.cos(SPOT.outer_cone), 0.0])
    down = dataclasses.replace(SPOT, direction=(0.0, -1.0, 0.0))
    assert spot_falloff(down, -edge) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("bad, message", [
    (dict(kind="spot", inner_cone=0.0, outer_cone=0.0), "outer_cone"),
    (dict(intensity=-1.0), "intensity"),
    (dict(kind="directional", direction=(0.0, 0.0, 0.0)), "direction"),
    (dict(position=(float("nan"), 0.0, 0.0)), "position"),
])
def test_bad_lights_are_one_line_usage_errors(make_renderer, bad: dict, message: str) -> None:
    r = make_renderer(plane_scene())
    with pytest.raises(UsageError, match=message) as info:
        render(r, [dataclasses.replace(POINT, **bad)])
    assert "\n" not in str(info.value)
