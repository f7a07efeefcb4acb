"""The environment pre-filter and ibl.glsl on lavapipe (validation on), each against an
independent NumPy evaluation: scene/sky.py (the sky), scene/environment.py (the panorama
mapping), analytic irradiance, and reference/ibl.py's Monte Carlo integral of the glTF BRDF.

Tolerances (stated with each test) allow for half floats (1e-3 relative), the small cubes of
EnvironmentSpec.small(), Monte Carlo noise of the reference, and, for the two-tone test, the
split-sum approximation's own error.
"""

from __future__ import annotations

import numpy as np
import pytest
from ibl_probe import compile_probe, ibl_probe

from vkpbr.gpu.device import Device
from vkpbr.gpu.image_io import read_rgba16f
from vkpbr.reference.ibl import ggx_albedo, mc_ibl, two_tone_environment, uniform_environment
from vkpbr.render.environment import LUT_SIZE, EnvironmentBaker, EnvironmentSpec
from vkpbr.scene.environment import equirect_to_direction, sample_equirect
from vkpbr.scene.sky import sky_model, sky_radiance

pytestmark = pytest.mark.timeout(120)


def cube_directions(size: int) -> np.ndarray:
    """(6, size, size, 3) texel-centre directions, env_common.glsl's cube_direction."""
    t = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    u, v = np.meshgrid(t, t)  # v along rows (y down)
    one = np.ones_like(u)
    faces = [(one, -v, -u), (-one, -v, u), (u, one, v), (u, -one, -v), (u, -v, one),
             (-u, -v, -one)]
    d = np.stack([np.stack(f, axis=-1) for f in faces])
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


@pytest.fixture(scope="module")
def gpu(tmp_path_factory):  # noqa: ANN001, ANN201
    device = Device(validation=True)
    baker = EnvironmentBaker(device, EnvironmentSpec.small(),
                             cache_dir=tmp_path_factory.mktemp("cache"))
    spirv = compile_probe(tmp_path_factory.mktemp("spv"))
    yield device, baker, spirv
    baker.destroy()
    device.check_validation()
    device.close()


def test_uniform_panorama_stays_uniform(gpu) -> None:  # noqa: ANN001
    """Every pre-filtered level of a constant environment is that constant (half floats)."""
    device, baker, _ = gpu
    env = baker.from_panorama(np.full((32, 64, 3), (0.25, 0.5, 2.0), np.float32))
    try:
        for k in range(env.max_lod + 1):
            level = read_rgba16f(device, env.specular.image, k)[..., :3]
            np.testing.assert_allclose(level, np.broadcast_to((0.25, 0.5, 2.0), level.shape),
                                       rtol=2e-3)
        irr = read_rgba16f(device, env.irradiance.image)[..., :3]
        np.testing.assert_allclose(irr, np.broadcast_to((0.25, 0.5, 2.0), irr.shape), rtol=2e-3)
    finally:
        env.destroy()


def test_panorama_to_cube_matches_numpy_lookup(gpu) -> None:  # noqa: ANN001
    """Level 0 of the source cube = a bilinear lookup of the panorama along each texel's
    direction (scene/environment.py's mapping), for a smooth panorama: 1% + 2e-3."""
    device, baker, _ = gpu
    h = 32
    u, v = np.meshgrid((np.arange(2 * h) + 0.5) / (2 * h), (np.arange(h) + 0.5) / h)
    d = equirect_to_direction(u, v)
    pano = np.stack([1.0 + d[..., 0], 1.0 + d[..., 1], 1.0 + 0.5 * d[..., 2]], -1).astype(np.float32)
    env = baker.from_panorama(pano)
    try:
        got = read_rgba16f(device, env.source.image)[..., :3]
        dirs = cube_directions(env.source.image.width)
        np.testing.assert_allclose(got, sample_equirect(pano, dirs), rtol=0.01, atol=2e-3)
    finally:
        env.destroy()


