"""Job entries with per-view worlds (issue 32, must-have 6) without a cluster: the "worlds"
key's checks (one line each, before any actor starts), the items' worlds, the manifest's
per-view world digests (a view whose world changed is not done, the others are), and the
renderer actor in-process: each view's frame equals `render` of its world alone (set with
set_poses(space="world") / set_visible), bit for bit on lavapipe, on both of its routes."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image

from vkpbr.app.cli import main
from vkpbr.distributed import MANIFEST_NAME, Manifest, job_from_doc, load_job
from vkpbr.errors import UsageError

# Two spheres of the built-in chart (scene: null), moved per world.
NODES = ["sphere-m0-r0", "sphere-m4-r3"]
POSES = ["0,1.5,6,0,1,0", "1,1.5,6,0,1,0", "-1,1.5,6,0,1,0", "0.5,2,6,0,1,0"]
SIZE = (64, 48)


def world_rows(worlds: int, seed: int = 0) -> np.ndarray:
    """(W, 2, 7) position + x,y,z,w quaternion rows: the spheres moved about the chart."""
    rng = np.random.default_rng(seed)
    rows = np.zeros((worlds, len(NODES), 7))
    rows[..., :3] = rng.normal(0.0, 0.6, (worlds, len(NODES), 3)) + [0.0, 1.0, 0.5]
    q = rng.normal(0.0, 1.0, (worlds, len(NODES), 4))
    rows[..., 3:] = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return rows


def write_job(folder: Path, worlds: object, **entry: object) -> Path:
    path = folder / "job.json"
    path.write_text(json.dumps([{"cameras": POSES, "out": "out", "size": list(SIZE),
                                 "worlds": worlds, **entry}]))
    return path


def test_entry_worlds_and_items(tmp_path: Path) -> None:
    rows = world_rows(2)
    np.save(tmp_path / "w.npy", rows)
    job = load_job(write_job(tmp_path, {"nodes": NODES, "poses": "w.npy", "quaternion": "wxyz",
                                        "visible": [[True, True], [False, True]],
                                        "world_of_view": [1, 0, 1, 1]}))
    worlds = job.scenes[0].worlds
    assert worlds.quaternion == "wxyz" and np.array_equal(worlds.poses, rows)
    assert worlds.world_of_view.tolist() == [1, 0, 1, 1]
    # An item ships only the worlds its views see, indexed per view.
    job2 = load_job(write_job(tmp_path, {"nodes": NODES, "poses": "w.npy",
                                         "world_of_view": [1, 0, 1, 1]}))
    item = job_from_doc({"scenes": json.loads((tmp_path / "job.json").read_text()),
                         "views_per_item": 2}, "job", tmp_path).items()[1]
    assert item.frames == (2, 3) and len(item.worlds.poses) == 1
    assert np.array_equal(item.worlds.poses[0], rows[1]) and item.worlds.index.tolist() == [0, 0]
    # Views of one world share a digest; another world, another visibility: another digest.
    d = [job.scenes[0].world_digest(v) for v in range(4)]
    assert d[0] == d[2] == d[3] != d[1] and len(d[0]) == 32
    assert job2.scenes[0].world_digest(1) != job.scenes[0].world_digest(1)  # visibility differs
    # Integer node indices, and matrices.
    mats = np.broadcast_to(np.eye(4), (4, 1, 4, 4)).copy()
    np.save(tmp_path / "m.npy", mats)
    job3 = load_job(write_job(tmp_path, {"nodes": [3], "poses": "m.npy"}))
    assert job3.scenes[0].worlds.poses.shape == (4, 1, 4, 4)


def _save(folder: Path, name: str, array: np.ndarray) -> str:
    np.save(folder / name, array)
    return name


def _bad_cases(tmp: Path) -> list[tuple[object, str]]:
    """(worlds value, expected message) pairs; files written into `tmp`."""
    ok = _save(tmp, "ok.npy", world_rows(4))
    nan = world_rows(4)
    nan[2, 1, 0] = np.nan
    zero_q = world_rows(4)
    zero_q[1, 0, 3:] = 0.0
    (tmp / "text.npy").write_text("not numpy")
    data = (tmp / "ok.npy").read_bytes()
    (tmp / "short.npy").write_bytes(data[:len(data) - 40])
    np.save(tmp / "objects.npy", np.array([{"a": 1}] * 4, dtype=object), allow_pickle=True)
    os.mkfifo(tmp / "fifo.npy")
    (tmp.parent / "outside.npy").write_bytes(data)
    return [
        ("w.npy", "worlds: expected an object with nodes and poses, got a string"),
        ({"nodes": NODES}, 'worlds: missing "poses"'),
        ({"nodes": NODES, "poses": ok, "pose": 1}, "worlds: unknown key 'pose'"),
        ({"nodes": [], "poses": ok}, "worlds: nodes: expected a list of node names"),
        ({"nodes": [True], "poses": ok}, "worlds: nodes: expected"),
        ({"nodes": ["a", "a"], "poses": ok}, "names one twice"),
        ({"poses": ok}, 'worlds: missing "nodes"'),
        ({"quaternion": "wxyz"}, 'worlds: missing "poses" (or "materials")'),
        ({"materials": {"names": ["floor"]}}, "worlds: materials: no factor given"),
        ({"materials": {"base_color": [[[1, 1, 1]]] * 4}}, 'materials: missing "names"'),
        ({"materials": {"names": ["floor"], "shine": 1}}, "materials: unknown key 'shine'"),
        ({"materials": {"names": ["floor"], "metallic": [[0.5]] * 3}},
         "3 world(s) for 4 view(s)"),
        ({"materials": {"names": ["floor"], "metallic": [[0.5, 0.5]] * 4}},
         r"metallic \(inline\): shape \(4, 2\) of float64; give \(worlds, 1\)"),
        ({"materials": {"names": ["floor"], "roughness": [[0.5]] * 3 + [[1.5]]}},
         r"roughness \(inline\): world 3 holds a value not within \[0, 1\]"),
        ({"materials": {"names": ["floor"], "emissive": [[[0, 0, -1]]] * 4}},
         "world 0 holds a value not >= 0"),
        ({"materials": {"names": ["floor"], "base_color": [[[0, 0, 1]]] * 4,
                        "metallic": [[0.5]] * 3}}, "the factors give [3, 4] worlds"),
        ({"nodes": NODES, "poses": ok, "materials": {"names": ["floor"], "metallic": [[0.5]] * 3}},
         "materials give 3 worlds, poses 4"),
        ({"nodes": NODES, "poses": ok, "quaternion": "wxzy"}, 'quaternion: expected "xyzw"'),
        ({"nodes": NODES, "poses": "missing.npy"}, "worlds: poses missing.npy: no such file"),
        ({"nodes": NODES, "poses": "../outside.npy"}, "is outside the job file's folder"),
        ({"nodes": NODES, "poses": "/dev/zero"}, "is outside the job file's folder"),
        ({"nodes": NODES, "poses": "fifo.npy"}, "poses fifo.npy: not a regular file"),
        ({"nodes": NODES, "poses": "text.npy"}, "poses text.npy: not a .npy file"),
        ({"nodes": NODES, "poses": "short.npy"}, "poses short.npy: the file is cut short"),
        ({"nodes": NODES, "poses": "objects.npy"}, "an array of object: give plain numbers"),
        ({"nodes": NODES, "poses": _save(tmp, "six.npy", np.zeros((4, 2, 6)))},
         r"shape \(4, 2, 6\); give \(worlds, nodes, 7\)"),
        ({"nodes": NODES[:1], "poses": ok}, "2 node(s) a world, but nodes names 1"),
        ({"nodes": NODES, "poses": _save(tmp, "three.npy", world_rows(3))},
         'worlds: 3 world(s) for 4 view(s); give one world per view, or "world_of_view"'),
        ({"nodes": NODES, "poses": _save(tmp, "nan.npy", nan)}, "world 2 holds NaN or infinity"),
        ({"nodes": NODES, "poses": _save(tmp, "zq.npy", zero_q)}, "a quaternion of length 0"),
        ({"nodes": NODES, "poses": ok, "visible": [[True, False]]},
         r"visible \(inline\): shape \(1, 2\), expected \(4, 2\)"),
        ({"nodes": NODES, "poses": ok, "visible": _save(tmp, "vis.npy", np.full((4, 2), 0.5))},
         "an array of float64; give bools"),
        ({"nodes": NODES, "poses": ok, "world_of_view": [0, 1, 2, 4]},
         r"view 3 sees world 4, out of range \(0..3\)"),
        ({"nodes": NODES, "poses": ok, "world_of_view": [0, 1]}, r"expected \(4,\) integers"),
    ]


def test_bad_worlds_are_one_line_before_any_work(capsys, tmp_path: Path) -> None:  # noqa: ANN001
    folder = tmp_path / "job"
    folder.mkdir()
    for worlds, message in _bad_cases(folder):
        code = main(["batch", str(write_job(folder, worlds))])
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1, (worlds, err)
        assert err.startswith(f"vkpbr: error: {folder / 'job.json'}: entry 0: worlds"), err
        assert re.search(message if "\\" in message else re.escape(message), err), (message, err)
        assert not (folder / "out").exists()


_KEYS = ["nodes", "poses", "quaternion", "visible", "world_of_view", "materials", "names",
         "base_color", "metallic", "roughness", "emissive"]
_LEAF = st.one_of(st.none(), st.booleans(), st.integers(-5, 10**30),
                  st.floats(allow_nan=False, allow_infinity=False), st.text(max_size=5),
                  st.sampled_from(["ok.npy", "../ok.npy", "sphere-*", "xyzw", "wxyz", "floor"]))
_DOCS = st.recursive(_LEAF, lambda c: st.one_of(st.lists(c, max_size=4),
                                                st.dictionaries(st.sampled_from(_KEYS), c, max_size=5)),
                     max_leaves=30)


@settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck))
@given(worlds=_DOCS)
def test_any_worlds_document_is_checked_or_one_line(tmp_path_factory: pytest.TempPathFactory,
                                                    worlds: object) -> None:
    """Random "worlds" values: accepted, or one UsageError line naming the entry; nothing
    else escapes (an AttributeError on a null was found this way)."""
    base = tmp_path_factory.getbasetemp() / "any-worlds"
    if not (base / "ok.npy").exists():
        base.mkdir(exist_ok=True)
        np.save(base / "ok.npy", world_rows(3))
    try:
        job_from_doc([{"cameras": POSES[:3], "out": str(base / "o"), "worlds": worlds}], "job", base)
    except UsageError as exc:
        assert str(exc).startswith("job: entry 0: worlds") and "\n" not in str(exc), exc


def test_outside_paths_are_read_when_the_entry_allows_them(tmp_path: Path) -> None:
    (tmp_path / "job").mkdir()
    np.save(tmp_path / "w.npy", world_rows(4))
    job = load_job(write_job(tmp_path / "job", {"nodes": NODES, "poses": "../w.npy"},
                             allow_outside_paths=True))
    assert job.scenes[0].worlds.poses.shape == (4, 2, 7)
    with pytest.raises(UsageError, match="outside the job file's folder"):
        load_job(write_job(tmp_path / "job", {"nodes": NODES, "poses": "../w.npy"}))


def test_manifest_keeps_views_whose_world_is_unchanged(tmp_path: Path) -> None:
    """A changed world makes only its views undone (and transforms.json wait for them); an
    entry without worlds does not take the views rendered in a world as its own."""
    rows = world_rows(4)
    np.save(tmp_path / "w.npy", rows)
    scene = load_job(write_job(tmp_path, {"nodes": NODES, "poses": "w.npy"})).scenes[0]
    out = tmp_path / "out"
    out.mkdir()
    m = Manifest.open(out, scene.fingerprint(), "e", len(scene.poses), scene.files,
                      scene.world_digest)
    cam = {"eye": [0.0, 1.0, 3.0], "target": [0.0, 0.0, 0.0]}
    for v in range(4):
        (out / f"frame_{v:05d}.png").write_bytes(b"x")
    m.done([0, 1, 2, 3], [f"frame_{v:05d}.png" for v in range(4)], [cam] * 4)
    m.close()
    rec = json.loads((out / MANIFEST_NAME).read_text().splitlines()[1])
    assert rec["worlds"] == [scene.world_digest(v) for v in range(4)]

    def reopened(worlds: object = None) -> Manifest:
        s = load_job(write_job(tmp_path, worlds)).scenes[0]
        return Manifest.open(out, s.fingerprint(), "e", len(s.poses), s.files,
                             s.world_digest if s.worlds is not None else None)

    assert reopened({"nodes": NODES, "poses": "w.npy"}).done_views() == {0, 1, 2, 3}
    rows[2, 0, 0] += 0.25
    np.save(tmp_path / "w.npy", rows)
    again = reopened({"nodes": NODES, "poses": "w.npy"})
    assert again.done_views() == {0, 1, 3} and again.cameras() is None
    assert reopened({"nodes": NODES[::-1], "poses": "w.npy"}).done_views() == set()
    assert reopened().done_views() == set()  # an entry without worlds
    # A damaged digest is one line naming the manifest and the line.
    text = (out / MANIFEST_NAME).read_text().replace(rec["worlds"][1], "xyz")
    (out / MANIFEST_NAME).write_text(text)
    with pytest.raises(UsageError, match=r"line 2: worlds: expected one world digest"):
        reopened({"nodes": NODES, "poses": "w.npy"})


@pytest.fixture
def actor(monkeypatch: pytest.MonkeyPatch):  # noqa: ANN201
    """A renderer actor in this process, its Renderer under the validation layer."""
    from vkpbr.distributed.actor import RendererActor

    monkeypatch.setenv("VKPBR_VALIDATION", "1")
    a = RendererActor()
    yield a
    a.close()


def _alone(renderer, camera, rows: np.ndarray, shown: np.ndarray | None, **options):  # noqa: ANN001, ANN202
    """`render` of one world set through the public API, then put back."""
    renderer.set_poses(NODES, rows, space="world", quaternion="xyzw")
    if shown is not None:
        renderer.set_visible([n for n, s in zip(NODES, shown, strict=True) if not s], False)
    try:
        # (the compute batch's rasteriser: a view then renders the same bytes in a batch as
        # alone on lavapipe, docs/batch.md)
        return renderer.render(camera, size=SIZE, raster="compute", **options)
    finally:
        renderer.state.reset()


@pytest.mark.parametrize(("shadows", "batch"), [(False, 64), (True, 64), (False, 0)])
def test_actor_renders_each_view_in_its_world(actor, tmp_path: Path, shadows: bool,  # noqa: ANN001
                                              batch: int) -> None:
    """Shadows off: one batch of worlds; on (or batch 0): world by world on the state (a
    batch's shadow maps are the state's). Each gives each view as `render` of its world
    alone."""
    rows = world_rows(3, seed=4)
    shown = np.array([[True, True], [False, True], [True, True]])
    np.save(tmp_path / "w.npy", rows)
    np.save(tmp_path / "v.npy", shown)
    options = {"shadows": shadows, "ao": "off"}
    job = load_job(write_job(tmp_path, {"nodes": NODES, "poses": "w.npy", "visible": "v.npy",
                                        "world_of_view": [2, 0, 1, 2]}, options=options,
                             batch=batch))
    item = job.items()[0]
    res = actor.render(item)
    assert res["ok"], res
    r = actor._renderer
    cams = [p.camera(r.default_camera()) for p in item.poses]
    rest = r.render(cams[0], size=SIZE, **options)
    for v, w in enumerate([2, 0, 1, 2]):
        got = np.asarray(Image.open(tmp_path / "out" / f"frame_{v:05d}.png"))
        want = _alone(r, cams[v], rows[w], shown[w], **options)
        assert np.array_equal(got, want), f"view {v} (world {w})"
    assert not np.array_equal(np.asarray(Image.open(tmp_path / "out" / "frame_00000.png")), rest)
    assert np.array_equal(r.render(cams[0], size=SIZE, **options), rest)  # the state put back


def test_worlds_job_on_renderer_processes_equals_in_process(tmp_path: Path,
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """A job whose views carry world state renders the same files on renderer processes
    (its items' worlds pickled to them) as in this process."""
    from vkpbr.distributed import render
    from vkpbr.distributed.driver import IN_PROCESS, PROCESSES

    monkeypatch.setenv("VKPBR_VALIDATION", "1")
    monkeypatch.setenv("VKPBR_CACHE_DIR", str(tmp_path / "cache"))
    rows = world_rows(3, seed=7)
    files = {}
    for how in (IN_PROCESS, PROCESSES):
        folder = tmp_path / how
        folder.mkdir()
        np.save(folder / "w.npy", rows)
        doc = json.loads(write_job(folder, {"nodes": NODES, "poses": "w.npy",
                                            "world_of_view": [2, 0, 1, 2]},
                                   options={"ao": "off"}).read_text())
        result = render(job_from_doc({"scenes": doc, "views_per_item": 2}, "job", folder), how,
                        actors=2 if how == PROCESSES else None)
        assert result.ok and result.rendered == len(POSES), result.summary()
        files[how] = {p.name: p.read_bytes() for p in sorted((folder / "out").glob("frame_*"))}
    assert files[IN_PROCESS] and files[PROCESSES] == files[IN_PROCESS]


def test_actor_fails_an_item_whose_nodes_the_scene_lacks(actor, tmp_path: Path) -> None:  # noqa: ANN001
    """Names are checked against the scene on the actor: bad input, no retry, one line."""
    np.save(tmp_path / "w.npy", world_rows(4))
    for nodes, message in ((["sphere-m0-r0", "no-such-node"], "no node is named 'no-such-node'"),
                           (["sphere-m*-r0", "floor*"], "are 6 node(s) of the scene")):
        job = load_job(write_job(tmp_path, {"nodes": nodes, "poses": "w.npy"}))
        res = actor.render(job.items()[0])
        assert not res["ok"] and res["retry"] is False, res
        assert res["error"].startswith(f"UsageError: {tmp_path / 'job.json'}: entry 0: worlds: "
                                       "nodes"), res["error"]
        assert message in res["error"] and "\n" not in res["error"]
        assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("shadows", [True, False])
def test_actor_renders_material_overrides_per_world(actor, tmp_path: Path, shadows: bool) -> None:  # noqa: ANN001
    """Material factors per world (with poses, and alone; world by world, and through
    render_batch(world_materials=) with shadows off): each view as `render` after
    set_material of its world's factors; the overrides are put back after the item."""
    rng = np.random.default_rng(8)
    colors = rng.uniform(0.0, 1.0, (4, 2, 3))
    rough = rng.uniform(0.0, 1.0, (4, 2))
    np.save(tmp_path / "c.npy", colors)
    rows = world_rows(4, seed=9)
    np.save(tmp_path / "w.npy", rows)
    materials = {"names": ["floor", "sphere-m0-r0"], "base_color": "c.npy", "roughness": rough.tolist()}
    for worlds in ({"materials": materials}, {"nodes": NODES, "poses": "w.npy", "materials": materials}):
        job = load_job(write_job(tmp_path, worlds, options={"ao": "off", "shadows": shadows}))
        res = actor.render(job.items()[0])
        assert res["ok"], res
        r = actor._renderer
        assert r.state.materials == {}  # the item's overrides put back
        cams = [p.camera(r.default_camera()) for p in job.scenes[0].poses]
        rest = r.render(cams[0], size=SIZE, ao="off", shadows=shadows)
        for v in range(4):
            if "poses" in worlds:
                r.set_poses(NODES, rows[v], space="world")
            for m, name in enumerate(materials["names"]):
                r.state.set_material(name, base_color=colors[v, m], roughness=rough[v, m])
            want = r.render(cams[v], size=SIZE, ao="off", shadows=shadows, raster="compute")
            r.state.reset()
            got = np.asarray(Image.open(tmp_path / "out" / f"frame_{v:05d}.png"))
            assert np.array_equal(got, want), (worlds.keys(), v)
        assert not np.array_equal(np.asarray(Image.open(tmp_path / "out" / "frame_00000.png")), rest)
        for f in (tmp_path / "out").iterdir():
            f.unlink()
    job = load_job(write_job(tmp_path, {"materials": {**materials, "names": ["floor", "flor"]}}))
    res = actor.render(job.items()[0])
    assert not res["ok"] and res["retry"] is False and "\n" not in res["error"]
    assert "entry 0: worlds: materials: no material is named 'flor'" in res["error"], res["error"]


@pytest.mark.parametrize(("argv", "worlds", "message"), [
    (["--worlds", "w.json"], None, "--worlds gives each view of a --cameras batch its world"),
    (["--cameras", "p.json", "--worlds", "none.json"], None, "--worlds none.json: cannot read it"),
    (["--cameras", "p.json", "--worlds", "w.json"], "{", "--worlds w.json: not valid JSON"),
    (["--cameras", "p.json", "--worlds", "w.json", "--time", "1"], {"materials": {}},
     "--worlds poses nodes per view: not with --time"),
    (["--cameras", "p.json", "--worlds", "w.json"], {"nodes": NODES, "poses": "x.npy"},
     "--worlds w.json: poses x.npy: no such file"),
])
def test_render_worlds_option_errors(capsys, monkeypatch: pytest.MonkeyPatch, tmp_path: Path,  # noqa: ANN001
                                     argv: list[str], worlds: object, message: str) -> None:
    """`vkpbr render --cameras --worlds`: the same checks, one line, before any work."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.json").write_text(json.dumps(POSES))
    if worlds is not None:
        (tmp_path / "w.json").write_text(worlds if isinstance(worlds, str) else json.dumps(worlds))
    code = main(["render", *argv, "--out", "out"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and message in err, err
    assert not (tmp_path / "out").exists()
