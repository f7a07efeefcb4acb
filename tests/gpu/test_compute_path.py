"""The compute path (render/compute_path.py) renders what the fragment path renders.

Every frame is rendered both ways by one Renderer and compared channel by channel on the
8-bit (sRGB) image: mean difference <= 1/255 and 99th percentile <= 3/255 (issue 13's bound;
the compute path's barycentrics come from a ray-triangle intersection in float32 and its
texture gradients from ray differentials instead of 2x2 quads, so edge and mip-boundary
pixels may differ by a step or two). The scenes cover the inputs the two paths read
differently: the built-in chart (vertex colours, blended and masked materials), glTF sample
models (textures with transforms, normal maps, double-sided and mirrored geometry), every
debug view, every TBN stream, alpha masking off, both lighting modes. The NumPy-reference
tests of both paths are in test_reference.py (parametrised by pipeline).
"""

from __future__ import annotations

import numpy as np
import pytest

from vkpbr.errors import UsageError
from vkpbr.render.layouts import PipelinePath, TbnMode, View
from vkpbr.render.options import RenderOptions
from vkpbr.render.paths import PATHS, RASTER_STEPS, STEP_NAMES

SIZE = (96, 72)


def assert_same(forward: np.ndarray, compute: np.ndarray, what: str) -> None:
    d = np.abs(forward[..., :3].astype(np.int32) - compute[..., :3].astype(np.int32))
    mean, p99 = d.mean(), np.percentile(d, 99)
    assert mean <= 1.0 and p99 <= 3.0, f"{what}: mean {mean:.3f}, p99 {p99}, max {d.max()}"


def both(r, **options) -> tuple[np.ndarray, np.ndarray]:  # noqa: ANN001
    f = r.render(size=SIZE, pipeline="forward", **options)
    c = r.render(size=SIZE, pipeline="compute", **options)
    return f, c


@pytest.fixture(scope="module")
def chart():
    from vkpbr.render.renderer import Renderer

    with Renderer(validation=True) as r:
        if not r.device.compute_path:
            pytest.skip(f"{r.device.info.name} lacks the compute path's features")
        yield r
        assert r.device.instance.errors == []


@pytest.mark.parametrize("lighting", ["pbr", "course"])
@pytest.mark.parametrize("view", [v.label for v in View])
def test_every_view_matches(chart, view: str, lighting: str) -> None:  # noqa: ANN001
    assert_same(*both(chart, view=view, lighting=lighting), f"{view} ({lighting})")


@pytest.mark.parametrize("tbn", [m.label for m in TbnMode])
def test_every_tbn_stream_and_no_alpha_mask(chart, tbn: str) -> None:  # noqa: ANN001
    assert_same(*both(chart, tbn=tbn, view="mapped-normal"), f"tbn {tbn}")
    assert_same(*both(chart, tbn=tbn, alpha_mask=False), f"tbn {tbn}, no alpha mask")


def test_linear_output_matches(chart) -> None:  # noqa: ANN001
    f = chart.render(size=SIZE, pipeline="forward", linear=True)
    c = chart.render(size=SIZE, pipeline="compute", linear=True)
    covered = np.isfinite(f).all(-1)
    np.testing.assert_allclose(np.median(np.abs(f - c)[covered]), 0.0, atol=1e-3)


def test_cameras_anywhere(chart) -> None:  # noqa: ANN001
    """Cameras around, above and inside the chart: the pixel rays of the compute path follow
    every view-projection the fragment path uses."""
    rng = np.random.default_rng(3)
    for eye in rng.uniform(-6, 6, (6, 3)):
        cam = f"{eye[0]:.3f},{abs(eye[1]) + 0.2:.3f},{eye[2]:.3f},0,0.5,0"
        f = chart.render(cam, size=SIZE, pipeline="forward")
        c = chart.render(cam, size=SIZE, pipeline="compute")
        assert_same(f, c, f"camera {cam}")


@pytest.mark.parametrize("model", ["DamagedHelmet", "NormalTangentMirrorTest",
                                   "TextureCoordinateTest", "AlphaBlendModeTest"])
def test_sample_models_match(make_renderer, sample_scene, model: str) -> None:  # noqa: ANN001
    r = make_renderer(sample_scene(model))
    if not r.device.compute_path:
        pytest.skip("no compute path on this device")
    for lighting in ("pbr", "course"):
        assert_same(*both(r, lighting=lighting), f"{model} ({lighting})")


