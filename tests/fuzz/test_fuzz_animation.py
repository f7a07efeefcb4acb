"""Bad animation, skin and morph input (issue 31, item 7): each case a one-line SceneError
naming the file and the animation/skin/mesh, or the fallback docs/animation.md states; then
seeded random mutations of an animated, skinned and morphed file (JSON and GLB bytes), each of
which must load (and sample) or fail in one line naming the file (tests/fuzzing.py's rule)."""

from __future__ import annotations

import json
import random
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from fuzzing import mutate_bytes, mutate_json, run_one
from gltf_files import GltfFile

from vkpbr.errors import SceneError, VkpbrError
from vkpbr.scene.animation import sample
from vkpbr.scene.gltf import load_gltf
from vkpbr.scene.gltf_meshes import MAX_MORPH_TARGETS


def _seed_file() -> GltfFile:
    """Root 0 with joints 1 and 2 and the skinned, morphed mesh node 3; node 4 is in no
    scene. Animation "walk": LINEAR translation of 1, CUBICSPLINE rotation of 2, STEP weights
    of 3; accessors: 0 POSITION, 1 JOINTS_0, 2 WEIGHTS_0, 3 target, 4 indices, 5 inverse
    binds, 6 NORMAL."""
    f = GltfFile()
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], np.float32)
    attrs = {"POSITION": f.accessor(pos),
             "JOINTS_0": f.accessor(np.array([[0, 1, 0, 0]] * 4, np.uint16)),
             "WEIGHTS_0": f.accessor(np.array([[0.5, 0.5, 0, 0]] * 4, np.float32))}
    target = f.accessor(np.full((4, 3), 0.25, np.float32))
    f.mesh(attrs, f.accessor(np.array([0, 1, 2, 2, 1, 3], np.uint16)[:, None]),
           targets=[{"POSITION": target}])
    ibm = np.tile(np.eye(4, dtype=np.float32), (2, 1, 1))
    view = f.view(ibm.tobytes())
    f.doc["accessors"].append({"bufferView": view, "componentType": 5126, "count": 2,
                               "type": "MAT4"})
    attrs["NORMAL"] = f.accessor(np.float32([[0, 0, 1]] * 4))  # the dict is the mesh's
    f.node(children=[1, 2, 3])
    f.node(root=False, translation=[0, 1, 0])
    f.node(root=False, rotation=[0, 0, 0, 1])
    f.node(root=False, mesh=0, skin=0)
    f.node(root=False, name="elsewhere")
    f.doc["skins"] = [{"name": "rig", "joints": [1, 2], "inverseBindMatrices": 5}]
    times = f.accessor(np.float32([[0.0], [0.5], [1.0]]))
    anim = {"name": "walk", "samplers": [
        {"input": times, "output": f.accessor(np.float32(np.arange(9).reshape(3, 3)))},
        {"input": times, "output": f.accessor(np.tile(np.float32([0, 0, 0, 1]), (9, 1))),
         "interpolation": "CUBICSPLINE"},
        {"input": times, "output": f.accessor(np.float32([[0.0], [0.5], [1.0]])),
         "interpolation": "STEP"}],
        "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}},
                     {"sampler": 1, "target": {"node": 2, "path": "rotation"}},
                     {"sampler": 2, "target": {"node": 3, "path": "weights"}}]}
    f.doc["animations"] = [anim]
    return f


def _data(f: GltfFile, accessor: int, values: np.ndarray) -> None:
    """Overwrite accessor's bytes (buffer 0) with `values` of its own dtype and size."""
    acc = f.doc["accessors"][accessor]
    view = f.doc["bufferViews"][acc["bufferView"]]
    raw = np.ascontiguousarray(values).tobytes()
    assert len(raw) <= view["byteLength"]
    buf = f.buffers[0]
    buf[view["byteOffset"]:view["byteOffset"] + len(raw)] = raw


def _times(f: GltfFile, values: list[float]) -> None:
    _data(f, f.doc["animations"][0]["samplers"][0]["input"], np.float32(values))


def _sampler0(f: GltfFile) -> dict:
    return f.doc["animations"][0]["samplers"][0]


def _add_targets(f: GltfFile, n: int) -> None:
    f.doc["meshes"][0]["primitives"][0]["targets"] = [{"POSITION": 3}] * n


