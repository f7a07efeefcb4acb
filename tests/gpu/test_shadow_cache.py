"""Shadow maps are redrawn only when what they hold changes (ShadowMaps.stale): a frame whose
lights' matrices equal the ones its maps were drawn with skips their passes. Every frame of a
sequence that changes one input at a time (the camera, a light, the alpha mask, the map
size, a batch in between, who draws the maps: the raster units into the images or the compute
kernels into the buffer the shading reads, and the frame path) must equal the same frame drawn
with every map redrawn (ShadowMaps.forget before it), bit for bit; and the maps that do not
depend on the camera (spot, point) are not redrawn when only the camera moves."""

from __future__ import annotations

import collections
import dataclasses

import numpy as np
import pytest
from shadow_scenes import BLOCK, CAMERA, CARD, GROUND, LIGHTS, rect_scene

from vkpbr.render.shadow_frames import SETTLED_FRAMES

SIZE = (96, 72)
# The raster units draw the maps unless a step says otherwise ("auto" would pick the compute
# kernels on GPUs: the switch at STEPS[9] must be one everywhere).
OPTS = {"shadow_resolution": 256, "env": "none", "shadow_raster": "hardware"}
ALL = [LIGHTS["directional"], LIGHTS["spot"], LIGHTS["point"]]
MOVED = dataclasses.replace(CAMERA, eye=(1.5, 4.0, 5.0))
# A step of 6 cm: the nearer cascades cross their snapping grid (shadow_math.snap_texels),
# the farther ones do not, so only some of the sun's layers are redrawn.
NUDGED = dataclasses.replace(CAMERA, eye=(0.06, 5.0, 6.0), target=(0.36, 0.0, 0.0))
POINT_MOVED = dataclasses.replace(LIGHTS["point"], position=(-0.4, 2.2, 0.6))


@pytest.fixture(scope="module")
def pair():
    """A renderer that caches its maps and one that redraws them every frame."""
    from vkpbr import Renderer

    made = [Renderer(rect_scene((GROUND, BLOCK, CARD)), validation=True, sync_validation=True)
            for _ in range(2)]
    yield made
    for r in made:
        instance = r.device.instance
        r.close()
        assert instance.errors == [], instance.errors[:3]


STEPS = [  # (camera, lights, options): each changes one thing from the step before
    (CAMERA, ALL, {}),
    (CAMERA, ALL, {}),                    # nothing changed: no map redrawn
    (MOVED, ALL, {}),                     # the sun's cascades refit; spot and point kept
    (CAMERA, ALL, {}),
    (NUDGED, ALL, {}),                    # some of the sun's cascades redrawn
    (CAMERA, [ALL[0], ALL[1], POINT_MOVED], {}),  # the point light moved: its cube redrawn
    (CAMERA, [ALL[0], ALL[1], POINT_MOVED], {"alpha_mask": False}),  # the card drawn whole
    (CAMERA, [ALL[0], ALL[1], POINT_MOVED], {"shadow_resolution": 128}),
    (MOVED, ALL, {}),
    # The compute kernels draw into their buffer: a switch redraws every layer (the buffer
    # holds none of the images' layers), then their cache works as the images' did, on
    # either frame path; back to the raster units, every layer of the images is redrawn.
    (MOVED, ALL, {"shadow_raster": "compute"}),
    (CAMERA, ALL, {"shadow_raster": "compute"}),
    (CAMERA, ALL, {"shadow_raster": "compute", "pipeline": "compute"}),
    (CAMERA, ALL, {}),
]
# The maps each step redraws from the one of STEPS[9] on: (directional, spot, point).
REDRAWN = {9: (True, True, True), 10: (True, False, False), 11: (False, False, False),
           12: (True, True, True)}


def test_cached_maps_draw_what_redrawn_maps_draw(pair) -> None:  # noqa: ANN001
    cached, fresh = pair
    images = []
    for i, (camera, lights, opts) in enumerate(STEPS):
        o = {**OPTS, **opts}
        got = cached.render(camera, lights, size=SIZE, linear=True, **o)
        if i == 4:  # a batch in between: one scene-wide sun map, spot and point kept
            cached.render_batch([camera, MOVED], SIZE, lights, linear=True, **o)
        fresh.shadows.forget()
        want = fresh.render(camera, lights, size=SIZE, linear=True, **o)
        assert np.array_equal(got, want), (i, float(np.abs(got - want).max()))
        if i in REDRAWN:
            assert tuple(dict(cached.shadows.last_redraw).values()) == REDRAWN[i], i
        images.append(got)
    # The inputs matter: the sequence is not one image over and over.
    assert not np.array_equal(images[0], images[2])
    assert not np.array_equal(images[3], images[5])  # the point light moved
    assert not np.array_equal(images[5], images[6])  # the card drawn whole