def test_asking_for_compute_where_it_cannot_run_is_one_line(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer(msaa=4)
    with pytest.raises(UsageError, match="single-sample") as info:
        r.render(size=(32, 24), pipeline="compute")
    assert "\n" not in str(info.value)
    assert r.render(size=(32, 24), pipeline="auto").shape == (24, 32, 4)  # auto: forward


def test_auto_takes_the_compute_path_where_it_can(make_renderer) -> None:  # noqa: ANN001
    """auto: compute on a single-sample offscreen target of a device that has the compute
    path (GPUs and, since session 26, CPUs: lavapipe measured it 1.6-2x the fragment path),
    forward with MSAA (docs/compute-path.md); the explicit choices are obeyed."""
    r = make_renderer()
    target = r.offscreen_target((32, 24))
    assert r.uses_compute(target, RenderOptions(pipeline=PipelinePath.AUTO)) == bool(
        r.device.compute_path)
    assert not r.uses_compute(target, RenderOptions(pipeline=PipelinePath.FORWARD))
    if r.device.compute_path:
        assert r.uses_compute(target, RenderOptions(pipeline=PipelinePath.COMPUTE))
    m = make_renderer(msaa=4)
    assert not m.uses_compute(m.offscreen_target((32, 24)), RenderOptions(pipeline=PipelinePath.AUTO))


@pytest.mark.parametrize("raster", ["hardware", "compute"])
def test_compute_timings_have_every_step(chart, raster) -> None:  # noqa: ANN001
    """Every timed step of the frame's path is timed (the compute rasteriser's kernels, the
    classification, the shading: render/paths.py), each >= 0, together the frame."""
    if raster == "compute" and not chart.device.compute_raster:
        pytest.skip("this device lacks 64-bit storage atomics (the compute rasteriser)")
    list(chart.render_many([None] * 4, size=SIZE, pipeline="compute", raster=raster))
    stats = chart.last_stats
    path = "compute_raster" if raster == "compute" else "compute"
    wanted = {"shadows", "transmission", "ao", "classify", "shading", "background", "blend",
              "copy"}
    wanted |= {*RASTER_STEPS} if raster == "compute" else {"opaque", "opaque_double", "mask"}
    assert "raster" in PATHS[path] or raster == "hardware"
    assert set(stats.pass_ms) == wanted, stats.pass_ms
    assert list(stats.pass_ms) == [n for n in STEP_NAMES if n in wanted]  # in frame order
    assert all(v >= 0.0 for v in stats.pass_ms.values()), stats.pass_ms
    assert sum(stats.pass_ms.values()) == pytest.approx(stats.gpu_ms, rel=1e-6, abs=1e-6)


def test_both_classification_kernels_agree(chart) -> None:  # noqa: ANN001
    """The GPUs' subgroup-aggregated binning and the CPUs' one-atomic-a-pixel binning
    (classify.comp) give the same image (lavapipe runs both here)."""
    scene = chart.compute_scene()
    default = scene.aggregate
    try:
        images = []
        for aggregate in (True, False):
            scene.aggregate = aggregate
            chart.recorder.free()  # recorded buffers name the kernels
            images.append(chart.render(size=SIZE, pipeline="compute"))
    finally:
        scene.aggregate = default
        chart.recorder.free()
    assert np.array_equal(images[0], images[1])


def _many_materials_scene(grid: int = 32, materials: int = 48):  # noqa: ANN202
    """A grid x grid wall of quads facing the camera, each quad one of `materials` materials
    (a draw each), so that a 16x16 tile of the classification holds more materials than it
    has shared slots (classify.comp LOCAL_SLOTS): both of its ways of adding get used."""
    from vkpbr.scene.types import Camera, Material, Mesh, Node, Scene

    cells = np.stack(np.meshgrid(np.arange(grid), np.arange(grid), indexing="ij"), -1).reshape(-1, 2)
    of = (cells[:, 0] * 7 + cells[:, 1] * 13) % materials
    corners = np.float32([[0, 0], [1, 0], [1, 1], [0, 1]])
    meshes = []
    for m in range(materials):
        mine = cells[of == m].astype(np.float32)
        xy = (mine[:, None, :] + corners[None]) * (2.0 / grid) - 1.0
        pos = np.concatenate([xy, np.zeros((*xy.shape[:2], 1), np.float32)], -1).reshape(-1, 3)
        quads = np.arange(len(mine), dtype=np.uint32)[:, None] * 4
        indices = (quads + np.uint32([0, 1, 2, 0, 2, 3])).reshape(-1)
        meshes.append(Mesh(f"cells {m}", pos, indices, normals=np.tile(np.float32([0, 0, 1]), (len(pos), 1)),
                           texcoords=np.zeros((len(pos), 2), np.float32), material=m))
    colours = np.random.default_rng(1).uniform(0.05, 1.0, (materials, 3))
    return Scene("many materials", meshes=meshes,
                 materials=[Material(base_color_factor=(*map(float, c), 1.0)) for c in colours],
                 nodes=[Node(m) for m in range(materials)],
                 cameras=[Camera(eye=(0.0, 0.0, 1.5), target=(0.0, 0.0, 0.0), yfov_deg=60.0)])


@pytest.mark.parametrize("raster", ["hardware", "compute"])
@pytest.mark.parametrize("materials", [48, 300])
def test_classification_bins_every_pixel_once(make_renderer, materials: int, raster: str) -> None:  # noqa: ANN001
    """Both binnings (classify.comp: per tile in shared memory, with per-subgroup adds for
    the materials a tile has no slot for; and one atomic a pixel) list each covered pixel
    exactly once, in its material's bin, and the images agree with the forward path's (300
    materials: the offsets' prefix sum takes two chunks). With the compute rasteriser its
    resolve counts the bins (bin_tiles.glsl) and the classification scatters."""
    r = make_renderer(_many_materials_scene(materials=materials))
    if not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    if raster == "compute" and not r.device.compute_raster:
        pytest.skip(f"{r.device.info.name} lacks 64-bit storage atomics")
    scene = r.compute_scene()
    size = (96, 80)
    target = r.offscreen_target(size)
    forward = r.render(size=size, pipeline="forward", view="base_color")
    listed = []
    for aggregate in (True, False):
        scene.aggregate = aggregate
        r.recorder.free()  # recorded buffers name the kernels
        image = r.render(size=size, pipeline="compute", raster=raster, view="base_color")
        assert_same(forward, image, f"aggregate {aggregate}")
        bins = scene.pixel_bins(target)
        assert sum(map(len, bins)) > 0.9 * size[0] * size[1]
        assert sum(len(b) > 0 for b in bins) > 0.9 * materials  # (and the default material)
        every = np.concatenate(bins)
        assert len(np.unique(every)) == len(every), "a pixel listed twice"
        listed.append([np.sort(b) for b in bins])
    for m, (tiles, plain) in enumerate(zip(*listed, strict=True)):
        assert np.array_equal(tiles, plain), f"material {m}: the two binnings differ"
