"""A loop's render_batch calls reuse what they share (render/batch_cache.py, issue 32's
Python per step) and replay the last step's recording of their frame slot
(render/batch_replay.py): a repeated or replayed call gives bit for bit what a fresh call
gives (the cache and the replays cleared), and a call that changes any part of the plan
(the cameras, the size, the options, the world count, the slots, a writable world_of_view
changed in place, visibility or material overrides given or not, shadows, the state) after
replayed steps gives what a fresh call with its arguments gives, and differs from the call
before (so a stale result would be seen). Renderer.batch_step is render_batch with its
arguments fixed. The module's renderer is validated (the layers' errors fail it at close).

One renderer for the module (validated), 24x18 views of the tests' analytic scene; the
layered batch (lavapipe's), and the compute batch where the device has it."""

from __future__ import annotations

import os
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from test_outputs import CAMERA, analytic_scene, translate
from test_worlds import MOVED, NO_SHADOWS, cameras, world_poses

from vkpbr.render.batch_cache import batch_cache
from vkpbr.scene.camera_batch import CameraBatch

SIZE = (24, 18)


@pytest.fixture(scope="module")
def r() -> Iterator[Any]:
    from vkpbr.render.renderer import Renderer

    renderer = Renderer(analytic_scene(), validation=True,
                        sync_validation=os.environ.get("VKPBR_SYNC_VALIDATION", "1") != "0")
    yield renderer
    instance = renderer.device.instance
    renderer.close()
    assert instance.errors == [], instance.errors[:3]


def batch(r: Any, cams: CameraBatch, poses: np.ndarray, size: tuple[int, int] = SIZE,
          **kw: Any) -> np.ndarray:
    kw = {"quaternion": "wxyz", "pipeline": "forward", **NO_SHADOWS, **kw}
    return r.render_batch(cams, size, worlds=poses, **kw)


def fresh(r: Any, *args: Any, **kw: Any) -> np.ndarray:
    """`batch` with nothing cached (the renderer's BatchCache and replays cleared first)."""
    batch_cache(r).clear()
    r.batch_path.replays.clear()
    return batch(r, *args, **kw)


def replayed(r: Any, *args: Any, **kw: Any) -> np.ndarray:
    """`batch` after as many of the same calls as the ring has slots (each slot then holds
    its recording): a replay, checked."""
    for _ in range(r.ring.count):
        batch(r, *args, **kw)
    count = r.batch_path.replays.replayed
    got = batch(r, *args, **kw)
    assert r.batch_path.replays.replayed == count + 1, "the step was not replayed"
    return got


def pipelines(r: Any) -> list[str]:
    return ["forward"] + ([] if r.compute_batch_unavailable() else ["compute"])


def test_repeated_calls_equal_a_fresh_call(r: Any) -> None:
    r.world_slots(MOVED)
    cams = CameraBatch.from_cameras(cameras(3), CAMERA)
    p1, p2 = world_poses(3, seed=1), world_poses(3, seed=2)
    for pipeline in pipelines(r):
        for expand in ("auto", "gpu"):
            kw = {"pipeline": pipeline, "world_expand": expand}
            first = fresh(r, cams, p1, **kw)
            hits = batch_cache(r).hits
            again = batch(r, cams, p2, **kw)  # the same call but the poses: from the cache
            assert batch_cache(r).hits > hits, "a repeated call missed the cache"
            assert not np.array_equal(first, again), "the poses changed nothing (test is moot)"
            assert np.array_equal(again, fresh(r, cams, p2, **kw)), (pipeline, expand)
            replayed(r, cams, p1, **kw)  # (host-made records too: written again)
            count = r.batch_path.replays.replayed
            assert np.array_equal(batch(r, cams, p2, **kw), again), (pipeline, expand, "replay")
            assert r.batch_path.replays.replayed == count + 1, "not replayed"
            step = r.batch_step(cams, SIZE, quaternion="wxyz", **NO_SHADOWS, **kw)
            assert np.array_equal(step(worlds=p2), again), (pipeline, expand)
            assert np.array_equal(step(worlds=p1), first), (pipeline, expand)


