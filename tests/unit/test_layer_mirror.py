"""The NumPy mirror of the KHR_materials_* layers (reference/brdf.py) against the extensions'
formulas and limits: each layer at zero is the core glTF BRDF (ref.evaluate_brdf, written
separately), ior 1.5 is F0 0.04, specular 0 removes the dielectric lobe, the Charlie
distribution is normalised, the fitted sheen albedo matches its integral, Beer-Lambert's
definition of the attenuation distance, and the coat's Fresnel blend at its limits."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vkpbr.reference import brdf as ref
from vkpbr.shading import Brdf


def directions(rng: np.random.Generator, count: int) -> np.ndarray:
    """Unit vectors in the upper hemisphere (z up)."""
    d = rng.normal(size=(count, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.05
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


@pytest.fixture
def points():  # noqa: ANN201
    rng = np.random.default_rng(5)
    count = 64
    n = np.broadcast_to([0.0, 0.0, 1.0], (count, 3))
    return n, directions(rng, count), directions(rng, count), rng.random((count, 3)), \
        rng.random(count), rng.uniform(0.05, 1.0, count)


def test_ior_and_specular_define_f0() -> None:
    assert np.allclose(ref.dielectric_f0(1.5, (1.0, 1.0, 1.0)), 0.04, rtol=0, atol=1e-15)
    assert np.all(ref.dielectric_f0(1.0, (1.0, 1.0, 1.0)) == 0.0)
    assert np.allclose(ref.dielectric_f0(1e6, (1.0, 1.0, 1.0)), 1.0, atol=1e-5)
    # specularColorFactor scales F0, clamped to 1 (KHR_materials_specular).
    assert np.allclose(ref.dielectric_f0(1.5, (2.0, 0.5, 100.0)), (0.08, 0.02, 1.0))


def test_default_layers_are_the_core_brdf(points) -> None:  # noqa: ANN001
    n, v, l, c, m, r = points
    core = ref.evaluate_brdf(n, v, l, c, m, r, Brdf.GLTF)
    t = ref.evaluate_layered_brdf(n, n, v, l, c, m, r, ref.Layers())
    nl = np.maximum(np.sum(n * l, -1), 0.0)[..., None]
    np.testing.assert_allclose(t.base.specular, core.specular * nl, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(t.base.diffuse, core.diffuse * nl, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(t.base.F, core.F, rtol=1e-12)
    assert not t.transmission.any() and not t.sheen.any() and not t.clearcoat.any()


@pytest.mark.parametrize("layers", [
    ref.Layers(clearcoat=0.0, clearcoat_roughness=0.4),  # clearcoat 0 == base
    ref.Layers(sheen_color=(0.0, 0.0, 0.0), sheen_roughness=0.3),  # sheen 0 == base
    ref.Layers(transmission=0.0, thickness=2.0, attenuation_distance=0.5,
               attenuation_color=(0.2, 0.3, 0.4)),  # volume without transmission: no effect
])
def test_a_layer_at_zero_leaves_the_base(points, layers: ref.Layers) -> None:  # noqa: ANN001
    n, v, l, c, m, r = points
    light = np.array([1.0, 0.9, 0.8])
    base = ref.shade_layered(n, v, l, c, m, r, light, ref.Layers())
    got = ref.shade_layered(n, v, l, c, m, r, light, layers)
    np.testing.assert_allclose(got["final"], base["final"], rtol=1e-12, atol=1e-15)


def test_specular_factor_zero_removes_the_dielectric_lobe(points) -> None:  # noqa: ANN001
    n, v, l, c, _, r = points
    zero = np.zeros(len(n))
    t = ref.evaluate_layered_brdf(n, n, v, l, c, zero, r, ref.Layers(specular=0.0))
    nl = np.maximum(np.sum(n * l, -1), 0.0)[..., None]
    assert not t.base.specular.any()
    np.testing.assert_allclose(t.base.diffuse, c / np.pi * nl, rtol=1e-12)  # all to Lambert
    metal = ref.evaluate_layered_brdf(n, n, v, l, c, np.ones(len(n)), r, ref.Layers(specular=0.0))
    assert metal.base.specular.max() > 0.0  # the metal's lobe is not the dielectric's


@pytest.mark.parametrize("alpha_g", [0.07, 0.2, 0.5, 1.0])
def test_charlie_distribution_is_normalised(alpha_g: float) -> None:
    """Integral of D(h) (n.h) over the hemisphere of h is 1 (midpoint rule in theta)."""
    k = 200_000
    theta = (np.arange(k) + 0.5) * (np.pi / 2) / k
    integral = np.sum(ref.d_charlie(np.cos(theta), alpha_g) * np.cos(theta) * np.sin(theta)) \
        * (np.pi / 2 / k) * 2 * np.pi
    assert integral == pytest.approx(1.0, abs=1e-6)


def test_sheen_albedo_fit_matches_its_integral() -> None:
    worst = 0.0
    for n_dot_v in (0.02, 0.1, 0.25, 0.5, 0.75, 1.0):
        for alpha_g in (0.07, 0.15, 0.3, 0.6, 1.0):
            exact = ref.sheen_albedo_integral(n_dot_v, alpha_g)
            worst = max(worst, abs(float(ref.sheen_albedo(n_dot_v, alpha_g)) - exact))
    assert worst < 5e-3


def test_volume_attenuation_distance_is_beer_lambert() -> None:
    color = (0.9, 0.5, 0.1)
    np.testing.assert_allclose(ref.volume_transmittance(np.asarray(2.0), color, 2.0), color)
    np.testing.assert_allclose(ref.volume_transmittance(np.asarray(4.0), color, 2.0),
                               np.square(color))
    assert np.all(ref.volume_transmittance(np.asarray(0.0), color, 2.0) == 1.0)  # thin
    assert np.all(ref.volume_transmittance(np.asarray(5.0), color, 0.0) == 1.0)  # infinite


def test_coat_blend_limits() -> None:
    n = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    v = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])  # normal incidence, grazing
    out = ref.shade_layered(n, v, n, np.full((2, 3), 0.5), np.zeros(2), np.full(2, 0.5),
                            np.zeros(3), ref.Layers(clearcoat=0.5))
    np.testing.assert_allclose(out["coat_blend"], [0.5 * 0.04, 0.5], rtol=1e-12)


@settings(max_examples=60, deadline=None)
@given(st.floats(1.0, 3.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0),
       st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.integers(0, 2**31))
def test_layered_brdf_is_finite_and_non_negative(ior, specular, clearcoat, sheen, sheen_r,  # noqa: ANN001
                                                 transmission, roughness, seed) -> None:  # noqa: ANN001
    rng = np.random.default_rng(seed)
    n = np.broadcast_to([0.0, 0.0, 1.0], (16, 3))
    v, l = directions(rng, 16), rng.normal(size=(16, 3))
    l /= np.linalg.norm(l, axis=-1, keepdims=True)  # lights from either side
    layers = ref.Layers(ior=ior, specular=specular, clearcoat=clearcoat,
                        clearcoat_roughness=max(roughness, ref.MIN_ROUGHNESS),
                        sheen_color=(sheen, sheen * 0.5, 0.0),
                        sheen_roughness=max(sheen_r, ref.MIN_SHEEN_ROUGHNESS),
                        transmission=transmission, thickness=1.0, attenuation_distance=1.0,
                        attenuation_color=(0.5, 0.5, 0.5))
    out = ref.shade_layered(n, v, l, rng.random((16, 3)), rng.random(16), np.full(16, roughness),
                            np.ones(3), layers)
    assert np.all(np.isfinite(out["final"])) and np.all(out["final"] >= 0.0)
    assert np.all(out["sheen_scaling"] >= 0.0) and np.all(out["sheen_scaling"] <= 1.0)
