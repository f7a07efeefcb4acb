"""KHR_materials_transmission through the scene (render/transmission.py) on lavapipe,
validation on, both frame paths: a transmissive slab (the plane y = 0) seen from above, an
unlit card (radiance C, its base colour) under part of it at y = -1, a uniform environment
of radiance L around, no punctual light.

What the slab lets through is computed independently: each pixel's ray is cast onto the slab
(pinhole.py, not the renderer's matrices), the refracted ray's exit point found with the
NumPy mirror (reference/brdf.py transmission_exit), and what the camera sees through that
point -- the card where its ray meets the card, else the environment -- is the radiance
behind. The transmission view must then equal the mirror's transmission * k_d * behind, k_d
the split sum's diffuse weight (read from the IBL diffuse view of the same slab without
transmission, as test_material_layers.py does). Tolerance rtol 1e-2 (the copy and the cubes
are half floats), away from the card's edge (pixels whose neighbours see the other side: the
copy is sampled bilinearly there).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import OpenEXR
import pytest
from pinhole import pixel_rays, project

from vkpbr.reference import brdf as ref
from vkpbr.render.environment import EnvironmentSpec
from vkpbr.render.options import RenderOptions
from vkpbr.render.transmission import copy_size
from vkpbr.scene.default import plane
from vkpbr.scene.types import Camera, Material, Node, Scene

pytestmark = pytest.mark.timeout(300)

W = H = 64
CAMERA = Camera(eye=(2.0, 2.5, 0.0), target=(0.0, 0.0, 0.0), up=(0.0, 0.0, -1.0), yfov_deg=50.0,
                znear=0.1, zfar=100.0)
L_ENV = 0.7
CARD = (0.8, 0.3, 0.1)
CARD_EDGE_X = -0.6  # the card covers x < this, at y = -1
SLAB = Material(base_color_factor=(0.9, 0.95, 0.85, 1), metallic_factor=0.0,
                roughness_factor=0.0, ior=1.5, transmission_factor=0.9)
THICK = dataclasses.replace(SLAB, ior=1.8, thickness_factor=0.9)


def slab_scene(slab: Material) -> Scene:
    card = plane(10.0, 20.0, y=-1.0)
    card.positions[:, 0] += CARD_EDGE_X - 5.0
    card.material = 1
    top = plane(40.0, 40.0)
    top.material = 0
    unlit = Material(base_color_factor=(*CARD, 1.0), unlit=True)
    return Scene("slab", meshes=[top, card], materials=[slab, unlit],
                 nodes=[Node(mesh=0), Node(mesh=1)], cameras=[CAMERA])


@pytest.fixture(scope="module")
def uniform_env(tmp_path_factory) -> Path:  # noqa: ANN001
    path = tmp_path_factory.mktemp("uniform-env") / "uniform.exr"
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": np.full((16, 32, 3), L_ENV, np.float32)}) as f:
        f.write(str(path))
    return path


def render(r, view: str, pipeline: str, **options: object) -> np.ndarray:  # noqa: ANN001
    return r.render(size=(W, H), view=view, linear=True, lighting="pbr", brdf="gltf",
                    pipeline=pipeline, lights=[], **options)[..., :3]


def slab_geometry() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per pixel the slab's point, normal and direction to the eye, by ray casting."""
    d = pixel_rays(CAMERA, W, H)
    eye = np.asarray(CAMERA.eye, np.float64)
    p = eye + (-eye[1] / d[..., 1])[..., None] * d
    n = np.broadcast_to([0.0, 1.0, 0.0], p.shape)
    v = (eye - p) / np.linalg.norm(eye - p, axis=-1, keepdims=True)
    return p, n, v


def seen_behind(exit_points: np.ndarray) -> np.ndarray:
    """(H, W, 3): what the copy of the opaque scene holds where each exit point projects --
    the card where the camera's ray through the point meets it, else the environment (also
    where the point projects off the screen, where the shader takes the environment)."""
    eye = np.asarray(CAMERA.eye, np.float64)
    d = exit_points - eye
    t = (-1.0 - eye[1]) / d[..., 1]
    x = eye[0] + t * d[..., 0]
    on_card = x < CARD_EDGE_X
    for idx in np.ndindex(exit_points.shape[:2]):
        row, col, z = project(CAMERA, exit_points[idx], W, H)
        if not (0.0 <= row <= H and 0.0 <= col <= W and z > 0.0):
            on_card[idx] = False
    return np.where(on_card[..., None], np.asarray(CARD), L_ENV)


