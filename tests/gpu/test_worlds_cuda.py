"""Batches of worlds fed from PyTorch on the GPU (issue 32 must-have 2): CUDA tensors of
poses read without a host copy (device to device into exported Vulkan memory, expanded by
worlds.comp) give the views the exact host path gives within 1 level (float32 matrices), into
NumPy and into torch; one-line errors for NaN poses, integer tensors and wrong shapes. Runs
where torch sees CUDA on the Vulkan device's GPU (the GPU test pass), skips saying why else.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_outputs import H, W, analytic_scene
from test_worlds import MOVED, NO_SHADOWS, cameras, world_poses

from vkpbr.errors import UsageError
from vkpbr.gpu.cuda import cuda_unavailable

WHY = cuda_unavailable()
pytestmark = pytest.mark.skipif(WHY is not None, reason=f"worlds on CUDA need CUDA: {WHY}")


@pytest.fixture
def renderer(make_renderer):  # noqa: ANN001, ANN201
    r = make_renderer(analytic_scene())
    if not r.device.external_memory_fd:
        pytest.skip(f"{r.device.info.name} cannot export memory to CUDA")
    r.world_slots(MOVED)
    return r


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_cuda_poses_give_the_host_worlds(renderer, pipeline: str) -> None:  # noqa: ANN001
    import torch

    r = renderer
    poses = world_poses(6, seed=3)
    shown = np.ones((6, 2), bool)
    shown[2, 0] = shown[4, 1] = False
    kw = dict(quaternion="wxyz", pipeline=pipeline, **NO_SHADOWS)
    host = r.render_batch(cameras(6), (W, H), worlds=poses, world_visible=shown, **kw)
    on_gpu = torch.as_tensor(poses, device="cuda", dtype=torch.float32)
    visible = torch.as_tensor(shown, device="cuda")
    into_numpy = r.render_batch(cameras(6), (W, H), worlds=on_gpu, world_visible=visible, **kw)
    into_torch = r.render_batch(cameras(6), (W, H), worlds=on_gpu, world_visible=visible,
                                device="cuda", **kw)
    assert into_torch.device.type == "cuda"
    for got in (into_numpy, into_torch.cpu().numpy()):
        diff = np.abs(host.astype(int) - got)
        assert np.mean(diff) <= 0.05 and np.mean(diff > 1) <= 0.001, (diff.mean(), diff.max())


def test_a_step_loop_rewrites_poses_in_place(renderer) -> None:  # noqa: ANN001
    """A simulator's loop: one tensor rewritten each step; each step's frames follow it."""
    import torch

    r = renderer
    buf = torch.zeros((3, 2, 7), device="cuda")
    frames = []
    for seed in (1, 2):
        buf.copy_(torch.as_tensor(world_poses(3, seed=seed), device="cuda"))
        frames.append(r.render_batch(cameras(3), (W, H), worlds=buf, quaternion="wxyz",
                                     device="cuda", **NO_SHADOWS).cpu().numpy())
        want = r.render_batch(cameras(3), (W, H), worlds=world_poses(3, seed=seed),
                              quaternion="wxyz", **NO_SHADOWS)
        assert np.mean(np.abs(frames[-1].astype(int) - want)) <= 0.05
    assert not np.array_equal(frames[0], frames[1])


def test_back_to_back_steps_keep_their_frames(renderer) -> None:  # noqa: ANN001
    """Two steps submitted without waiting (the poses buffer rewritten right after the first
    call returns): each step's tensor holds its own poses' frames (the GPU-side ordering of
    render/cuda_order.py, where the driver shares semaphores)."""
    import torch

    r = renderer
    buf = torch.zeros((4, 2, 7), device="cuda")
    got = []
    for seed in (5, 6, 7):
        buf.copy_(torch.as_tensor(world_poses(4, seed=seed), device="cuda"))
        got.append(r.render_batch(cameras(4), (W, H), worlds=buf, quaternion="wxyz",
                                  device="cuda", pipeline="compute", **NO_SHADOWS))
    # Where the driver shares semaphores (NVIDIA's), the steps were ordered on the GPU.
    assert (r.batch_path.cuda_order is not None) == bool(r.device.external_semaphore_fd)
    for seed, frames in zip((5, 6, 7), got, strict=True):
        want = r.render_batch(cameras(4), (W, H), worlds=world_poses(4, seed=seed),
                              quaternion="wxyz", pipeline="compute", **NO_SHADOWS)
        assert np.mean(np.abs(frames.cpu().numpy().astype(int) - want)) <= 0.05, seed


def test_frames_as_a_view_follow_each_step(renderer) -> None:  # noqa: ANN001
    """batch_step(frames="view"): the frames are the exported memory itself (the same tensor
    each step, no clone), holding each step's frames when read before the next call (the
    steps past the ring's slots replayed); equal to the cloned default's."""
    import torch

    r = renderer
    buf = torch.zeros((3, 2, 7), device="cuda")
    kw = dict(quaternion="wxyz", device="cuda", pipeline="compute", **NO_SHADOWS)
    cams = cameras(3)
    copied = r.batch_step(cams, (W, H), **kw)
    want = {}
    for seed in (1, 2):
        buf.copy_(torch.as_tensor(world_poses(3, seed=seed), device="cuda"))
        want[seed] = copied(worlds=buf).cpu().numpy()
    assert not np.array_equal(want[1], want[2]), "the poses changed nothing (test is moot)"
    viewed = r.batch_step(cams, (W, H), frames="view", **kw)
    replayed = r.batch_path.replays.replayed
    seen = []
    for seed in (1, 2, 1, 2, 1, 2):
        buf.copy_(torch.as_tensor(world_poses(3, seed=seed), device="cuda"))
        got = viewed(worlds=buf)
        seen.append(got)
        assert np.array_equal(got.cpu().numpy(), want[seed]), seed  # (read before the next)
    assert all(t is seen[0] for t in seen[1:]), "a new tensor a step (a clone?)"
    assert r.batch_path.replays.replayed > replayed, "no step was replayed"
    assert r.batch_path.frames_view is False  # (only during the view step's calls)


def three_worlds(r) -> tuple[list, dict, dict]:  # noqa: ANN001
    """Three views of three worlds, the compute path's keywords, and the host path's frames
    of the worlds posed by seeds 1 and 2 (which must differ)."""
    cams = cameras(3)
    kw = dict(quaternion="wxyz", pipeline="compute", **NO_SHADOWS)
    want = {seed: r.render_batch(cams, (W, H), worlds=world_poses(3, seed=seed), **kw)
            for seed in (1, 2)}
    assert not np.array_equal(want[1], want[2]), "the poses changed nothing (test is moot)"
    return cams, kw, want


def test_a_step_loop_takes_the_short_way_until_the_plan_changes(renderer) -> None:  # noqa: ANN001
    """batch_step's short way (BatchStep._lane_step): once a step replayed, the steps with a
    tensor alike skip render_batch's argument handling, and each step's frames are still its
    poses' (the host path's, within 1 level). What changes the plan takes the full way: the
    state moved between steps (set_poses: the replay key's version), a float64 tensor (the
    full way converts it), another number of worlds; the frames follow all of them."""
    import torch

    r = renderer
    cams, kw, want = three_worlds(r)
    step = r.batch_step(cams, (W, H), device="cuda", **kw)
    buf = torch.zeros((3, 2, 7), device="cuda")

    def check(worlds: object, seed: int) -> None:
        got = step(worlds=worlds).cpu().numpy()
        assert np.mean(np.abs(got.astype(int) - want[seed])) <= 0.05, seed

    for seed in (1, 2, 1, 2, 1, 2, 1):
        buf.copy_(torch.as_tensor(world_poses(3, seed=seed), device="cuda"))
        check(buf, seed)
    assert step.lane_steps >= 2, "the loop never took the short way"
    before = step.lane_steps
    big = r.state.tree.find("big sphere")
    r.set_poses(big, r.state.local[big].copy())
    check(buf, 1)  # (the same pose: the state's version alone changed)
    check(buf.double(), 1)
    assert step.lane_steps == before, "a changed plan took the short way"
    # (back on it once a step replayed again: each of the ring's frames records its new plan
    # first, then a step replays and the lane is made for the next)
    for seed in (2, 1, 2, 1, 2, 1, 2):
        buf.copy_(torch.as_tensor(world_poses(3, seed=seed), device="cuda"))
        check(buf, seed)
    assert step.lane_steps > before
    with pytest.raises(UsageError, match="worlds"):  # (2 worlds for 3 views: checked again)
        step(worlds=buf[:2].contiguous())


def test_poses_written_into_the_renderers_input_are_read_in_place(renderer) -> None:  # noqa: ANN001
    """batch_step.worlds_input(): a simulator writes each step's poses into the renderer's
    own input memory (no copy a step); each step's frames are its poses' (the host path's,
    within 1 level), on the full way and the short one; a step given another tensor copies
    it as before; after a step of more worlds the old tensor is still mapped memory and a
    new one is asked for; before any CUDA step there is none (one line)."""
    import torch

    r = renderer
    cams, kw, want = three_worlds(r)
    step = r.batch_step(cams, (W, H), device="cuda", **kw)
    with pytest.raises(UsageError, match="call the step once") as err:
        step.worlds_input()
    assert "\n" not in str(err.value)
    step(worlds=torch.as_tensor(world_poses(3, seed=2), device="cuda", dtype=torch.float32))
    poses = step.worlds_input()
    assert poses.shape == (3, 2, 7) and poses.dtype == torch.float32 and poses.is_cuda
    assert poses.data_ptr() == r.batch_path.world_kernel._imports[0].ptr  # (the input itself)
    for seed in (1, 2, 1, 2, 1, 2, 1):
        poses.copy_(torch.as_tensor(world_poses(3, seed=seed), device="cuda"))  # "the simulator"
        got = step(worlds=poses).cpu().numpy()
        assert np.mean(np.abs(got.astype(int) - want[seed])) <= 0.05, seed
    assert step.lane_steps >= 2, "the loop never took the short way"
    other = torch.as_tensor(world_poses(3, seed=2), device="cuda", dtype=torch.float32)
    got = step(worlds=other).cpu().numpy()  # (copied into the input)
    assert np.mean(np.abs(got.astype(int) - want[2])) <= 0.05
    more = r.batch_step(cameras(40), (W, H), device="cuda", **kw)
    more(worlds=torch.as_tensor(world_poses(40, seed=4), device="cuda", dtype=torch.float32))
    poses.zero_()  # (the replaced input: still mapped, nothing crashes)
    torch.cuda.synchronize()
    assert more.worlds_input().shape == (40, 2, 7)


@pytest.mark.parametrize("device", ["cpu", "cuda"])
def test_nan_poses_on_the_gpu_are_hidden_and_reported(renderer, device: str) -> None:  # noqa: ANN001
    """CUDA poses are not read back before the batch: the kernel hides a world whose pose is
    NaN or a zero quaternion and the renderer reports it in one line once the batch is done
    (into torch: at the next call, which waits for it)."""
    import torch

    poses = torch.as_tensor(world_poses(3, seed=2), device="cuda", dtype=torch.float32)
    poses[1, 0, 0] = float("nan")
    poses[2, 1, 3:] = 0.0
    r = renderer

    def call() -> object:
        return r.render_batch(cameras(3), (W, H), worlds=poses, quaternion="wxyz",
                              device=device, pipeline="compute", **NO_SHADOWS)

    with pytest.raises(UsageError, match="world 1 has a pose with NaN") as err:
        call()
        call()  # (into torch, the first call returns before the batch is done)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize(("make", "message"), [
    (lambda t: t.zeros((2, 2, 7), device="cuda", dtype=t.int32), "float32"),
    (lambda t: t.zeros((2, 3, 7), device="cuda"), "shape"),
])
def test_bad_cuda_poses_are_one_line_errors(renderer, make, message: str) -> None:  # noqa: ANN001
    import torch

    with pytest.raises(UsageError, match=message) as err:
        renderer.render_batch(cameras(2), (W, H), worlds=make(torch))
    assert "\n" not in str(err.value)