ERRORS: dict[str, tuple[Callable[[GltfFile], None], str]] = {
    "times not increasing": (lambda f: _times(f, [0.0, 0.5, 0.5]),
                             r"animation 'walk': sampler 0: keyframe times are not increasing"),
    "times negative": (lambda f: _times(f, [-1.0, 0.5, 1.0]), "finite and >= 0"),
    "time infinite": (lambda f: _times(f, [0.0, 0.5, np.inf]), "finite and >= 0"),
    "value NaN": (lambda f: _data(f, _sampler0(f)["output"], np.float32([np.nan] * 3)),
                  "animation 'walk': sampler 0: output has non-finite values"),
    "output count": (lambda f: _sampler0(f).update(output=2),
                     r"output has 16 values, expected 3 keyframes x 1 x 3"),
    "cubic output count": (lambda f: _sampler0(f).update(interpolation="CUBICSPLINE"),
                           r"output has 9 values, expected 3 keyframes x 3 x 3"),
    "interpolation": (lambda f: _sampler0(f).update(interpolation="SMOOTH"),
                      "unknown interpolation 'SMOOTH'"),
    "sampler index": (lambda f: f.doc["animations"][0]["channels"][0].update(sampler=7),
                      "animation 'walk' channel 0 sampler 7 out of range"),
    "channel node missing": (lambda f: f.doc["animations"][0]["channels"][0]["target"].update(
        node=9), "animation 'walk' channel 0 target node 9 out of range"),
    "weights without targets": (lambda f: f.doc["animations"][0]["channels"][2]["target"].update(
        node=1), "animates the weights of node 1, whose mesh has no morph targets"),
    "matrix node animated": (lambda f: f.doc["nodes"][1].update(
        translation=None, matrix=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 2, 3, 1]),
        "node 1, which gives a matrix"),
    "joint beyond the skin": (lambda f: _data(f, 1, np.uint16([[0, 2, 0, 0]] * 4)),
                              "joint index 2 is beyond skin 'rig''s 2 joints"),
    "skin joint missing": (lambda f: f.doc["skins"][0].update(joints=[1, 12]),
                           "skin 'rig' joint 12 out of range"),
    "skin joint not shown": (lambda f: f.doc["skins"][0].update(joints=[1, 4]),
                             "skin 'rig': joint node 4 is not in the displayed scene"),
    "inverse binds NaN": (lambda f: _data(f, 5, np.float32([np.nan] * 16)),
                          "skin 'rig': inverseBindMatrices has non-finite values"),
    "inverse binds short": (lambda f: f.doc["skins"][0].update(joints=[1, 2, 0]),
                            "inverseBindMatrices must be 3 float MAT4"),
    "weights negative": (lambda f: _data(f, 2, np.float32([[1.5, -0.5, 0, 0]] * 4)),
                         "skin weights must be finite and >= 0"),
    "joints without weights": (lambda f: f.doc["meshes"][0]["primitives"][0]["attributes"].pop(
        "WEIGHTS_0"), "JOINTS_0 and WEIGHTS_0 come in pairs"),
    "too many targets": (lambda f: _add_targets(f, MAX_MORPH_TARGETS + 1),
                         f"{MAX_MORPH_TARGETS + 1} morph targets, more than vkpbr's budget of "
                         f"{MAX_MORPH_TARGETS}"),
    "mesh weights count": (lambda f: f.doc["meshes"][0].update(weights=[0.1, 0.2]),
                           "weights must be 1 numbers"),
    "node weights count": (lambda f: f.doc["nodes"][3].update(weights=[0.1, 0.2]),
                           "node 3: 2 weights for mesh 0's 1 morph targets"),
    "target NaN": (lambda f: _data(f, 3, np.float32([np.nan] * 12)),
                   "morph target POSITION has non-finite values"),
    "primitives disagree": (lambda f: f.doc["meshes"][0]["primitives"].append(
        {"attributes": {"POSITION": 0}, "indices": 4}), "different numbers of morph targets"),
}