def away_from_edges(behind: np.ndarray) -> np.ndarray:
    """Pixels whose 8 neighbours see the same side as they do."""
    side = behind[..., 0] != L_ENV
    keep = np.ones_like(side)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            keep &= np.roll(np.roll(side, dy, 0), dx, 1) == side
    keep[[0, -1], :] = keep[:, [0, -1]] = False
    return keep


def diffuse_weight(make_renderer, env: Path, cache: Path, slab: Material = SLAB) -> np.ndarray:  # noqa: ANN001
    """k_d per pixel: the slab without transmission, IBL diffuse view / L (GTAO off: it
    occludes that view, and k_d is the BRDF's weight alone)."""
    opaque = dataclasses.replace(slab, transmission_factor=0.0)
    r = make_renderer(slab_scene(opaque), env_spec=EnvironmentSpec.small(), cache_dir=cache)
    return render(r, "ibl-diffuse", "forward", env=str(env), ao="off") / L_ENV


def mirrored_transmission(slab: Material, k_d: np.ndarray, behind: np.ndarray | None
                          ) -> np.ndarray:
    """The mirror's transmission view of the slab (no punctual light): `behind` the radiance
    through it (None: the environment's)."""
    _, n, v = slab_geometry()
    shape = n.shape[:2]
    return ref.shade_layered(n, v, n, np.broadcast_to(slab.base_color_factor[:3], n.shape),
                             np.zeros(shape), np.full(shape, slab.roughness_factor), np.zeros(3),
                             ref.Layers.of(slab), env_radiance=L_ENV, ibl_diffuse_weight=k_d,
                             behind=behind)["transmission"]


