"""GTAO (render/ao.py) on multisampled frames (paths.py "forward_ao": a depth pre-pass whose
resolved depth -- each pixel's sample 0 -- GTAO reads, then the passes). The other paths:
the layered batch in test_ao.py (test_forward_and_compute_paths_agree: its views equal
render(pipeline="forward") bit for bit, GTAO on) and test_batch.py (B=7, the chart's masked
and blended materials); windows in tests/viewer/test_viewer.py (a window's GTAO frame
equals `render`'s bit for bit).

On test_ao.py's box corner (64 x 48, radius 0.5, `gtao`), lavapipe, off the edge band:

    msaa 4 "ao" view against    mean     p95      bound (mean, p95)
    the compute path's `ao`     0.0068   0.033    0.01, 0.045
    the ray-cast reference      0.026    0.142    0.035, 0.16  (compute path: 0.023, 0.118)

The multisampled frame's GTAO differs from the compute path's by its depths only: sample 0
lies (-1/8, -3/8) of a pixel from the centre GTAO reconstructs it at, so the depth image is
the scene shifted by that fraction of a pixel -- against the reference, cast through the
pixels' centres, the creases move by it (the p95 rises there; the mean by 0.003).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from ao_reference import first_hits, scene_triangles, visibility
from test_ao import RADIUS, H, W, corner, edge_band

from vkpbr.render import ao as AO


@pytest.fixture(scope="module")
def renderers() -> Iterator[dict[int, object]]:
    """The corner with 1 and 4 samples a pixel (validation and synchronization validation
    on: any error fails at teardown)."""
    from vkpbr.render.renderer import Renderer

    scene, _ = corner()
    made = {n: Renderer(scene, validation=True, sync_validation=True, msaa=n) for n in (1, 4)}
    yield made
    for r in made.values():
        instance = r.device.instance
        r.close()
        assert instance.errors == [], instance.errors[:3]


def test_msaa_frames_take_gtao(renderers) -> None:  # noqa: ANN001
    """A 4x frame's GTAO (its "ao" view, float) against the compute path's `ao` and the ray
    cast reference off the edge band; and its image-based light occluded as the compute path
    does (the ibl-diffuse view is the one without GTAO times GTAO's multi-bounce)."""
    scene, cam = corner()
    kw = {"camera": cam, "size": (W, H), "ao_radius": RADIUS, "linear": True}
    msaa = renderers[4].render(view="ao", **kw)[..., 0]
    out = renderers[1].render(camera=cam, size=(W, H), outputs=("ao", "depth"),
                              pipeline="compute", ao_radius=RADIUS)
    tris = scene_triangles(scene)
    p, n, hit = first_hits(cam, W, H, tris)
    keep = hit & ~edge_band(out["depth"])
    d = np.abs(msaa - out["ao"])[keep]
    ref = visibility(p[keep], n[keep], tris, RADIUS, AO.FALLOFF)
    e = np.abs(msaa[keep] - ref)
    print(f"msaa vs compute: mean {d.mean():.4f} p95 {np.percentile(d, 95):.4f}; "
          f"vs reference: mean {e.mean():.4f} p95 {np.percentile(e, 95):.4f}")
    assert d.mean() <= 0.01 and np.percentile(d, 95) <= 0.045
    assert e.mean() <= 0.035 and np.percentile(e, 95) <= 0.16
    on = renderers[4].render(view="ibl-diffuse", **kw)[..., 0]
    off = renderers[4].render(view="ibl-diffuse", ao="off", **kw)[..., 0]
    a, b, c = 2.0404 - 0.3324, -4.7951 + 0.6417, 2.7552 + 0.6903
    bounce = np.maximum(msaa, ((msaa * a + b) * msaa + c) * msaa)
    # (two pixels off the band: a pixel's samples may straddle a silhouette its 4-neighbours'
    # depths do not show, where the resolve averages lit and unlit samples)
    inner = keep.copy()
    for axis in (0, 1):
        for shift in (1, -1):
            inner &= np.roll(keep, shift, axis)
    lit = inner & (off > 0.05)
    assert lit.mean() > 0.5 and (msaa[lit] < 0.9).any()
    np.testing.assert_allclose(on[lit], (off * bounce)[lit], rtol=2e-3, atol=2e-3)


def test_the_upsample_may_run_the_last_denoise_pass(renderers) -> None:  # noqa: ANN001
    """AoImages.fuse (benchmarks/bench_ao.py --fuse): the half-resolution presets' last
    denoise pass run by the upsample gives the same `ao` but for the 16 bits the working
    image keeps between them (measured 7.7e-6 on the corner and the sphere; their errors
    against the reference unchanged to 4 decimals), with no kernel of its own."""
    r, (_, cam) = renderers[1], corner()
    kw = {"camera": cam, "size": (W, H), "outputs": ("ao",), "pipeline": "compute",
          "ao_radius": RADIUS}
    apart = r.render(**kw)["ao"]
    r.device.wait_idle()
    r.parts.recorder.free()  # (its recordings run the pass apart)
    r.parts.ao.fuse, r.parts.ao.profile = True, True
    try:
        fused = r.render(**kw)["ao"]
        assert not any(k.startswith("ao_denoise") for k in r.last_stats.pass_ms)
    finally:
        r.device.wait_idle()
        r.parts.recorder.free()
        r.parts.ao.fuse, r.parts.ao.profile = False, False
    assert (apart < 0.9).any()
    assert np.abs(fused - apart).max() <= 2.0 / 65535.0


def mip_levels(depth: np.ndarray, radius: float, levels: int) -> tuple[list[np.ndarray], int]:
    """XeGTAO's depth MIPs (XeGTAO_DepthMIPFilter) of a frame's view-space `depth` (inf where
    nothing was drawn) in NumPy: level k's texel is the weighted mean of its 2 x 2 children of
    level k - 1 that lie in the frame (their first pixel), each weighted by how far it is in
    front of the farthest (0 beyond 0.75 of the search radius `radius`); and how many
    children took a weight strictly between 0 and 1 (the test sees the filter's falloff)."""
    partial = 0
    out = [np.minimum(depth, 3.0e38).astype(np.float64)]
    h, w = depth.shape
    r = 0.75 * radius
    rng = AO.FALLOFF * r
    for k in range(1, levels):
        prev = out[-1]
        th, tw = -(-h // (1 << k)), -(-w // (1 << k))
        kids = np.full((4, th, tw), np.nan)
        for i, (dy, dx) in enumerate(((0, 0), (0, 1), (1, 0), (1, 1))):
            sub = prev[dy::2, dx::2][:th, :tw]
            kids[i, :sub.shape[0], :sub.shape[1]] = sub
        present = ~np.isnan(kids)
        far = np.nanmax(kids, axis=0)
        wgt = np.clip((far - kids) * (-1.0 / rng) + r * (1 - AO.FALLOFF) / rng + 1.0, 0, 1)
        wgt = np.where(present, wgt, 0.0)
        partial += int(((wgt > 0.01) & (wgt < 0.99) & (far < 3.0e38)).sum())
        mean = far + np.nansum(wgt * (kids - far), axis=0) / wgt.sum(axis=0)
        out.append(np.minimum(mean, 3.0e38))
    return out, partial


@pytest.mark.parametrize("raster", ["hardware", "compute"])
def test_depth_mips_are_xegtaos_filter(renderers, raster: str) -> None:  # noqa: ANN001
    """ao_prefilter.comp's levels against mip_levels' NumPy over the frame's `depth` output,
    at a size no level divides (texels past the frame's edge average the children inside);
    from the depth image (the hardware raster) and from the compute rasteriser's buffer
    (its AO_DEPTH_BUFFER build: no copy into the depth image)."""
    from vkpbr.gpu.image_io import read_level

    r, (_, cam) = renderers[1], corner()
    # (a radius at which some children fall in the weights' falloff: 177 of 2546)
    size, radius = (W - 13, H - 11), 0.1  # 51 x 37
    depth = r.render(camera=cam, size=size, outputs=("depth",), pipeline="compute",
                     raster=raster, ao_radius=radius)["depth"]
    r.device.wait_idle()
    want, partial = mip_levels(depth, radius * AO.RADIUS_MULTIPLIER, AO.DEPTH_MIPS)
    # The `depth` output is the shading's (its interpolated point), the MIPs' the raster's
    # depths: within 2e-6 on lavapipe, 7.7e-5 apart (relative) with the H200's raster units
    # (runs w, y: their depth interpolation is not the shading's).
    rtol = 2e-4
    assert partial > 100
    image = r.parts.ao.mips[0]
    for k, ref in enumerate(want):
        got = read_level(r.device, image, k, dtype=np.float32, channels=1)[0, ..., 0]
        got = got[:ref.shape[0], :ref.shape[1]]
        assert (ref < 3.0e38).any() and (ref >= 3.0e38).any(), k  # surfaces and background
        np.testing.assert_allclose(got, ref, rtol=rtol, err_msg=f"level {k}")


def _mip_block(r, at: tuple[int, int], size: int = 64) -> list[np.ndarray]:  # noqa: ANN001
    """Each level of the depth MIPs' block whose level-0 corner is `at` (x, y)."""
    from vkpbr.gpu.image_io import read_level

    r.device.wait_idle()
    out = []
    for k in range(AO.DEPTH_MIPS):
        level = read_level(r.device, r.parts.ao.mips[0], k, dtype=np.float32, channels=1)[0, ..., 0]
        y, x, n = at[1] >> k, at[0] >> k, size >> k
        out.append(level[y:y + n, x:x + n])
    return out


def test_batch_views_take_their_tiles_mips(renderers) -> None:  # noqa: ANN001
    """A compute batch's views in tiles no MIP level divides (60 x 50 in a 3 x 3 grid) with a
    radius whose samples read levels 1 to 3 (8: up to about 100 pixels): each tile's MIP
    block equals the view's own, rendered alone (ao_common.glsl ao_mip_base: each tile's MIPs
    group its own pixels; with one grid over the atlas they did not, 0.041 in GTAO in one
    view of 8), and so does its GTAO, to the 16 bits of the working image. (Until the compute
    rasteriser covered a view in its tile's own pixels, the batch's depths were a few ulps
    off the frame's, 7e-7 in view-space depth on lavapipe, which GTAO's edges and normals at
    the tiles' borders made up to 103/65535 on the H200: session 15, runs z2, z3, gpu5.)"""
    from test_batch import cameras_of

    r = renderers[1]
    if r.compute_batch_unavailable() is not None:
        pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
    cams = cameras_of(r, 8, seed=3)
    kw = {"pipeline": "compute", "ao_radius": 8.0, "view": "ao", "linear": True}
    batch = r.render_batch(cams, (60, 50), **kw)
    assert "ao" in r.last_stats.pass_ms  # (the compute batch, GTAO in its atlas)
    rows = r.parts.ao.mips[0].height // 64  # (tiles a column: 64 x 64 blocks)
    blocks = [_mip_block(r, (64 * (i // rows), 64 * (i % rows))) for i in range(len(cams))]
    bound = 2.0 / 65535.0
    for i, cam in enumerate(cams):
        one = r.render(camera=cam, size=(60, 50), raster="compute", **kw)
        for k, (got, want) in enumerate(zip(blocks[i], _mip_block(r, (0, 0)), strict=True)):
            np.testing.assert_allclose(got, want, rtol=1e-5, err_msg=f"view {i} level {k}")
        d = np.abs(batch[i] - one)
        assert d.max() <= bound, (i, float(d.max()) * 65535, int((d > bound).sum()))