@pytest.mark.parametrize("case", sorted(ERRORS))
def test_bad_animation_input_is_one_line_naming_the_file(tmp_path: Path, case: str) -> None:
    f = _seed_file()
    edit, match = ERRORS[case]
    edit(f)
    f.doc = json.loads(json.dumps(f.doc, default=lambda o: None))
    for node in f.doc["nodes"]:  # a None left by an edit is a field removed
        for key in [k for k, v in node.items() if v is None]:
            del node[key]
    path = f.save(tmp_path / "anim.glb")
    with pytest.raises(SceneError) as info:
        load_gltf(path)
    text = str(info.value)
    assert "\n" not in text and "anim.glb" in text, text
    assert match in text, text


def test_the_seed_file_loads_and_samples(tmp_path: Path) -> None:
    scene = load_gltf(_seed_file().save(tmp_path / "anim.glb"))
    pose = sample(scene, np.array([0.25, 0.75, 2.0]))
    np.testing.assert_allclose(pose.translation[:, 1], [[1.5, 2.5, 3.5], [4.5, 5.5, 6.5],
                                                        [6, 7, 8]])
    np.testing.assert_allclose(pose.weights[3][:, 0], [0.0, 0.5, 1.0])  # STEP


def test_weights_not_summing_to_one_are_normalised(tmp_path: Path) -> None:
    """The spec's fallback: a loader may renormalise. A row of zeros binds to its first joint."""
    f = _seed_file()
    _data(f, 2, np.float32([[2, 2, 0, 0], [0, 0, 0, 0], [1, 3, 0, 0], [0, 0.3, 0, 0]]))
    mesh = load_gltf(f.save(tmp_path / "w.glb")).meshes[0]
    assert mesh.joints.shape == (4, 8) and mesh.weights.shape == (4, 8)
    np.testing.assert_allclose(mesh.weights[:, :2], [[0.5, 0.5], [1, 0], [0.25, 0.75], [0, 1]])
    assert mesh.joints.dtype == np.uint16 and mesh.joints[3, 0] == 0  # weight 0: joint 0


def test_channels_on_nodes_outside_the_scene_are_dropped(tmp_path: Path) -> None:
    f = _seed_file()
    f.doc["animations"][0]["channels"][0]["target"]["node"] = 4
    scene = load_gltf(f.save(tmp_path / "drop.glb"))
    assert [c.path for c in scene.animations[0].channels] == ["rotation", "weights"]
    assert len(scene.animations[0].samplers) == 2  # renumbered: only the used ones


def test_unknown_paths_are_one_warning(tmp_path: Path) -> None:
    f = _seed_file()
    for ch in f.doc["animations"][0]["channels"][:2]:
        ch["target"]["path"] = "skew"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_gltf(f.save(tmp_path / "skew.glb"))
    lines = [str(w.message) for w in caught if "skew" in str(w.message)]
    assert len(lines) == 1 and "skew.glb" in lines[0]
    assert [c.path for c in scene.animations[0].channels] == ["weights"]


@pytest.mark.timeout(120)
def test_random_mutations_load_or_fail_in_one_line(tmp_path: Path) -> None:
    """60 JSON and 30 byte mutations of the seed file; a loaded one must sample too."""
    rng = random.Random(31)
    seed = _seed_file()
    base = seed.save(tmp_path / "seed.glb")
    doc = json.loads(json.dumps(seed.doc))
    outcomes: dict[str, int] = {"loaded": 0, "clean": 0}
    failures = []
    for k in range(90):
        if k < 60:
            seed.doc = mutate_json(doc, rng)
            path = seed.save(tmp_path / f"m{k}.gltf")
        else:
            path = tmp_path / f"m{k}.glb"
            path.write_bytes(mutate_bytes(base.read_bytes(), rng))
        outcome, detail = run_one(path, path.name)
        if outcome == "loaded":
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    sample(load_gltf(path), np.array([-1.0, 0.3, 0.9, 5.0]))
            except VkpbrError as exc:
                outcome, detail = "unclean", f"sampling: {exc}"
            except Exception as exc:  # noqa: BLE001 - the point of the test
                outcome, detail = "unclean", f"sampling: {type(exc).__name__}: {exc}"
        if outcome == "unclean":
            failures.append(f"{path.name}: {detail}")
        else:
            outcomes[outcome] += 1
    assert not failures, "\n".join(failures[:10])
    assert outcomes["loaded"] > 2 and outcomes["clean"] > 20, outcomes
