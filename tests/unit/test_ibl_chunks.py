"""reference/ibl.py evaluates its Monte Carlo estimates a chunk of points at a time (to keep
its temporaries small): the chunk size changes nothing, bit for bit, for every coupling,
broadcast argument and F0 form (the GPU tests' IBL references rest on it)."""

from __future__ import annotations

import numpy as np
import pytest

from vkpbr.reference import ibl


def _unit(x: np.ndarray) -> np.ndarray:
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def both(monkeypatch: pytest.MonkeyPatch, call):  # noqa: ANN001, ANN201
    """call() with chunks of ~7 points and with everything in one piece."""
    monkeypatch.setattr(ibl, "CHUNK_PAIRS", 7 * 64)
    small = call()
    monkeypatch.setattr(ibl, "CHUNK_PAIRS", 1 << 40)
    return small, call()


def test_mc_ibl_does_not_depend_on_the_chunks(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(3)
    n = _unit(rng.normal(size=(3, 4, 3)))
    v = _unit(n + 0.7 * rng.normal(size=n.shape))
    env = ibl.two_tone_environment((1.0, 0.9, 0.8), (0.1, 0.1, 0.1))
    cases = [((rng.uniform(size=(3, 4, 3)), rng.uniform(size=(3, 4)),
               rng.uniform(0.05, 1.0, (3, 4))), kw)
             for kw in ({}, {"coupling": "gltf"}, {"multiple_scattering": False})]
    cases.append((((1.0, 0.78, 0.34), 1.0, 0.3), {}))  # broadcast colour, metallic, roughness
    for (c, metallic, rough), kw in cases:
        small, whole = both(monkeypatch, lambda c=c, m=metallic, r=rough, kw=kw: ibl.mc_ibl(
            n, v, c, m, r, env, samples=64, **kw))
        assert small.shape == whole.shape == (3, 4, 3)
        np.testing.assert_array_equal(small, whole)


def test_ggx_albedo_does_not_depend_on_the_chunks(monkeypatch: pytest.MonkeyPatch) -> None:
    mu, rough = np.meshgrid(np.linspace(0.05, 1.0, 6), np.linspace(0.05, 1.0, 5))
    for f0 in (1.0, np.array([0.04, 0.5, 0.9]), np.random.default_rng(4).uniform(size=(5, 6, 7))):
        small, whole = both(monkeypatch, lambda f0=f0: ibl.ggx_albedo(mu, rough, f0, samples=64))
        assert small.shape == whole.shape == (5, 6) + np.shape(f0)[-1:]
        np.testing.assert_array_equal(small, whole)
    assert np.shape(ibl.ggx_albedo(0.5, 0.3, samples=64)) == ()
