"""Shadow maps drawn by compute shaders (render/shadow_raster.py, shadow_raster="compute")
against the raster units' (shadow_raster="hardware"), on lavapipe with validation and
synchronization validation on.

Bounds (measured on lavapipe, Mesa 22.3, in brackets):
- coverage: the texels one draws and the other does not, <= 0.2% of a layer [0 - 0.003%]:
  the raster units' top-left rule and 1/256-texel snapping against exact centre tests.
- depth where both draw, bias included, away from a depth step or the coverage's border:
  |difference| <= 2e-6 on 99% of the texels [p99 1.2e-7]; over 1e-5 on at most 0.2% of a layer's texels [texel centres on an edge between
  two surfaces at different depths, which the two rules give to different sides;
  alpha-tested texels on a hole's border, where the two samplings' gradients differ] and at
  most 0.1% of those away from a depth step or the coverage's border [0].
- images lit through them (8-bit): mean <= 0.25/255 and p99 <= 1/255 [0 and 0].
The shading reads the compute-drawn maps from the kernels' depth buffer by hand (no copy into
the images: shaders/shadow_sampling.glsl hand_compare). Measured on lavapipe, whose sampler
filters these D32 images nearest (hand_compare then does too): linear float frames of a sun,
a spot, a point light and all three, at 256 and 512 texels, on the fragment and the compute
frame path and both batches, equal bit for bit those of the copy into the images it replaced
and those of the raster units' maps (the bounds above stay the test's, for GPUs).
On GPUs the depth bounds also allow the slope-scaled bias's own spread: Vulkan lets the
raster units take m as sqrt(dz/dx^2 + dz/dy^2) or approximate it by the larger of the two
(what lavapipe and shadow_raster.comp do), so a difference of up to (sqrt 2 - 1) x |slope
factor| x m (m from the map's own gradient) is the spec's, not an error.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from shadow_scenes import BLOCK, CAMERA, CARD, GROUND, LIGHTS, rect_scene

SIZE = (96, 72)
ALL = [LIGHTS["directional"], LIGHTS["spot"], LIGHTS["point"]]
MOVED = dataclasses.replace(CAMERA, eye=(1.5, 4.0, 5.0))


def _maps(r, camera, lights, mode: str, **opts):  # noqa: ANN001, ANN202
    """The frame's image and every layer of its maps, drawn `mode` from scratch."""
    r.shadows.forget()
    image = r.render(camera, lights, size=SIZE, shadow_raster=mode, **opts)
    assert r.shadows.compute == (mode == "compute")
    return image, *r.shadows.read_maps()


def _compare_layers(a: np.ndarray, b: np.ndarray, label: str, r, min_inner: float = 0.02  # noqa: ANN001
                    ) -> None:
    """Layers `a` (the raster units') and `b` (compute) within the bounds above; `r` the
    renderer (on a GPU the slope bias's spread is allowed)."""
    from vkpbr.render.shadows import DEPTH_BIAS

    slope_factor = max(abs(s) for _, s in DEPTH_BIAS.values())
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        xor = (x > 0) != (y > 0)
        assert xor.mean() <= 0.002, (label, i, xor.mean())
        both = (x > 0) & (y > 0)
        if not both.any():
            continue
        d = np.abs(x - y)
        if r.device.info.kind != "cpu":
            gy, gx = np.gradient(x.astype(np.float64))
            d = np.maximum(d - (np.sqrt(2) - 1) * slope_factor * np.maximum(abs(gx), abs(gy)) * 1.01, 0)
        inner = both & ~_edges(x)
        far = (d > 1e-5)
        if inner.any():
            assert np.percentile(d[inner], 99) <= 2e-6, (label, i, np.percentile(d[inner], 99))
        assert inner.mean() >= min_inner, (label, i, inner.mean())  # the test sees planes
        assert far.mean() <= 0.002 and (far & inner).sum() <= 0.001 * max(inner.sum(), 1), (
            label, i, far.mean(), far[inner].mean())


def _edges(x: np.ndarray) -> np.ndarray:
    """Texels within one of a depth step (a second difference over 1e-5 along a row, a
    column or a diagonal: a plane's is ~0) or of the coverage's border."""
    p = np.pad(x, 2, mode="edge")
    h, w = x.shape

    def at(dy: int, dx: int) -> np.ndarray:
        return p[2 + dy:2 + dy + h, 2 + dx:2 + dx + w]

    step = np.zeros(x.shape, bool)
    for dy, dx in ((0, 1), (1, 0), (1, 1), (1, -1)):
        step |= np.abs(at(dy, dx) - 2 * x + at(-dy, -dx)) > 1e-5
    near = np.stack([at(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1)])
    grown = np.stack([np.pad(step, 1)[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]
                      for dy in (-1, 0, 1) for dx in (-1, 0, 1)]).any(0)
    return grown | ((near > 0).any(0) != (near > 0).all(0))


