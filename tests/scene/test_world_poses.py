"""Worlds in NumPy (vkpbr.scene.worlds): every world's draw matrices against the state posed
world by world through the public API (set_poses(space="world") level by level and
set_visible), on random hierarchies, poses and visibility (hypothesis); and the checks of
what users give (one-line UsageErrors)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vkpbr.errors import UsageError
from vkpbr.render.batch_call import apply_saved, apply_world
from vkpbr.scene.state import SceneState
from vkpbr.scene.tree import NodeTree
from vkpbr.scene.worlds import WorldPoses, WorldSlots, world_models


def make_tree(names: list[str], parents: np.ndarray, local: np.ndarray) -> NodeTree:
    k = len(names)
    return NodeTree(names, np.asarray(parents), np.asarray(local, np.float64), np.zeros((k, 3)),
                    np.tile([0.0, 0, 0, 1], (k, 1)), np.ones((k, 3)), np.ones(k, bool), np.arange(k))


def random_rigid(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 4, 4) rotations (QR of Gaussian matrices) with translations."""
    q, r = np.linalg.qr(rng.normal(size=(n, 3, 3)))
    q *= np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]
    q[np.linalg.det(q) < 0, :, 0] *= -1
    out = np.tile(np.eye(4), (n, 1, 1))
    out[:, :3, :3] = q
    out[:, :3, 3] = rng.normal(size=(n, 3))
    return out


def random_state(rng: np.random.Generator, nodes: int, draws: int) -> SceneState:
    parents = np.array([-1] + [int(rng.integers(-1, i)) for i in range(1, nodes)])
    local = random_rigid(rng, nodes)
    local[:, :3, :3] *= rng.uniform(0.5, 2.0, (nodes, 1, 1))  # scaled nodes too
    tree = make_tree([f"n{i}" for i in range(nodes)], parents, local)
    draw_tree = rng.integers(0, nodes, draws)
    draw_local = np.tile(np.eye(4), (draws, 1, 1))
    below = rng.random(draws) < 0.3  # some draws below their node (instancing)
    draw_local[below] = random_rigid(rng, int(below.sum()))
    boxes = np.stack([-np.ones((draws, 3)), np.ones((draws, 3))], 1)
    rest = tree.world()[draw_tree] @ draw_local
    state = SceneState(tree, draw_tree, draw_local, boxes, rest)
    state.set_poses([0], local[:1])  # version > 0: models from the hierarchy
    return state


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), nodes=st.integers(1, 9), draws=st.integers(1, 12),
       worlds=st.integers(1, 4), hide=st.booleans(), space=st.sampled_from(["world", "local"]))
def test_world_models_equal_the_state_posed_world_by_world(seed: int, nodes: int, draws: int,
                                                           worlds: int, hide: bool, space: str) -> None:
    rng = np.random.default_rng(seed)
    state = random_state(rng, nodes, draws)
    chosen = rng.choice(nodes, int(rng.integers(1, nodes + 1)), replace=False)
    slots = WorldSlots.of(state, chosen.tolist())
    poses = random_rigid(rng, worlds * len(chosen)).reshape(worlds, len(chosen), 4, 4)
    visible = rng.random((worlds, len(chosen))) < 0.7 if hide else None
    wp = WorldPoses.of(poses, len(chosen), visible=visible, space=space)
    if space == "local" and slots.nested:  # (local poses below another chosen node: refused)
        with pytest.raises(UsageError, match="space='local'"):
            world_models(state, slots, wp)
        return
    got = world_models(state, slots, wp)
    restore = apply_saved(state)
    before = state.draw_models().copy()
    for w in range(worlds):
        apply_world(state, slots, wp, w)
        np.testing.assert_allclose(got[w], state.draw_models(), atol=1e-9, rtol=1e-9)
    restore()
    np.testing.assert_array_equal(state.draw_models(), before)


def test_root_nodes_take_their_pose_bit_for_bit() -> None:
    rng = np.random.default_rng(3)
    tree = make_tree(["a", "b"], np.array([-1, -1]), np.tile(np.eye(4), (2, 1, 1)))
    state = SceneState(tree, np.array([0, 1]), np.tile(np.eye(4), (2, 1, 1)),
                       np.zeros((2, 2, 3)), np.tile(np.eye(4), (2, 1, 1)))
    slots = WorldSlots.of(state, ["b", "a"])
    rows = np.concatenate([rng.normal(size=(3, 2, 3)), rng.normal(size=(3, 2, 4))], -1)
    got = world_models(state, slots, WorldPoses.of(rows, 2))
    for w in range(3):
        state.set_poses(["b", "a"], rows[w], space="world")
        assert np.array_equal(got[w], state.draw_models())


@pytest.mark.parametrize(("poses", "message"), [
    (np.zeros((2, 3, 7)), "shape"),
    (np.full((2, 2, 7), np.nan), "NaN"),
    (np.zeros((2, 2, 7)), "length 0"),
    (np.zeros((2, 2, 4, 4)), "last row"),
    (np.zeros((0, 2, 7)), "no worlds"),
    ("poses", "not an array"),
])
def test_bad_poses_are_one_line_errors(poses: object, message: str) -> None:
    with pytest.raises(UsageError, match=message) as err:
        WorldPoses.of(poses, 2)
    assert "\n" not in str(err.value)


def test_bad_visibility_and_order() -> None:
    rows = np.tile([0, 0, 0, 0, 0, 0, 1.0], (2, 2, 1))
    with pytest.raises(UsageError, match="visible"):
        WorldPoses.of(rows, 2, visible=np.ones((2, 3), bool))
    with pytest.raises(UsageError, match="quaternion"):
        WorldPoses.of(rows, 2, quaternion="zyxw")
    tree = make_tree(["a"], np.array([-1]), np.eye(4)[None])
    state = SceneState(tree, np.array([0]), np.eye(4)[None], np.zeros((1, 2, 3)), np.eye(4)[None])
    with pytest.raises(UsageError, match="nothing|no node|match"):
        WorldSlots.of(state, ["missing"])
    with pytest.raises(UsageError, match="twice"):
        WorldSlots.of(state, ["a", "a"])