def _changed(part: str) -> tuple[tuple, dict, tuple, dict, Any]:
    """(args, kwargs) of a call, (args, kwargs) of the same call with `part` changed, and
    what changes between them (or None)."""
    cams = CameraBatch.from_cameras(cameras(3), CAMERA)
    p = world_poses(3, seed=4)
    base: tuple = ((cams, p), {"world_expand": "gpu"})
    if part == "cameras":
        other = CameraBatch.from_cameras(cameras(4)[1:], CAMERA)
        return (*base, (other, p), base[1], None)
    if part == "size":
        return (*base, (cams, p, (18, 24)), base[1], None)
    if part == "options":
        return (*base, (cams, p), {**base[1], "exposure": 1.0}, None)
    if part == "world count":  # the same views (a read-only world_of_view), 2 then 3 worlds
        which = np.array([0, 1, 1])
        which.flags.writeable = False
        return ((cams, p[:2]), {**base[1], "world_of_view": which},
                (cams, world_poses(3, seed=5)), {**base[1], "world_of_view": which}, None)
    if part == "world_of_view":  # a writable array, changed in place between the calls
        which = np.array([0, 1, 2])
        kw = {**base[1], "world_of_view": which}
        return ((cams, p), kw, (cams, p), kw, lambda: which.__setitem__(slice(None), [2, 0, 1]))
    if part == "visibility":  # given, where the call before had none
        return (*base, base[0], {**base[1], "world_visible": np.array([[True, False]] * 3)}, None)
    if part == "materials":  # per-world factors, where the call before had none
        factors = {"base_color": np.tile([0.9, 0.1, 0.1, 1.0], (3, 2, 1))}
        return (*base, base[0], {**base[1], "world_materials": factors}, None)
    if part == "shadows":
        return (*base, base[0], {**base[1], "shadows": True}, None)
    if part == "state":  # the same arguments; a node the worlds do not pose moved between
        return (*base, *base, lambda: STATE.set_poses(["big sphere"], LIFTED, space="local"))
    raise AssertionError(part)


LIFTED = translate(-1.2, 1.1, 0.0)[None]  # the big sphere (analytic_scene) raised
STATE: Any = None  # (the module's renderer, for the "state" part's change)


@pytest.mark.parametrize("part", ["cameras", "size", "options", "world count",
                                  "world_of_view", "visibility", "materials", "shadows", "state"])
def test_a_changed_key_part_is_noticed(r: Any, part: str) -> None:
    global STATE
    STATE = r
    r.world_slots(MOVED, materials=["m1", "m2"])
    args, kw, args2, kw2, between = _changed(part)
    batch_cache(r).clear()
    # (every slot holds the first plan's recording: a stale replay would be taken)
    first = (batch if part == "world_of_view" else replayed)(r, *args, **kw).copy()
    try:
        if between is not None:
            between()
        second = batch(r, *args2, **kw2)
        assert first.shape != second.shape or not np.array_equal(first, second), \
            f"changing the {part} changed nothing (test is moot)"
        assert np.array_equal(second, fresh(r, *args2, **kw2)), f"a stale cache after the {part}"
    finally:
        r.reset_pose()


def test_other_slots_are_noticed(r: Any) -> None:
    cams = CameraBatch.from_cameras(cameras(3), CAMERA)
    p = world_poses(3, seed=6)[:, :1]  # one slot node's poses
    batch_cache(r).clear()
    r.world_slots(MOVED[:1])
    first = replayed(r, cams, p, world_expand="gpu")
    r.world_slots(MOVED[1:])
    second = batch(r, cams, p, world_expand="gpu")
    assert not np.array_equal(first, second), "other slots changed nothing (test is moot)"
    assert np.array_equal(second, fresh(r, cams, p, world_expand="gpu"))


def test_replayed_world_shadows_equal_fresh_ones(r: Any) -> None:
    """Worlds that move shadow casters draw their own maps every step (render/
    world_shadows.py): a replayed step draws them from its poses as a fresh call does."""
    r.world_slots(MOVED)
    cams = CameraBatch.from_cameras(cameras(3), CAMERA)
    p1, p2 = world_poses(3, seed=8), world_poses(3, seed=9)
    kw = {"world_expand": "gpu", "shadows": True}
    first = replayed(r, cams, p1, **kw)
    # (the full steps before drew the worlds' own maps: their WorldJob was kept)
    assert r.batch_path._wshadow is not None, "no world shadow maps (test is moot)"
    count = r.batch_path.replays.replayed
    second = batch(r, cams, p2, **kw)
    assert r.batch_path.replays.replayed == count + 1, "not replayed"
    assert not np.array_equal(first, second)
    assert np.array_equal(second, fresh(r, cams, p2, **kw))