def test_sky_cube_matches_numpy_sky(gpu) -> None:  # noqa: ANN001
    """The GPU sky (env_sky.comp) = scene/sky.py's sky_radiance at every texel: 1% + 1e-3
    (half floats; texels straddling the horizon are excluded)."""
    device, baker, _ = gpu
    sun = (0.3, -0.5, -0.81)
    env = baker.from_sky(sun)
    try:
        got = read_rgba16f(device, env.source.image)[..., :3]
        dirs = cube_directions(env.source.image.width)
        want = sky_radiance(dirs, sky_model(sun))
        keep = np.abs(dirs[..., 1]) > 0.05
        np.testing.assert_allclose(got[keep], want[keep], rtol=0.01, atol=1e-3)
        assert want[dirs[..., 1] > 0.05][:, 2].mean() > want[dirs[..., 1] > 0.05][:, 0].mean()
    finally:
        env.destroy()


def test_two_tone_irradiance_is_analytic(gpu) -> None:  # noqa: ANN001
    """Sky U over ground D: the cosine-weighted mean radiance about n is
    U (1 + n.y) / 2 + D (1 - n.y) / 2 exactly; the irradiance cube matches it to 0.03 U
    (importance sampling with 128 samples and an 8^2 cube)."""
    device, baker, _ = gpu
    h = 64
    v = (np.arange(h) + 0.5) / h
    pano = np.where((v < 0.5)[:, None, None], 1.0, 0.1) * np.ones((h, 2 * h, 3))
    env = baker.from_panorama(pano.astype(np.float32))
    try:
        got = read_rgba16f(device, env.irradiance.image)[..., 0]
        ny = cube_directions(env.irradiance.image.width)[..., 1]
        want = 1.0 * (1 + ny) / 2 + 0.1 * (1 - ny) / 2
        np.testing.assert_allclose(got, want, atol=0.03)
    finally:
        env.destroy()


def test_brdf_lut_matches_monte_carlo(gpu) -> None:  # noqa: ANN001
    """The split-sum table against reference/ibl.py's independent Monte Carlo albedo of the
    same lobe: A + B (F0 = 1) and 0.04 A + B (F0 = 0.04), within 0.01 + 2%."""
    device, baker, _ = gpu
    lut = read_rgba16f(device, baker.brdf_lut().image)[0, ..., :2]
    rows = np.array([8, 40, 80, 120])
    cols = np.array([10, 40, 80, 125])
    r = (rows + 0.5) / LUT_SIZE
    mu = (cols + 0.5) / LUT_SIZE
    rr, mm = np.meshgrid(r, mu, indexing="ij")
    ab = lut[rows[:, None], cols[None, :]]
    np.testing.assert_allclose(ab.sum(-1), ggx_albedo(mm, rr, 1.0, samples=8192), atol=0.01,
                               rtol=0.02)
    np.testing.assert_allclose(0.04 * ab[..., 0] + ab[..., 1],
                               ggx_albedo(mm, rr, 0.04, samples=8192), atol=0.01, rtol=0.02)
    assert baker.lut_path().is_file()  # cached for the next process