def test_only_the_maps_that_changed_are_redrawn(pair) -> None:  # noqa: ANN001
    r, _ = pair
    def redrawn(camera, lights) -> dict[str, bool]:  # noqa: ANN001
        r.render(camera, lights, size=SIZE, **OPTS)
        return dict(r.shadows.last_redraw)

    redrawn(CAMERA, ALL)
    assert redrawn(CAMERA, ALL) == {"directional": False, "spot": False, "point": False}
    redrawn(NUDGED, ALL)
    layers = dict(r.shadows.last_redrawn_layers)
    assert 0 < layers["directional"] < 4 and layers["spot"] == layers["point"] == 0, layers
    assert redrawn(MOVED, ALL) == {"directional": True, "spot": False, "point": False}
    moved_point = [ALL[0], ALL[1], POINT_MOVED]
    assert redrawn(MOVED, moved_point) == {"directional": False, "spot": False, "point": True}
    r.shadows.forget()
    assert redrawn(MOVED, moved_point) == {"directional": True, "spot": True, "point": True}


def test_a_walk_refits_only_the_cascades_as_a_whole_write_would(pair) -> None:  # noqa: ANN001
    """A walking camera's frames rewrite only the sun's cascades in their slot's ShadowData
    (ShadowFrames.write: ShadowMaps.write_cascades, Python floats) and redraw the cascades
    that crossed their snapping grid. Each must equal, in the ShadowData the shaders read and
    in the image, bit for bit, the frame of a renderer that writes the whole ShadowData and
    redraws every map (ShadowFrames.forget before each frame)."""
    cached, fresh = pair

    def shadow_data(r) -> bytes:  # noqa: ANN001 - the slot of the renderer's latest frame
        ring = r.frame_path.parts.ring
        return r.shadows._views[(ring.number - 1) % ring.count].tobytes()

    for _ in range(3):  # every slot written whole for these lights
        cached.render(CAMERA, ALL, size=SIZE, **OPTS)
    whole = []
    real_write = cached.shadows.write
    cached.shadows.write = lambda *a, **k: whole.append(1) or real_write(*a, **k)  # counts
    try:
        layers, images = [], []
        for i in range(1, 11):  # 3 cm a frame, as NUDGED
            camera = dataclasses.replace(CAMERA, eye=(0.03 * i, 5.0, 6.0),
                                         target=(0.3 + 0.03 * i, 0.0, 0.0))
            got = cached.render(camera, ALL, size=SIZE, linear=True, **OPTS)
            layers.append(dict(cached.shadows.last_redrawn_layers))
            fresh.shadow_frames.forget()
            want = fresh.render(camera, ALL, size=SIZE, linear=True, **OPTS)
            assert shadow_data(cached) == shadow_data(fresh), i
            assert np.array_equal(got, want), (i, float(np.abs(got - want).max()))
            images.append(got)
    finally:
        del cached.shadows.write
    assert whole == []  # every frame took the cascades' refit
    assert all(n["spot"] == n["point"] == 0 for n in layers), layers
    assert any(0 < n["directional"] < 4 for n in layers), layers  # some cascades kept
    assert not np.array_equal(images[0], images[-1])


def assert_scrolled_alike(maps: np.ndarray, want: np.ndarray, image: np.ndarray,
                          image_want: np.ndarray, frame: int) -> None:
    """A scrolled cascade's map against a full redraw's: the moved matrix rounds a vertex's
    last bits another way, so its depths may differ by 4 float32 ulps of 1, and a texel
    centre within an ulp of an edge may be covered on one side only (at most one texel in
    10,000: on lavapipe none, and the images equal); a scroll the wrong way, by the wrong
    amount or drawn outside its strip differs in whole depths and thousands of texels."""
    covered, covered_want = maps > 0, want > 0
    assert np.count_nonzero(covered != covered_want) <= maps.size // 10_000, frame
    both = covered & covered_want
    assert float(np.abs(maps - want)[both].max(initial=0.0)) <= 4 * 2.0 ** -23, frame
    assert np.count_nonzero(np.any(image != image_want, axis=-1)) <= image.shape[0] * image.shape[1] // 1000, (
        frame, float(np.abs(image - image_want).max()))