def expected_transmission(slab: Material, k_d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mirror's transmission view through the copy, and the radiance behind per pixel."""
    p, n, v = slab_geometry()
    behind = seen_behind(ref.transmission_exit(p, n, v, ref.Layers.of(slab)))
    return mirrored_transmission(slab, k_d, behind), behind


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
@pytest.mark.parametrize("slab", ["thin", "thick"])
def test_the_slab_shows_what_is_behind_it(make_renderer, uniform_env: Path, tmp_path: Path,
                                          slab: str, pipeline: str) -> None:
    """The card through the slab where the refracted ray's exit point sees it, the
    environment elsewhere, with the environment drawn through glass even where the frame
    draws no background (env_background off)."""
    mat = SLAB if slab == "thin" else THICK
    r = make_renderer(slab_scene(mat), env_spec=EnvironmentSpec.small(), cache_dir=tmp_path)
    if pipeline == "compute" and not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    got = render(r, "transmission", pipeline, env=str(uniform_env), env_background=False)
    if pipeline == "compute":  # the copy was drawn on the compute path too (its resources)
        assert any(id(t) in r.compute_scene()._targets for t in r.opaque_copies.targets)
    want, behind = expected_transmission(mat, diffuse_weight(make_renderer, uniform_env, tmp_path,
                                                             mat))
    keep = away_from_edges(behind)
    assert keep.sum() > 0.6 * W * H and (behind[keep][:, 0] != L_ENV).sum() > 0.2 * W * H
    np.testing.assert_allclose(got[keep], want[keep], rtol=1e-2, atol=1e-4)
    # The final image composes it as the other layers' tests check; the card shows in it.
    final = render(r, "final", pipeline, env=str(uniform_env), env_background=False)
    on_card = keep & (behind[..., 0] != L_ENV)
    assert np.all(final[on_card][:, 0] > 1.5 * final[on_card][:, 2])


def test_refraction_moves_the_card_edge() -> None:
    """The thick slab's refraction moves where the card's edge shows by pixels, so the
    thick case above tells a refracted exit point from a straight one."""
    p, n, v = slab_geometry()
    thin = seen_behind(p)[..., 0] != L_ENV
    thick = seen_behind(ref.transmission_exit(p, n, v, ref.Layers.of(THICK)))[..., 0] != L_ENV
    assert (thin != thick).sum() >= 4 * H


def test_roughness_blurs_what_is_behind(make_renderer, uniform_env: Path, tmp_path: Path) -> None:
    """A rough slab samples the copy's mips (lod log2(1024) x roughness x (2 ior - 2)): the
    card's edge spreads over pixels; far from it the values are the smooth slab's."""
    rough = dataclasses.replace(SLAB, roughness_factor=0.7)
    views = {}
    for name, mat in (("smooth", SLAB), ("rough", rough)):
        r = make_renderer(slab_scene(mat), env_spec=EnvironmentSpec.small(), cache_dir=tmp_path)
        img = render(r, "transmission", "forward", env=str(uniform_env))
        views[name] = img[..., 2] / img[..., 0]  # the card is red, the environment grey
        r.close()

    def mixed(ratio: np.ndarray) -> int:  # pixels neither card nor environment
        env = SLAB.base_color_factor[2] / SLAB.base_color_factor[0]  # the slab's tint
        card = env * CARD[2] / CARD[0]
        return int(((ratio > card + 0.05) & (ratio < env - 0.05)).sum())

    assert mixed(views["rough"]) >= 3 * mixed(views["smooth"]) and mixed(views["rough"]) >= 4 * H
    far = np.zeros((H, W), bool)
    far[:, :4] = far[:, -4:] = True  # the card's far side and the environment's
    np.testing.assert_allclose(views["rough"][far], views["smooth"][far], rtol=0.05)


def test_without_an_environment_the_card_still_shows(make_renderer, uniform_env: Path,
                                                     tmp_path: Path) -> None:
    """No environment (env none): the glass still shows the card (through the copy), and
    black where nothing is behind it."""
    r = make_renderer(slab_scene(SLAB), env_spec=EnvironmentSpec.small(), cache_dir=tmp_path)
    got = render(r, "transmission", "forward", env="none")
    want, behind = expected_transmission(SLAB, diffuse_weight(make_renderer, uniform_env, tmp_path))
    keep = away_from_edges(behind)
    card = keep & (behind[..., 0] != L_ENV)
    np.testing.assert_allclose(got[card], want[card], rtol=1e-2, atol=1e-4)
    assert np.abs(got[keep & ~card]).max() < 1e-4


def test_batches_keep_the_environment(make_renderer, uniform_env: Path, tmp_path: Path) -> None:
    """render_batch's views share a frame slot: transmission there refracts the environment
    (render/transmission.py), the card unseen -- the documented fallback, not a crash."""
    r = make_renderer(slab_scene(SLAB), env_spec=EnvironmentSpec.small(), cache_dir=tmp_path)
    got = r.render_batch([CAMERA, CAMERA], size=(W, H), view="transmission", linear=True,
                         lighting="pbr", brdf="gltf", lights=[], env=str(uniform_env))
    want = mirrored_transmission(SLAB, diffuse_weight(make_renderer, uniform_env, tmp_path), None)
    for view in np.asarray(got)[..., :3]:
        np.testing.assert_allclose(view[1:-1, 1:-1], want[1:-1, 1:-1], rtol=1e-2, atol=1e-4)


def test_copy_size_follows_the_frame() -> None:
    assert [copy_size(e) for e in ((64, 64), (64, 48), (65, 10), (100, 5), (1, 1), (640, 360),
                                   (1920, 1080), (4096, 16))] == [64, 64, 64, 128, 1, 512, 1024, 1024]


def test_a_new_frame_size_remakes_the_copies(make_renderer, uniform_env: Path, tmp_path: Path) -> None:
    """Frames of another size class get copies of their own size (the recordings naming the
    old ones dropped): 64, then 256, then 64 again gives the first image back exactly."""
    r = make_renderer(slab_scene(SLAB), env_spec=EnvironmentSpec.small(), cache_dir=tmp_path)
    first = render(r, "final", "forward", env=str(uniform_env))
    assert r.opaque_copies.size == 64
    big = r.render(size=(256, 192), view="final", linear=True, lights=[], env=str(uniform_env))
    assert r.opaque_copies.size == 256 and np.isfinite(big).all()
    np.testing.assert_array_equal(render(r, "final", "forward", env=str(uniform_env)), first)


def test_the_depth_prepass_leaves_the_copy_alone(make_renderer, uniform_env: Path,
                                                 tmp_path: Path) -> None:
    """With the depth pre-pass (GPUs' rule) the copy is drawn as the frame is, pre-pass
    first: the same image as without it."""
    images = []
    for prepass in (False, True):
        r = make_renderer(slab_scene(THICK), env_spec=EnvironmentSpec.small(), cache_dir=tmp_path,
                          depth_prepass=prepass)
        images.append(render(r, "final", "forward", env=str(uniform_env)))
    np.testing.assert_allclose(images[1], images[0], rtol=0, atol=1e-6)


def test_every_view_and_option_with_glass(make_renderer, uniform_env: Path, tmp_path: Path) -> None:
    """A transmissive scene under every debug view, both lightings and BRDFs, the frame paths,
    4x MSAA, the dataset outputs and a batch: finite images, no validation error (the
    factory checks), the copy drawn only where the glTF BRDF shades (the others ignore the
    layers)."""
    from vkpbr.render.layouts import View

    r = make_renderer(slab_scene(THICK), env_spec=EnvironmentSpec.small(), cache_dir=tmp_path)
    compute = {View.FINAL, View.TRANSMISSION, View.VOLUME} if r.device.compute_path else set()
    for view in View:  # the compute path shades every view with the same function: three
        for pipeline in ("forward", "compute") if view in compute else ("forward",):
            img = r.render(size=(24, 16), view=view.name.lower().replace("_", "-"),
                           pipeline=pipeline, lights=[], env=str(uniform_env))
            assert img.shape == (16, 24, 4)
    s = make_renderer(slab_scene(SLAB), env_spec=EnvironmentSpec.small(), cache_dir=tmp_path)
    for lighting, brdf in (("course", None), ("course", "gltf"), ("pbr", "ggx"), ("pbr", "gltf")):
        s.render(size=(24, 16), lighting=lighting, brdf=brdf)
        layered = lighting == "pbr" and brdf == "gltf"
        assert s.screen_transmission(RenderOptions(lighting=lighting, brdf=brdf)) == layered
        assert s.opaque_copies.size == (32 if layered else 0)  # made on the first frame that draws it
    out = r.render(size=(24, 16), outputs=("color", "depth", "instance", "normal"), lights=[])
    assert np.isfinite(out["depth"]).any()
    views = r.render_batch([CAMERA] * 3, size=(24, 16), linear=True, lights=[])
    assert np.isfinite(np.asarray(views)).all()
    msaa = make_renderer(slab_scene(SLAB), msaa=4, env_spec=EnvironmentSpec.small(), cache_dir=tmp_path)
    assert np.isfinite(msaa.render(size=(24, 16), linear=True, lights=[])).all()


def test_the_copy_holds_no_rasteriser_buffers(make_renderer, uniform_env: Path, tmp_path: Path) -> None:
    """The copies are drawn with the raster units' visibility pass: the compute path makes
    them none of the compute rasteriser's per-target buffers (12 bytes a scene triangle)."""
    r = make_renderer(slab_scene(SLAB), env_spec=EnvironmentSpec.small(), cache_dir=tmp_path)
    if not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    render(r, "final", "compute", env=str(uniform_env))
    cs = r.compute_scene()
    made = [cs._targets[id(t)] for t in r.opaque_copies.targets if id(t) in cs._targets]
    assert made and all(res.raster.size == 16 and res.raster_big.size == 16 for res in made)


DISPERSIVE = dataclasses.replace(THICK, dispersion=20.0)  # iors 1.4, 1.8, 2.2


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_dispersion_refracts_each_channel_at_its_own_index(make_renderer, uniform_env: Path,
                                                           tmp_path: Path, pipeline: str) -> None:
    """KHR_materials_dispersion on the thick slab: each channel shows what is behind where
    its own refracted ray (ior - s, ior, ior + s; ref.dispersion_iors) leaves the volume,
    against the mirror's ray casts channel by channel; the card's edge lands on different
    pixels in red and blue."""
    layers = ref.Layers.of(DISPERSIVE)
    iors = ref.dispersion_iors(layers)
    assert iors == pytest.approx((1.4, 1.8, 2.2))
    p, n, v = slab_geometry()
    sides = [seen_behind(ref.transmission_exit(p, n, v, dataclasses.replace(layers, ior=ior)))
             for ior in iors]
    behind = np.stack([sides[i][..., i] for i in range(3)], -1)
    edges = [s[..., 0] != L_ENV for s in sides]
    assert (edges[0] != edges[2]).sum() >= 3 * H  # the channels see different places
    r = make_renderer(slab_scene(DISPERSIVE), env_spec=EnvironmentSpec.small(), cache_dir=tmp_path)
    if pipeline == "compute" and not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    got = render(r, "transmission", pipeline, env=str(uniform_env), env_background=False)
    k_d = diffuse_weight(make_renderer, uniform_env, tmp_path, DISPERSIVE)
    want = mirrored_transmission(DISPERSIVE, k_d, behind)
    keep = np.logical_and.reduce([away_from_edges(s) for s in sides])
    assert keep.sum() > 0.5 * W * H
    np.testing.assert_allclose(got[keep], want[keep], rtol=1e-2, atol=1e-4)
