"""SceneState (the living scene, NumPy) against plain NumPy written here: random hierarchies,
random poses in both quaternion orders, local and world space, hidden subtrees, normal
matrices (np.linalg.inv), and what a change touches (the shadow cache's question)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vkpbr.errors import UsageError
from vkpbr.scene.state import SceneState, normal_matrices
from vkpbr.scene.tree import NodeTree


def random_tree(rng: np.random.Generator, k: int) -> NodeTree:
    parents = np.array([-1] + [int(rng.integers(-1, i)) for i in range(1, k)])
    local = np.tile(np.eye(4), (k, 1, 1))
    local[:, :3, 3] = rng.normal(size=(k, 3))
    local[:, :3, :3] = [rotation(q) * s for q, s in zip(rng.normal(size=(k, 4)),
                                                         rng.uniform(0.5, 2.0, k), strict=True)]
    return NodeTree([f"n{i}" for i in range(k)], parents, local, np.zeros((k, 3)),
                    np.tile([0.0, 0, 0, 1], (k, 1)), np.ones((k, 3)), np.ones(k, bool), np.arange(k))


def rotation(q: np.ndarray) -> np.ndarray:
    """The rotation of quaternion (x, y, z, w) by Rodrigues' formula (not the renderer's)."""
    q = q / np.linalg.norm(q)
    angle = 2 * np.arctan2(np.linalg.norm(q[:3]), q[3])
    axis = q[:3] / max(np.linalg.norm(q[:3]), 1e-300)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def world_by_walking(tree: NodeTree, local: np.ndarray) -> np.ndarray:
    out = np.zeros_like(local)
    for i in range(len(tree)):  # parents first
        p = tree.parents[i]
        out[i] = local[i] if p < 0 else out[p] @ local[i]
    return out


def state_of(tree: NodeTree) -> SceneState:
    k = len(tree)
    return SceneState(tree, np.arange(k), np.tile(np.eye(4), (k, 1, 1)),
                      np.tile([[-1.0, -1, -1], [1, 1, 1]], (k, 1, 1)), tree.world())


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), k=st.integers(1, 30))
def test_random_hierarchies_and_poses(seed: int, k: int) -> None:
    rng = np.random.default_rng(seed)
    tree = random_tree(rng, k)
    state = state_of(tree)
    np.testing.assert_allclose(state.world(), world_by_walking(tree, tree.local), atol=1e-9)
    nodes = rng.choice(k, size=int(rng.integers(1, k + 1)), replace=False)
    rows = np.concatenate([rng.normal(size=(len(nodes), 3)), rng.normal(size=(len(nodes), 4))], 1)
    state.set_poses(nodes, rows)  # x, y, z, w
    want = tree.local.copy()
    for n, row in zip(nodes, rows, strict=True):
        want[n] = np.eye(4)
        want[n, :3, :3], want[n, :3, 3] = rotation(row[3:]), row[:3]
    np.testing.assert_allclose(state.world(), world_by_walking(tree, want), atol=1e-9)
    # The same poses in w, x, y, z order give the same world.
    other = state_of(tree)
    other.set_poses(nodes, rows[:, [0, 1, 2, 6, 3, 4, 5]], quaternion="wxyz")
    np.testing.assert_allclose(other.world(), state.world(), atol=1e-12)
    # World-space poses land where asked, whatever the parents did.
    target = np.tile(np.eye(4), (len(nodes), 1, 1))
    target[:, :3, 3] = rng.normal(size=(len(nodes), 3))
    for n, t in zip(nodes, target, strict=True):  # one at a time: a parent may be among them
        state.set_pose(int(n), t, space="world")
        np.testing.assert_allclose(state.world()[n], t, atol=1e-9)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), k=st.integers(2, 30))
def test_hidden_subtrees_and_what_a_change_touches(seed: int, k: int) -> None:
    rng = np.random.default_rng(seed)
    tree = random_tree(rng, k)
    state = state_of(tree)
    node = int(rng.integers(0, k))
    below = {node}
    for i in range(k):
        if tree.parents[i] in below:
            below.add(i)
    state.set_visible(node, False)
    models = state.draw_models()
    hidden = np.all(models == 0, axis=(1, 2))
    assert set(np.flatnonzero(hidden)) == below
    v = state.version
    assert state.changed_since(np.isin(np.arange(k), sorted(below))) == v
    untouched = ~np.isin(np.arange(k), sorted(below))
    assert state.changed_since(untouched) < v or not untouched.any()


def test_normal_matrices_are_the_inverse_transpose() -> None:
    rng = np.random.default_rng(3)
    m = np.tile(np.eye(4), (200, 1, 1))
    m[:, :3, :3] = rng.normal(size=(200, 3, 3))
    n = normal_matrices(m)
    np.testing.assert_allclose(n[:, :3, :3], np.linalg.inv(m[:, :3, :3]).transpose(0, 2, 1),
                               rtol=1e-7, atol=1e-7)
    assert np.all(normal_matrices(np.zeros((1, 4, 4)))[0, :3, :3] == 0)  # a hidden draw's


def test_names_paths_and_patterns() -> None:
    tree = NodeTree(["truck", "wheel_f", "wheel_r", "cab"], np.array([-1, 0, 0, 0]),
                    np.tile(np.eye(4), (4, 1, 1)), np.zeros((4, 3)), np.tile([0.0, 0, 0, 1], (4, 1)),
                    np.ones((4, 3)), np.ones(4, bool), np.arange(4))
    assert tree.find("wheel*").tolist() == [1, 2]
    assert tree.find("truck/cab").tolist() == [3]
    assert tree.indices(["cab", 0]).tolist() == [3, 0]
    with pytest.raises(UsageError, match="no node is named"):
        tree.indices("axle")
    with pytest.raises(UsageError, match="out of range"):
        tree.indices(4)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), k=st.integers(1, 25), steps=st.integers(1, 8))
def test_frame_updates_of_changed_subtrees_match_plain_numpy(seed: int, k: int, steps: int) -> None:
    """Poses and visibility set in random steps, the frame's arrays read between some of
    them (so that each update covers only what changed since): the world matrices, models,
    GPU records (model and np.linalg.inv normal matrix) and bounds equal plain NumPy's of
    the final state, and a draw's version moves exactly when its subtree changed."""
    rng = np.random.default_rng(seed)
    tree = random_tree(rng, k)
    state = state_of(tree)
    local, visible = tree.local.copy(), np.ones(k, bool)
    for _ in range(steps):
        nodes = rng.choice(k, size=int(rng.integers(1, k + 1)), replace=False)
        before = state.draw_versions.copy() if rng.random() < 0.5 else None
        if before is not None:
            state.draw_models()
            before = state.draw_versions.copy()
        if rng.random() < 0.3:
            mask = rng.random(len(nodes)) < 0.5
            state.set_visible(nodes, mask)
            visible[nodes] = mask
        elif rng.random() < 0.5:
            rows = np.concatenate([rng.normal(size=(len(nodes), 3)), rng.normal(size=(len(nodes), 4))], 1)
            state.set_poses(nodes, rows)
            for n, row in zip(nodes, rows, strict=True):
                local[n] = np.eye(4)
                local[n, :3, :3], local[n, :3, 3] = rotation(row[3:]), row[:3]
        else:
            mats = np.tile(np.eye(4), (len(nodes), 1, 1))
            mats[:, :3, :3] = rng.normal(size=(len(nodes), 3, 3)) + 2 * np.eye(3)
            mats[:, :3, 3] = rng.normal(size=(len(nodes), 3))
            state.set_poses(nodes, mats)
            local[nodes] = mats
        if before is not None:  # the draws below the changed nodes, and only they, move on
            below = np.zeros(k, bool)
            below[nodes] = True
            for i in range(k):
                below[i] |= tree.parents[i] >= 0 and below[tree.parents[i]]
            state.draw_models()
            assert np.all((state.draw_versions > before) == below)
    world = world_by_walking(tree, local)
    shown = visible.copy()
    for i in range(k):
        shown[i] &= tree.parents[i] < 0 or shown[tree.parents[i]]
    want = np.where(shown[:, None, None], world, 0.0)
    np.testing.assert_allclose(state.world(), world, atol=1e-9)
    np.testing.assert_allclose(state.draw_models(), want, atol=1e-9)
    rec = state.draw_matrices()
    np.testing.assert_allclose(rec[:, 0], np.swapaxes(want, 1, 2), atol=1e-5)
    for i in np.flatnonzero(shown):
        inv_t = np.linalg.inv(world[i, :3, :3]).T
        np.testing.assert_allclose(rec[i, 1, :3, :3], inv_t.T, rtol=1e-4, atol=1e-4)
    lo, hi = state.bounds()
    if shown.any():
        corners = np.array([[x, y, z, 1.0] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        pts = np.einsum("dij,cj->dci", world[shown], corners)[..., :3].reshape(-1, 3)
        np.testing.assert_allclose(lo, pts.min(0), atol=1e-9)
        np.testing.assert_allclose(hi, pts.max(0), atol=1e-9)
    else:
        assert np.all(lo == 0) and np.all(hi == 0)


def test_set_poses_keeps_no_reference_to_the_callers_arrays() -> None:
    tree = random_tree(np.random.default_rng(1), 4)
    state = state_of(tree)
    rows = np.array([[1.0, 2, 3, 0, 0, 0, 1]] * 2)
    nodes = np.array([0, 1])
    state.set_poses(nodes, rows)
    rows[:] = 0.0  # changed after the call (the frame makes the matrices later)
    nodes[:] = 3
    np.testing.assert_allclose(state.local[:2, :3, 3], [[1, 2, 3], [1, 2, 3]])
    np.testing.assert_allclose(state.local[3], tree.local[3])