def _compare_images(a: np.ndarray, b: np.ndarray, label: str) -> None:
    d = np.abs(a.astype(np.int16) - b.astype(np.int16))[..., :3]
    assert d.mean() <= 0.25 and np.percentile(d, 99) <= 1, (label, d.mean(), np.percentile(d, 99))


@pytest.fixture(scope="module")
def renderer():
    from vkpbr import Renderer

    r = Renderer(rect_scene((GROUND, BLOCK, CARD)), validation=True, sync_validation=True)
    r.shadows.readable = True  # made readable with the first maps of another size
    yield r
    instance = r.device.instance
    r.close()
    assert instance.errors == [], instance.errors[:3]


@pytest.mark.parametrize("alpha_mask", [True, False])
def test_every_layer_equals_the_raster_units(renderer, alpha_mask: bool) -> None:  # noqa: ANN001
    """Cascades, a spot map and a point light's six faces, with the masked card's hole cut
    out (alpha_mask) or drawn whole; at a size where the ground is a big triangle (listed in
    bands for work groups) and where the card's triangles are too (the masked kernel's
    group)."""
    for res in (256, 512):
        opts = {"shadow_resolution": res, "env": "none", "alpha_mask": alpha_mask}
        hard = _maps(renderer, CAMERA, ALL, "hardware", **opts)
        comp = _maps(renderer, CAMERA, ALL, "compute", **opts)
        _compare_layers(hard[1][:6], comp[1][:6], f"2D layers at {res}", renderer)
        _compare_layers(hard[2][:6], comp[2][:6], f"cube faces at {res}", renderer)
        _compare_images(hard[0], comp[0], f"image at {res}")
        # The layers hold something: the ground under every cascade, the card's hole.
        assert all((layer > 0).mean() > 0.1 for layer in comp[1][:5])
    hole = _maps(renderer, CAMERA, [LIGHTS["spot"]], "compute", shadow_resolution=256,
                 env="none", alpha_mask=alpha_mask)
    whole = _maps(renderer, CAMERA, [LIGHTS["spot"]], "compute", shadow_resolution=256,
                  env="none", alpha_mask=not alpha_mask)
    assert not np.array_equal(hole[1][0], whole[1][0])  # the cut-out changes the spot map


def test_partial_redraws_and_the_choice(renderer) -> None:  # noqa: ANN001
    """A camera that moves redraws only the sun's cascades, by compute shaders, and they
    equal the raster units' all the same; "auto" is the raster units on a CPU and the
    compute kernels on a GPU (where the frame path recorded nothing else)."""
    opts = {"shadow_resolution": 256, "env": "none"}
    renderer.render(CAMERA, ALL, size=SIZE, shadow_raster="compute", **opts)
    renderer.render(MOVED, ALL, size=SIZE, shadow_raster="compute", **opts)
    assert dict(renderer.shadows.last_redraw) == {"directional": True, "spot": False,
                                                  "point": False}
    moved = renderer.shadows.read_maps()
    hard = _maps(renderer, MOVED, ALL, "hardware", **opts)
    _compare_layers(hard[1][:5], moved[0][:5], "moved camera", renderer)
    _compare_layers(hard[2][:6], moved[1][:6], "kept cube", renderer)
    renderer.render(CAMERA, ALL, size=SIZE, shadow_raster="auto", **opts)
    on_cpu = renderer.device.info.kind == "cpu"
    assert renderer.shadows.compute is not on_cpu, renderer.device.info.kind
    from vkpbr.errors import UsageError

    with pytest.raises(UsageError):
        renderer.render(CAMERA, ALL, size=SIZE, shadow_raster="fast", **opts)
    # Every layer's depths in one storage binding: lavapipe's is 128 MiB, 4 x 4096^2 x 4 bytes
    # are not, a one-line error (and the renderer draws on after it).
    limit = int(renderer.device.limits.maxStorageBufferRange)
    if limit < 4 * 4 * 4096 ** 2:
        with pytest.raises(UsageError, match="shadow-resolution"):
            renderer.render(CAMERA, [LIGHTS["directional"]], size=SIZE, shadow_raster="compute",
                            shadow_resolution=4096, env="none")
    renderer.render(CAMERA, ALL, size=SIZE, shadow_raster="compute", **opts)