def grid_step(r) -> np.ndarray:  # noqa: ANN001
    """A level world offset that moves the sun's nearest cascade (layer 0 of the renderer's
    latest frame) by one snapping step along both of its axes (the grid read from the matrix:
    row 0 is right / half a side; shadow_math._fit_cascades)."""
    from vkpbr.render import shadow_math as SM
    from vkpbr.render.shadows import MATRICES

    ring = r.frame_path.parts.ring
    cols = np.frombuffer(r.shadows.matrices_bytes((ring.number - 1) % ring.count), np.float32)
    row0 = cols.reshape(MATRICES, 16)[0, [0, 4, 8]].astype(np.float64)
    res = r.shadows.resolution
    grid = SM.snap_texels(res) * 2.0 / (np.linalg.norm(row0) * res)
    right, up, _ = SM.light_basis(LIGHTS["directional"].direction)
    # level (no height: the automatic near and far planes, and so the cascades' fit, stay):
    # x and z such that the offset's parts along right and up are one grid each
    x, z = np.linalg.solve([[right[0], right[2]], [up[0], up[2]]], [grid, grid])
    return np.array([x, 0.0, z])


def test_a_walk_scrolls_the_cascades_it_moves_by_whole_texels(pair) -> None:  # noqa: ANN001
    """Compute-drawn cascades that a walking camera moves by whole texels (its snapping grid)
    keep their texels, moved, and draw only the strip that came into view
    (shadow_math.layer_scroll, ShadowMaps._write_clips, shadow_raster.comp's save and move
    kernels). Every frame's maps equal those of a renderer that redraws every map: the
    depths within 4 float32 ulps of 1 (the moved matrix rounds a vertex's last bits another
    way), the texels covered alike, and the images equal. A scroll the wrong way, by the
    wrong amount or drawn outside its strip differs by whole depths."""
    cached, fresh = pair
    opts = {**OPTS, "shadow_raster": "compute"}
    for _ in range(3):
        cached.render(CAMERA, ALL, size=SIZE, **opts)
    scrolled = []
    # 3 cm a frame, then back 9 cm a frame; then (`grid_step`) a snapping step along both of
    # the nearest cascade's axes each frame: its texels move along both at once
    walk = [np.array((0.03 * i, 0.0, 0.0)) for i in [*range(1, 28), *range(26, -14, -3)]]
    for i in range(len(walk) + 4):
        if i >= len(walk):
            walk.append(walk[-1] + grid_step(cached))
        camera = dataclasses.replace(CAMERA, eye=tuple(np.add(CAMERA.eye, walk[i])),
                                     target=tuple(np.add(CAMERA.target, walk[i])))
        got = cached.render(camera, ALL, size=SIZE, linear=True, **opts)
        scrolled += cached.shadows.last_scrolled
        fresh.shadow_frames.forget()
        want = fresh.render(camera, ALL, size=SIZE, linear=True, **opts)
        (maps, cubes), (maps_want, cubes_want) = cached.shadows.read_maps(), fresh.shadows.read_maps()
        assert np.array_equal(cubes, cubes_want), i
        assert_scrolled_alike(maps, maps_want, got, want, i)
    step = opts["shadow_resolution"] // 8  # shadow_math.snap_texels
    assert len(scrolled) >= 3, scrolled
    assert all(dx % step == dy % step == 0 for _, dx, dy in scrolled), scrolled
    assert any(dx and dy for _, dx, dy in scrolled), scrolled  # (the diagonal: both at once)
    assert {dx + dy > 0 for _, dx, dy in scrolled} == {True, False}, scrolled  # both ways