def test_depth_after_replays_is_fresh(r: Any) -> None:
    """Depth asked for after replayed steps: the colour and the depth as a fresh call gives
    them (such calls take the full path; dataset outputs render view by view)."""
    r.world_slots(MOVED)
    cams = CameraBatch.from_cameras(cameras(3), CAMERA)
    p = world_poses(3, seed=7)
    replayed(r, cams, p, world_expand="gpu")
    color, dist = batch(r, cams, p, world_expand="gpu", depth=True)
    color2, dist2 = fresh(r, cams, p, world_expand="gpu", depth=True)
    assert np.array_equal(color, color2) and np.array_equal(dist, dist2)


def test_a_steps_gpu_timings_are_read_when_asked_for(r: Any) -> None:
    """last_stats of a (replayed) step: its GPU timings read from its slot's queries on first
    use (render/batch_replay.py StepStats) while the slot holds them, NaN once it drew again
    (never another step's); dataclasses.replace and asdict take them."""
    import dataclasses
    import math

    r.world_slots(MOVED)
    cams = CameraBatch.from_cameras(cameras(3), CAMERA)
    replayed(r, cams, world_poses(3), world_expand="gpu")
    stats = r.last_stats
    if r.ring.query_pool is None:
        pytest.skip("the device has no timestamp queries: no GPU timings to read")
    assert stats.gpu_ms > 0 and math.isclose(sum(stats.pass_ms.values()), stats.gpu_ms)
    assert dataclasses.asdict(dataclasses.replace(stats))["gpu_ms"] == stats.gpu_ms
    batch(r, cams, world_poses(3), world_expand="gpu")
    unread = r.last_stats  # (not read before its slot draws again)
    for _ in range(r.ring.count):
        batch(r, cams, world_poses(3), world_expand="gpu")
    assert math.isnan(unread.gpu_ms) and unread.pass_ms == {}
    assert r.last_stats.gpu_ms > 0


def test_batch_step_takes_the_poses_each_call(r: Any) -> None:
    from vkpbr.errors import UsageError

    cams = CameraBatch.from_cameras(cameras(2), CAMERA)
    with pytest.raises(UsageError, match="worlds is given each call"):
        r.batch_step(cams, SIZE, worlds=world_poses(2))
    with pytest.raises(UsageError, match="frames='view' is for device='cuda'"):
        r.batch_step(cams, SIZE, frames="view")
    with pytest.raises(UsageError, match="frames 'clone': choose 'copy' or 'view'"):
        r.batch_step(cams, SIZE, device="cuda", frames="clone")


def test_poses_changed_in_place_are_seen_by_replayed_steps(r: Any) -> None:
    """A simulator writes its poses into the same float32 array every step (no copy is made
    of it: render/worlds.py): each replayed step sees that step's values, equal to a fresh
    call's pixels, and the NaN check still sees a bad value written in place."""
    from vkpbr.errors import UsageError

    r.world_slots(MOVED)
    cams = CameraBatch.from_cameras(cameras(2), CAMERA)
    a, b = world_poses(2, seed=7).astype(np.float32), world_poses(2, seed=8).astype(np.float32)
    for expand in ("auto", "gpu"):
        want_a = fresh(r, cams, a.copy(), world_expand=expand)
        want_b = fresh(r, cams, b.copy(), world_expand=expand)
        assert not np.array_equal(want_a, want_b), "the poses changed nothing (test is moot)"
        step = r.batch_step(cams, SIZE, quaternion="wxyz", pipeline="forward", **NO_SHADOWS,
                            world_expand=expand)
        live = a.copy()
        for _ in range(r.ring.count):  # (each slot records its step: the next ones replay)
            step(worlds=live)
        count = r.batch_path.replays.replayed
        for want, src in ((want_b, b), (want_a, a), (want_b, b)):
            np.copyto(live, src)  # (the same array, new values)
            assert np.array_equal(step(worlds=live), want), expand
        assert r.batch_path.replays.replayed == count + 3, "the steps were not replayed"
        live[1, 0, 2] = np.nan
        with pytest.raises(UsageError, match="NaN or infinity"):
            step(worlds=live)