def test_a_moving_caster_redraws(renderer) -> None:  # noqa: ANN001
    """The block moved through the scene state: the compute-drawn maps follow it (the frame
    after the move differs from the one before and equals the raster units' of the moved
    scene), with no map forgotten by hand."""
    opts = {"shadow_resolution": 256, "env": "none", "shadow_raster": "compute"}
    before = renderer.render(CAMERA, ALL, size=SIZE, **opts)
    lifted = np.eye(4)
    lifted[:3, 3] = (0.6, 0.5, -0.4)
    renderer.set_pose(1, lifted)  # node 1: the block
    try:
        after = renderer.render(CAMERA, ALL, size=SIZE, **opts)
        assert dict(renderer.shadows.last_redraw) == {"directional": True, "spot": True,
                                                      "point": True}
        maps = renderer.shadows.read_maps()
        hard = _maps(renderer, CAMERA, ALL, "hardware", shadow_resolution=256, env="none")
        assert not np.array_equal(before, after)
        _compare_images(hard[0], after, "moved block")
        _compare_layers(hard[1][:5], maps[0][:5], "moved block 2D", renderer)
        _compare_layers(hard[2][:6], maps[1][:6], "moved block cube", renderer)
    finally:
        renderer.set_pose(1, np.eye(4))


def test_skinned_casters(make_renderer, sample_scene) -> None:  # noqa: ANN001
    """CesiumMan posed by the deform step casts the same shadow either way, and its shadow
    moves with the animation (the posed vertices, not the bind pose)."""
    from vkpbr import Camera

    scene = sample_scene("CesiumMan")
    r = make_renderer(scene)
    r.shadows.readable = True
    lo, hi = (np.asarray(v, float) for v in scene.bounds())
    centre = (lo + hi) / 2
    cam = Camera(eye=tuple(centre + np.array([0.0, 1.0, 2.5]) * (hi - lo).max()),
                 target=tuple(centre))
    sun = [dataclasses.replace(LIGHTS["directional"])]
    spot = dataclasses.replace(LIGHTS["spot"], position=tuple(centre + [0.0, 0.0, 2.0 * (hi - lo).max()]),
                               direction=(0.0, 0.0, -1.0), outer_cone=0.7)
    lights = [sun[0], spot]
    got = {}
    for t in (0.3, 1.1):
        for mode in ("hardware", "compute"):
            r.shadows.forget()
            image = r.render(cam, lights, size=SIZE, time=t, shadow_raster=mode,
                             shadow_resolution=256, env="none")
            got[t, mode] = (image, r.shadows.read_maps(cubes=False)[0])  # (no cube: its stand-in is not readable)
        _compare_layers(got[t, "hardware"][1][:5], got[t, "compute"][1][:5], f"CesiumMan at {t}", r,
                        min_inner=0.0)  # (a figure: few planes)
        assert (got[t, "compute"][1][4] > 0).mean() > 0.01  # the spot map sees the figure
        _compare_images(got[t, "hardware"][0], got[t, "compute"][0], f"CesiumMan at {t}")
    assert not np.array_equal(got[0.3, "compute"][1][4], got[1.1, "compute"][1][4])
    assert not np.array_equal(got[0.3, "hardware"][1][4], got[1.1, "compute"][1][4])


@pytest.mark.slow  # ~20 s on 2 shared cores (the load, lavapipe's kernels over 262 k triangles)
def test_sponza_cascades(make_renderer, assets) -> None:  # noqa: ANN001
    """Sponza (262 k triangles, alpha-masked foliage and chains) under the sun's cascades: the
    same maps either way, and the same image (its point-light cube: measured alike, p99
    4e-7, left out for time: lavapipe runs the kernels on 2 cores)."""
    from vkpbr import load_scene
    from vkpbr.scene.types import Light

    path = assets / "Sponza" / "glTF" / "Sponza.gltf"
    if not path.is_file():
        pytest.skip(f"no Sponza at {path}")
    r = make_renderer(load_scene(path))
    r.shadows.readable = True
    lights = [Light(kind="directional", direction=(0.3, -1.0, 0.2))]
    got = {}
    for mode in ("hardware", "compute"):
        r.shadows.forget()
        image = r.render(None, lights, size=(48, 32), shadow_raster=mode, shadow_resolution=256,
                         ao="off")
        got[mode] = (image, r.shadows.read_maps(cubes=False)[0])
    _compare_layers(got["hardware"][1][:4], got["compute"][1][:4], "Sponza cascades", r,
                    min_inner=0.0)
    _compare_images(got["hardware"][0], got["compute"][0], "Sponza")
    assert (got["compute"][1][0] > 0).mean() > 0.5