def _points(n_dot_v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = np.tile([0.0, 0.0, 1.0], (len(n_dot_v), 1))
    v = np.stack([np.sqrt(1 - n_dot_v**2), np.zeros_like(n_dot_v), n_dot_v], -1)
    return n, v


@pytest.mark.parametrize("metallic", [0.0, 1.0])
def test_furnace(gpu, metallic: float) -> None:  # noqa: ANN001
    """A white sphere in a uniform white environment (radiance 0.8) returns 0.8 for every
    roughness and view angle, metal and dielectric, with energy compensation: the GPU to
    1.5% (half floats, LUT interpolation), the Monte Carlo reference (glTF BRDF +
    Fdez-Aguera) to 6% (its noise at 4096 samples), and without compensation a rough metal
    loses energy (< 0.8 * 0.8), so the compensation is what closes the gap."""
    _, baker, spirv = gpu
    env = baker.from_panorama(np.full((32, 64, 3), 0.8, np.float32))
    try:
        mu = np.array([0.95, 0.7, 0.4, 0.2])
        rough = np.array([0.05, 0.25, 0.5, 0.75, 1.0])
        mm, rr = np.meshgrid(mu, rough)
        n, v = _points(mm.ravel())
        c = np.ones_like(n)
        diffuse, specular = ibl_probe(baker.device, env, spirv, n, v, c, metallic, rr.ravel())
        np.testing.assert_allclose(diffuse + specular, 0.8, rtol=0.015)
        if metallic == 1.0:
            assert np.abs(diffuse).max() < 1e-6
        ref = mc_ibl(n, v, c, metallic, rr.ravel(), uniform_environment(0.8), samples=4096)
        np.testing.assert_allclose(ref, 0.8, rtol=0.06)
        if metallic == 1.0:
            single = mc_ibl(n, v, c, metallic, rr.ravel(), uniform_environment(0.8),
                            samples=4096, multiple_scattering=False)
            assert single[rr.ravel() == 1.0].max() < 0.8 * 0.8
    finally:
        env.destroy()


def test_two_tone_sphere_matches_monte_carlo(gpu) -> None:  # noqa: ANN001
    """Sphere pixels seen along -Z (orthographic), lit by sky 1 over ground 0.1, for a grey
    dielectric and a gold metal at three roughnesses: ibl_evaluate against the Monte Carlo
    integral of the same BRDF (2048 samples a pixel). Tolerance: 0.06 absolute on 95% of
    pixels and 0.15 on all (the split-sum's error at grazing angles near the horizon's edge)."""
    _, baker, spirv = gpu
    h = 64
    vv = (np.arange(h) + 0.5) / h
    pano = (np.where((vv < 0.5)[:, None, None], 1.0, 0.1) * np.ones((h, 2 * h, 3)))
    env = baker.from_panorama(pano.astype(np.float32))
    try:
        g = np.linspace(-0.95, 0.95, 9)
        x, y = np.meshgrid(g, g)
        inside = x**2 + y**2 < 0.95**2
        n = np.stack([x[inside], y[inside], np.sqrt(1 - x[inside] ** 2 - y[inside] ** 2)], -1)
        v = np.tile([0.0, 0.0, 1.0], (len(n), 1))
        errors = []
        for metallic, color in ((0.0, (0.5, 0.5, 0.5)), (1.0, (1.0, 0.78, 0.34))):
            c = np.tile(color, (len(n), 1))
            for rough in (0.2, 0.5, 0.9):
                d, s = ibl_probe(baker.device, env, spirv, n, v, c, metallic, rough)
                ref = mc_ibl(n, v, c, metallic, rough, two_tone_environment((1, 1, 1),
                                                                            (0.1, 0.1, 0.1)),
                             samples=2048)
                errors.append(np.abs(d + s - ref).max(-1))
        err = np.concatenate(errors)
        print(f"two-tone: max {err.max():.3f}, 95th percentile {np.percentile(err, 95):.3f}")
        assert np.percentile(err, 95) < 0.06
        assert err.max() < 0.15
    finally:
        env.destroy()


def test_env_intensity_and_rotation(gpu) -> None:  # noqa: ANN001
    """env_intensity scales both terms; rotating a panorama that is bright only towards +X
    by 90 degrees about +Y moves the brightness to -Z (env_rotate's convention)."""
    _, baker, spirv = gpu
    h = 32
    u, v = np.meshgrid((np.arange(2 * h) + 0.5) / (2 * h), (np.arange(h) + 0.5) / h)
    d = equirect_to_direction(u, v)
    pano = np.repeat(np.maximum(d[..., :1], 0.0) ** 4, 3, -1).astype(np.float32)
    env = baker.from_panorama(pano)
    try:
        n = np.array([[1.0, 0, 0], [0, 0, -1.0]])
        c = np.ones_like(n)
        d0, s0 = ibl_probe(baker.device, env, spirv, n, n, c, 0.0, 0.5)
        d2, s2 = ibl_probe(baker.device, env, spirv, n, n, c, 0.0, 0.5, intensity=2.0)
        np.testing.assert_allclose(d2, 2 * d0, rtol=1e-5)
        np.testing.assert_allclose(s2, 2 * s0, rtol=1e-5)
        d9, s9 = ibl_probe(baker.device, env, spirv, n, n, c, 0.0, 0.5, rotation_deg=90.0)
        assert d0[0, 0] > 5 * d0[1, 0]
        np.testing.assert_allclose(d9[1], d0[0], rtol=0.02)
    finally:
        env.destroy()