def test_casters_that_never_moved_keep_maps_of_their_own(pair) -> None:  # noqa: ANN001
    """Compute-drawn maps where some casters moved and others did not
    (ShadowFrames.split, shadows.Redraw): the maps of those that did not are kept apart,
    redrawn only when their layer's matrix changes (or scrolled: a walking camera) or the
    set of moved casters changes, and a frame copies them in and draws the moved casters
    over them. Every frame's maps and image equal, bit for bit, those of one pass over every
    caster (the other renderer, its split turned off and every map redrawn): a texel's depth
    is the same from either pass, and the nearest wins either way. First the block moves
    every frame (its shadow, and the card's on it) and the camera every third; then the
    block rests until it settles (SETTLED_FRAMES, 3 here) and the card moves: the kept maps
    are redrawn once with the block where it came to rest. The sun's cascades, the spot map
    and the point light's cube all take part."""
    cached, fresh = pair
    opts = {**OPTS, "shadow_raster": "compute"}
    rest = [r.state.local[1:3].copy() for r in pair]
    fresh.parts.shadow_frames.split = lambda moved: None  # one pass over every caster
    cached.parts.shadow_frames._versions = collections.deque(maxlen=3)
    kept_redraws, splits, latest = [], [], [None]
    real_split = cached.parts.shadow_frames.split
    cached.parts.shadow_frames.split = lambda moved: latest.__setitem__(0, real_split(moved)) or latest[0]
    try:
        for i in range(20):
            node, step = (1, i) if i < 12 else (2, i - 12) if i >= 15 else (None, 0)
            for r, m in zip(pair, rest, strict=True):
                if node is not None:
                    moved = m[node - 1].copy()
                    moved[:3, 3] += (0.04 * step, 0.03 * (step % 3), -0.02 * step)
                    r.set_pose(node, moved)
            camera = dataclasses.replace(CAMERA, eye=(0.06 * min(i // 3, 3), 5.0, 6.0),
                                         target=(0.3 + 0.06 * min(i // 3, 3), 0.0, 0.0))
            if i == 5:  # a batch in between: its scene-wide sun map, over the kept maps too
                got = cached.render_batch([camera, MOVED], SIZE, ALL, linear=True, **opts)
                want = fresh.render_batch([camera, MOVED], SIZE, ALL, linear=True, **opts)
                assert cached.shadows.last_kept_layers  # (the batch drew over kept maps)
                assert np.array_equal(got, want), float(np.abs(got - want).max())
            got = cached.render(camera, ALL, size=SIZE, linear=True, **opts)
            kept_redraws.append(dict(cached.shadows.last_kept_layers))
            splits.append(latest[0])  # (the frame's split: its id, the moving casters)
            fresh.shadow_frames.forget()
            want = fresh.render(camera, ALL, size=SIZE, linear=True, **opts)
            for a, b in zip(cached.shadows.read_maps(), fresh.shadows.read_maps(), strict=True):
                assert np.array_equal(a, b), i
            assert np.array_equal(got, want), (i, float(np.abs(got - want).max()))
    finally:
        del fresh.parts.shadow_frames.split, cached.parts.shadow_frames.split
        cached.parts.shadow_frames._versions = collections.deque(maxlen=SETTLED_FRAMES)
        for r, m in zip(pair, rest, strict=True):
            r.set_poses([1, 2], m)
    # The kept maps were drawn whole once, then only where the camera moved a cascade: the
    # spot map and the cube never again while the block moved.
    assert kept_redraws[0] == {"directional": 4, "spot": 1, "point": 6}, kept_redraws[0]
    assert all(k and k["spot"] == k["point"] == 0 for k in kept_redraws[1:12]), kept_redraws
    assert any(k["directional"] for k in kept_redraws[3:12:3]), kept_redraws
    assert not any(k["directional"] for k in kept_redraws[1:3]), kept_redraws
    # The block at rest settles; the card moving is a new set: every kept map redrawn once.
    assert kept_redraws[12:15] == [{}, {}, {}] and splits[13] is None is splits[14], splits[12:15]
    assert kept_redraws[15] == {"directional": 4, "spot": 1, "point": 6}, kept_redraws[15]
    assert splits[15][0] != splits[11][0] and splits[15][1][2] and not splits[15][1][1], splits[15]
    assert all(k["spot"] == k["point"] == 0 for k in kept_redraws[16:]), kept_redraws


def test_past_max_splits_the_maps_are_drawn_in_one_pass(pair) -> None:  # noqa: ANN001
    """A renderer that has kept maps apart for MAX_SPLITS sets of moving casters draws its
    maps in one pass from then on (each set has caster tables and descriptor sets on the
    GPU: a scene whose moving casters keep changing must not grow), the same maps."""
    from vkpbr.render.shadow_frames import MAX_SPLITS

    cached, fresh = pair
    opts = {**OPTS, "shadow_raster": "compute"}
    frames = cached.parts.shadow_frames
    rest = cached.state.local[1].copy()
    before = frames._moved
    frames._moved = (before[0], MAX_SPLITS, before[2])
    try:
        for i in range(1, 3):
            moved = rest.copy()
            moved[0, 3] += 0.05 * i
            for r in pair:
                r.set_pose(1, moved)
            got = cached.render(CAMERA, ALL, size=SIZE, linear=True, **opts)
            assert cached.shadows.last_kept_layers == () and any(d for _, d in cached.shadows.last_redraw)
            fresh.shadow_frames.forget()
            assert np.array_equal(got, fresh.render(CAMERA, ALL, size=SIZE, linear=True, **opts))
    finally:
        frames._moved = before
        for r in pair:
            r.set_pose(1, rest)


def test_auto_takes_the_kernels_on_a_cpu_while_few_casters_move() -> None:
    """shadow_raster "auto": compute kernels on GPUs; on a CPU the raster units, but the
    kernels while the casters that moved (in the last SETTLED_FRAMES frames) hold under
    CPU_COMPUTE_SHARE of the casters' triangles, where the still ones' kept maps are copied
    in (render/shadow_frames.py). 20 spheres alike: one moving is 5% of them, three 15%."""
    from vkpbr import Renderer
    from vkpbr.scene.synthetic import sphere_field

    with Renderer(sphere_field(20, rings=4, segments=8, materials=2), validation=True) as r:
        sun = [LIGHTS["directional"]]
        cpu = r.device.info.kind == "cpu"

        def drawn(moving: list[int], frames: int = 3) -> bool:
            for i in range(frames):
                for n in moving:
                    pose = r.state.local[n].copy()
                    pose[1, 3] += 0.01 * (i + 1)
                    r.set_pose(n, pose)
                r.render(CAMERA, sun, size=(32, 24), shadow_resolution=128, env="none")
            return r.shadows.compute

        assert drawn([]) is (not cpu)  # nothing moves: the raster units on a CPU
        assert drawn([3]) is True  # 5% of the triangles
        assert drawn([3, 7, 11]) is (not cpu)  # 15%
        r.check_validation()


def test_kept_maps_scroll_with_a_walking_camera(pair) -> None:  # noqa: ANN001
    """A moving caster (the block, every frame) seen by a walking camera (3 cm a frame): the
    still casters' kept cascades scroll when the camera moves them by whole texels, and each
    frame copies them in and draws the block over them. The maps equal one pass's over every
    caster within 4 float32 ulps (a scrolled map's last bits: the scroll test's bound), the
    same texels covered, the images equal."""
    cached, fresh = pair
    opts = {**OPTS, "shadow_raster": "compute"}
    rest = [r.state.local[1].copy() for r in pair]
    fresh.parts.shadow_frames.split = lambda moved: None
    scrolled, kept = [], []
    try:
        for i in range(1, 28):
            for r, m in zip(pair, rest, strict=True):
                moved = m.copy()
                moved[:3, 3] += (0.01 * i, 0.0, 0.02 * (i % 4))
                r.set_pose(1, moved)
            camera = dataclasses.replace(CAMERA, eye=(0.03 * i, 5.0, 6.0),
                                         target=(0.3 + 0.03 * i, 0.0, 0.0))
            got = cached.render(camera, ALL, size=SIZE, linear=True, **opts)
            scrolled += cached.shadows.last_scrolled
            kept.append(bool(cached.shadows.last_kept_layers))
            fresh.shadow_frames.forget()
            want = fresh.render(camera, ALL, size=SIZE, linear=True, **opts)
            (maps, cubes), (maps_want, cubes_want) = cached.shadows.read_maps(), fresh.shadows.read_maps()
            assert np.array_equal(cubes, cubes_want), i
            assert_scrolled_alike(maps, maps_want, got, want, i)
    finally:
        del fresh.parts.shadow_frames.split
        for r, m in zip(pair, rest, strict=True):
            r.set_pose(1, m)
    assert all(kept), kept
    assert len(scrolled) >= 2, scrolled  # (the kept cascades moved by whole texels)


def test_an_animated_file_draws_over_its_still_casters_kept_maps(sample_scene) -> None:  # noqa: ANN001
    """BoxAnimated (glTF animation: one box turns and moves, the other stands still) played
    at ten times with compute-drawn maps: every frame draws the moving box over the still
    one's kept maps, and equals bit for bit the frame of one pass over both (another
    renderer, its split turned off, every map redrawn) on the forward path, whose shading
    reads the maps' images alike in both; on auto's path (the compute path, on CPUs too)
    within 1e-6 (lavapipe rounds the two renderers' shading kernels, which read a frame's
    freshly drawn maps from their buffer, 1-2 ulp apart)."""
    from vkpbr import Renderer

    a, b = (Renderer(sample_scene("BoxAnimated"), validation=True) for _ in range(2))
    try:
        b.parts.shadow_frames.split = lambda moved: None
        cam = a.default_camera()
        for path in ("forward", "auto"):
            for t in np.linspace(0.0, 3.0, 10):
                got = a.render(cam, size=(96, 72), time=float(t), shadow_raster="compute",
                               linear=True, pipeline=path)
                assert a.shadows.last_kept_layers, t
                b.shadow_frames.forget()
                want = b.render(cam, size=(96, 72), time=float(t), shadow_raster="compute",
                                linear=True, pipeline=path)
                if path == "forward":
                    assert np.array_equal(got, want), (t, float(np.abs(got - want).max()))
                else:
                    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6, err_msg=f"t={t}")
        a.check_validation()
        b.check_validation()
    finally:
        a.close()
        b.close()


def test_streamed_frames_draw_over_kept_maps_alike(pair) -> None:  # noqa: ANN001
    """`render_many` (frames in flight sharing the kept maps and the depth buffer) of a walk
    while the block moves: every frame equals the one-pass renderer's stream of the same
    walk, bit for bit, and synchronization validation finds no hazard between a frame's
    kept pass and the frames before it reading those maps."""
    cached, fresh = pair
    opts = {**OPTS, "shadow_raster": "compute"}
    rest = cached.state.local[1].copy()
    fresh.parts.shadow_frames.split = lambda moved: None

    def walk(r):  # noqa: ANN001, ANN202
        for i in range(18):
            pose = rest.copy()
            pose[:3, 3] += (0.03 * i, 0.0, 0.01 * (i % 5))
            r.set_pose(1, pose)
            yield dataclasses.replace(CAMERA, eye=(0.03 * i, 5.0, 6.0),
                                      target=(0.3 + 0.03 * i, 0.0, 0.0))
    try:
        got = list(cached.render_many(walk(cached), ALL, size=SIZE, linear=True, **opts))
        want = list(fresh.render_many(walk(fresh), ALL, size=SIZE, linear=True, **opts))
    finally:
        del fresh.parts.shadow_frames.split
        for r in pair:
            r.set_pose(1, rest)
    assert all(np.array_equal(g, w) for g, w in zip(got, want, strict=True))
    assert not np.array_equal(got[0], got[-1])


def test_kept_maps_follow_every_option_change(pair) -> None:  # noqa: ANN001
    """The block moving every frame while the options change one at a time (the alpha mask,
    the map size, the raster units and back, the frame path): every frame equals the
    one-pass renderer's bit for bit, and the frames drawn by the compute kernels draw over
    kept maps (none by the raster units)."""
    cached, fresh = pair
    rest = cached.state.local[1].copy()
    fresh.parts.shadow_frames.split = lambda moved: None
    steps = [{}, {"alpha_mask": False}, {}, {"shadow_resolution": 128}, {"shadow_raster": "hardware"},
             {}, {"pipeline": "compute"}, {}]
    try:
        for i, change in enumerate(steps):
            opts = {**OPTS, "shadow_raster": "compute", **change}
            for r in pair:
                pose = rest.copy()
                pose[0, 3] += 0.05 * (i + 1)
                r.set_pose(1, pose)
            got = cached.render(CAMERA, ALL, size=SIZE, linear=True, **opts)
            assert bool(cached.shadows.last_kept_layers) is (opts["shadow_raster"] == "compute"), i
            fresh.shadow_frames.forget()
            want = fresh.render(CAMERA, ALL, size=SIZE, linear=True, **opts)
            assert np.array_equal(got, want), (i, change, float(np.abs(got - want).max()))
    finally:
        del fresh.parts.shadow_frames.split
        for r in pair:
            r.set_pose(1, rest)