def test_frames_in_flight_and_batches(renderer) -> None:  # noqa: ANN001
    """render_many's frames in flight share the compute kernels' buffers (the graph orders
    each frame's first use after the frame before): a walk's frames equal the raster units'
    frame by frame; a batch's scene-wide sun map too, on the layered batch and the compute
    batch."""
    opts = {"shadow_resolution": 256, "env": "none"}
    cams = [dataclasses.replace(CAMERA, eye=(0.25 * i, 5.0, 6.0 - 0.2 * i)) for i in range(6)]
    frames = {mode: [f.copy() for f in renderer.render_many(cams, ALL, size=SIZE, shadow_raster=mode,
                                                           **opts)]
              for mode in ("hardware", "compute")}
    for i, (a, b) in enumerate(zip(frames["hardware"], frames["compute"], strict=True)):
        _compare_images(a, b, f"frame {i} of the walk")
    assert not np.array_equal(frames["compute"][0], frames["compute"][-1])
    for pipeline in ("forward", "compute"):
        views = {}
        for mode in ("hardware", "compute"):
            renderer.shadows.forget()
            views[mode] = renderer.render_batch(cams[:3], SIZE, ALL, pipeline=pipeline, ao="off",
                                                shadow_raster=mode, **opts)
            assert renderer.shadows.compute == (mode == "compute")
        _compare_images(views["hardware"], views["compute"], f"{pipeline} batch")


def test_image_frames_bind_pipelines_without_the_by_hand_reads(renderer, monkeypatch) -> None:  # noqa: ANN001
    """Shading pipelines per read (shadow_sampling.glsl SHADOW_HAND_READS, specialisation
    constant 3): a frame that reads the compute-drawn maps' buffer binds pipelines built with
    it 1 (the default); the next, whose catch-up copies every layer into the images
    (SETTLE_FRAMES 1 here) and compares in hardware, binds other pipeline objects, built with
    it 0 (the driver drops the by-hand code): the compute path's shading kernels (a 1-view
    compute batch) and the fragment path's lit passes (a frame), recorded anew; every
    recording's ShadeVariant (a compute-path frame's kernels) says the read it was made for."""
    import vkpbr.render.shadows as shadows

    cs, rec = renderer.compute_scene(), renderer.recorder
    real_kernel, real_pipeline, bound = cs._pipeline, rec.pipeline, []

    def kernel(name, push_bytes, constants=()):  # noqa: ANN001, ANN202
        pipe = real_kernel(name, push_bytes, constants)
        if name.startswith("shade_"):
            bound.append((constants[3], pipe))
        return pipe

    def pipeline(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        pipe = real_pipeline(*args, **kwargs)
        if pipe.spec.fragment_shader in ("pbr_opaque.frag.spv", "pbr_mask.frag.spv"):
            bound.append((dict(pipe.spec.fragment_constants).get(3, 1), pipe))
        return pipe

    monkeypatch.setattr(cs, "_pipeline", kernel)
    monkeypatch.setattr(rec, "pipeline", pipeline)
    monkeypatch.setattr(rec, "_recorded", {})  # (recordings made with the spies)
    monkeypatch.setattr(shadows, "SETTLE_FRAMES", 1)
    opts = {"shadow_raster": "compute", "shadow_resolution": 256, "env": "none"}
    for draw in (lambda: renderer.render_batch([CAMERA], (32, 24), ALL, pipeline="compute",
                                                ao="off", **opts),
                 lambda: renderer.render(CAMERA, ALL, size=(32, 24), pipeline="forward", **opts)):
        renderer.shadows.forget()
        seen = {}
        for _ in range(2):  # the buffer, then the images
            bound.clear()
            draw()
            assert renderer.shadows.compute and bound
            seen[renderer.shadows.reads_buffer] = list(bound)
        assert set(seen) == {True, False}, seen.keys()
        assert {c for c, _ in seen[True]} == {1} and {c for c, _ in seen[False]} == {0}, seen
        assert not {id(p) for _, p in seen[True]} & {id(p) for _, p in seen[False]}
    keys = list(rec._recorded)  # (target, image, slot, FrameSpec, reads the buffer)
    assert {k[4] for k in keys} == {True, False}
    assert all(k[3].variant.hand_reads == k[4] for k in keys), keys


def test_the_shading_reads_the_kernels_buffer(renderer, monkeypatch) -> None:  # noqa: ANN001
    """No copy step: the compute-drawn frame's shadow steps touch only the kernels' buffers,
    and their last, "shadows", hands the depth buffer to the shading (a read by compute and
    fragment shaders, the graph's barrier). The shading reads that buffer, not the images:
    the images still hold another light's maps, drawn by the raster units just before."""
    import vkpbr.render.recorder as recorder

    recorded: list[list] = []
    real = recorder.record_steps

    def spy(cmd, steps, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN202
        recorded.append(list(steps))
        return real(cmd, steps, *args, **kwargs)

    monkeypatch.setattr(recorder, "record_steps", spy)
    opts = {"shadow_resolution": 256, "env": "none"}
    away = [dataclasses.replace(LIGHTS["spot"], position=(-2.0, 3.0, -1.0)), LIGHTS["point"]]
    other = renderer.render(CAMERA, away, size=SIZE, shadow_raster="hardware", **opts)  # images: `away`'s
    spot = [LIGHTS["spot"], LIGHTS["point"]]
    recorded.clear()
    renderer.shadows.forget()
    got = renderer.render(CAMERA, spot, size=SIZE, shadow_raster="compute", **opts)
    steps = [s for s in recorded[-1] if s.name.startswith("shadows")]
    # (one pass; or, where an earlier test of this module moved a caster, the maps of those
    # that never moved drawn apart first, then copied in: no save, nothing scrolls; a pass
    # whose casters hold no masked draw has no masked kernel)
    drawing = ["shadows.clear", "shadows.move", "shadows.small", "shadows.args", "shadows.big",
               "shadows.masked", "shadows"]
    unmasked = [n for n in drawing if n != "shadows.masked"]
    names = [s.name for s in steps]
    kept = [n.replace("kept.", "") for n in names if n.startswith("shadows.kept.")]
    final = names[len(kept):]
    assert final == ["shadows.save", *drawing] if not kept else final in (drawing, unmasked), names
    assert kept in ([], ["shadows.save", *drawing[:-1]], ["shadows.save", *unmasked[:-1]]), names
    uses = {u for s in steps for _, u in s.all_uses()}
    assert not any("transfer_src" in u for u in uses), uses  # (the copy's)
    assert steps[-1].uses == (("shadow_depths", "storage_read|fragment_storage_read"),)
    want = renderer.render(CAMERA, spot, size=SIZE, shadow_raster="hardware", **opts)
    _compare_images(want, got, "over the buffer")
    assert not np.array_equal(want, other)  # (the images' maps would have shown)


def test_moving_frames_read_the_buffer_then_the_images_catch_up(renderer) -> None:  # noqa: ANN001
    """Where the shading reads compute-drawn maps (ShadowMaps._choose_reads): frames that
    redraw every layer (a caster moving each frame) read the kernels' buffer; still frames
    keep reading it for SETTLE_FRAMES - 1 frames, then every layer is redrawn and copied into
    the images, which later frames compare in hardware. The images last held the block at
    rest: without the catch-up copy the still frames would show its old shadow."""
    from vkpbr.render.shadows import SETTLE_FRAMES

    opts = {"shadow_resolution": 256, "env": "none", "shadow_raster": "compute"}
    sm = renderer.shadows
    renderer.render(CAMERA, ALL, size=SIZE, **opts)  # (the images: at rest, after SETTLE)
    for _ in range(SETTLE_FRAMES):
        renderer.render(CAMERA, ALL, size=SIZE, **opts)
    assert not sm.reads_buffer
    try:
        for k in range(3):
            lifted = np.eye(4)
            lifted[:3, 3] = (0.2 * k + 0.3, 0.5, -0.4)
            renderer.set_pose(1, lifted)
            moving = renderer.render(CAMERA, ALL, size=SIZE, **opts)
            assert sm.reads_buffer and all(n > 0 for _, n in sm.last_redrawn_layers)
        still = []
        for k in range(SETTLE_FRAMES + 1):
            still.append(renderer.render(CAMERA, ALL, size=SIZE, **opts))
            redrawn = [n for _, n in sm.last_redrawn_layers]
            if k < SETTLE_FRAMES - 1:
                assert sm.reads_buffer and not any(redrawn), (k, redrawn)
            elif k == SETTLE_FRAMES - 1:  # the catch-up: every layer again, into the images
                assert not sm.reads_buffer and all(redrawn), (k, redrawn)
            else:
                assert not sm.reads_buffer and not any(redrawn), (k, redrawn)
        for k, image in enumerate(still):
            assert np.array_equal(image, moving) if renderer.device.info.kind == "cpu" else True, k
        hard = _maps(renderer, CAMERA, ALL, "hardware", shadow_resolution=256, env="none")
        _compare_images(hard[0], still[-1], "images after the catch-up")
        renderer.set_pose(1, np.eye(4))
        assert renderer.render(CAMERA, ALL, size=SIZE, **opts) is not None
        assert sm.reads_buffer  # a moved caster: the buffer again at once, no copy
    finally:
        renderer.set_pose(1, np.eye(4))


def test_a_lone_redraw_of_every_layer_for_new_matrices_copies_them(renderer) -> None:  # noqa: ANN001
    """ShadowMaps._choose_reads: a frame that redraws every layer because every matrix moved
    (the sun turned a little, as a walking camera whose cascades all cross their grid at
    once), its casters still, copies the layers into the images and compares in hardware (no
    buffer reads, so no catch-up redraw SETTLE_FRAMES on); its image is the raster units'
    from scratch. A second such frame in a row reads the buffer (a light moving every frame)."""
    from vkpbr.render.shadows import SETTLE_FRAMES

    opts = {"shadow_resolution": 256, "env": "none", "shadow_raster": "compute"}
    sm = renderer.shadows
    sun = LIGHTS["directional"]
    for _ in range(SETTLE_FRAMES + 1):  # (settled: the images)
        renderer.render(CAMERA, [sun], size=SIZE, **opts)
    assert not sm.reads_buffer
    turned = [dataclasses.replace(sun, direction=tuple(np.add(sun.direction, (0.05, 0.0, 0.02))))]
    got = renderer.render(CAMERA, turned, size=SIZE, **opts)
    assert all(n == 4 for _, n in sm.last_redrawn_layers), sm.last_redrawn_layers
    assert not sm.reads_buffer
    sm.forget()
    hard = renderer.render(CAMERA, turned, size=SIZE, **{**opts, "shadow_raster": "hardware"})
    _compare_images(hard, got, "a lone redraw of every layer, copied")
    for _ in range(SETTLE_FRAMES + 1):  # (settled on the images again)
        renderer.render(CAMERA, [sun], size=SIZE, **opts)
    assert not sm.reads_buffer
    renderer.render(CAMERA, turned, size=SIZE, **opts)
    assert not sm.reads_buffer
    renderer.render(CAMERA, [sun], size=SIZE, **opts)
    assert sm.reads_buffer, "a second frame in a row redrawing every layer should read the buffer"


def test_the_4x4_by_hand_pcf_equals_nine_taps(renderer, monkeypatch) -> None:  # noqa: ANN001
    """shadow_sampling.glsl hand_pcf_linear (the 3 x 3 linear taps of a by-hand compare
    from their 4 x 4 texels) against the nine taps it replaces: the same frame with taps
    2^-20 texel further apart takes the nine-tap path. Run where the maps filter linearly
    (NVIDIA); on lavapipe the header's linear flag is forced (the by-hand compare needs no
    sampler), and the nearest frame differs at the shadows' edges, so a wrong weight shows."""
    import vkpbr.render.shadows as shadows

    opts = {"shadow_resolution": 256, "env": "none", "shadow_raster": "compute"}
    sun = [LIGHTS["directional"]]
    frames_of = renderer.shadow_plan.__self__  # (ShadowFrames: its per-slot header cache)

    def frame() -> np.ndarray:
        frames_of._rows.clear()
        renderer.shadows.forget()  # every layer redrawn: the buffer is read
        out = renderer.render(CAMERA, sun, size=SIZE, **opts)
        assert renderer.shadows.reads_buffer
        return out.astype(np.int16)

    nearest = frame()
    monkeypatch.setattr(renderer.shadows.maps, "filterable", True)
    fast = frame()
    monkeypatch.setattr(shadows, "PCF_RADIUS", 1.0 + 2.0 ** -20)
    nine = frame()
    assert np.abs(fast - nine).max() <= 1, np.abs(fast - nine).max()
    if not renderer.shadows.maps.filterable or renderer.device.info.kind == "cpu":
        assert np.abs(fast - nearest).max() >= 3  # (linear and nearest edges differ)
