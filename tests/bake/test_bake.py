# Tests of the bake stage: determinism, robustness to degenerate input, deduplication,
# the report, bake_file / cached_bake and the `bake` subcommand.
from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np
import pytest

from vkpbr.app import bake_cmd
from vkpbr.bake.bake import KEYS_FILE, bake_file, bake_report, bake_scene, cached_bake
from vkpbr.scene.baked_file import TANGENTS_FROM_FILE, read_baked, write_baked
from vkpbr.scene.types import Material, Mesh, Node, Scene


def grid(n: int) -> Mesh:
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    u, v = i.ravel() / (n - 1), j.ravel() / (n - 1)
    p = np.stack([u, 0.2 * np.sin(3 * u) + 0.1 * np.cos(5 * v), v], 1).astype(np.float32)
    normals = np.tile(np.float32([0, 1, 0]), (n * n, 1))
    a = (i[:-1, :-1] * n + j[:-1, :-1]).ravel()
    idx = np.stack([a, a + n, a + 1, a + 1, a + n, a + n + 1], 1).ravel().astype(np.uint32)
    return Mesh("grid", p, idx, normals, np.stack([u, v], 1).astype(np.float32), material=0)


def scene_of(*meshes: Mesh) -> Scene:
    return Scene("t", meshes=list(meshes), materials=[Material()],
                 nodes=[Node(i) for i in range(len(meshes))])


def test_bake_is_deterministic(tmp_path: Path) -> None:
    scene = scene_of(grid(40), Mesh("flat", grid(10).positions, grid(10).indices))
    paths = [tmp_path / "a.vkpbr", tmp_path / "b.vkpbr"]
    for p in paths:
        write_baked(p, bake_scene(scene))
    assert paths[0].read_bytes() == paths[1].read_bytes()


def test_degenerate_input_gives_finite_frames() -> None:
    rng = np.random.default_rng(0)
    p = rng.normal(size=(12, 3)).astype(np.float32)
    p[1] = p[2] = p[0]  # zero-area triangle
    p[5] = np.nan
    normals = rng.normal(size=(12, 3)).astype(np.float32)
    normals[3] = 0.0
    normals[4] = np.inf
    idx = np.array([0, 1, 2, 3, 4, 6, 4, 5, 6, 7, 8, 9, 9, 10, 99, 0, 0, 0, 9, 10, 11],
                   np.uint32)
    meshes = [Mesh("a", p, idx, normals), Mesh("b", p, idx, None, np.zeros((12, 2), np.float32)),
              Mesh("c", p, idx, normals, None, tangents=np.full((12, 4), np.nan, np.float32)),
              Mesh("empty", p[:0], idx[:0])]
    baked = bake_scene(scene_of(*meshes))
    for name, arr in baked.streams.items():
        if arr.dtype.kind == "f":
            assert np.isfinite(arr).all(), name
    t = baked.streams["tangents"]
    np.testing.assert_allclose(np.linalg.norm(t[:, :3], axis=1), 1.0, atol=1e-5)
    np.testing.assert_allclose(np.einsum("ij,ij->i", t[:, :3], baked.streams["normals"]), 0.0,
                               atol=1e-5)
    # the triangle with index 99 and the NaN one are gone; zero-area distinct ones stay
    for k in range(len(meshes)):
        assert baked.mesh_stream(k, "indices").max(initial=0) < max(
            int(baked.mesh_table[k]["vertex_count"]), 1)
    report = bake_report(scene_of(*meshes), baked)
    assert report["tbn_error_deg"]["max"] <= 0.25


def test_duplicates_merge_and_file_tangents_are_kept() -> None:
    g = grid(6)
    corners = g.indices  # unindexed copy: every corner its own vertex, -0.0 mixed in
    pos = g.positions[corners].copy()
    pos[pos == 0.0] = -0.0
    tangents = np.tile(np.float32([2, 0, 0, -1]), (len(corners), 1))
    m = Mesh("unindexed", pos, np.arange(len(corners), dtype=np.uint32), g.normals[corners],
             g.texcoords[corners], tangents=tangents)
    baked = bake_scene(scene_of(m))
    assert len(baked.streams["positions"]) == 36
    assert baked.mesh_table[0]["flags"] & TANGENTS_FROM_FILE
    t = baked.streams["tangents"]
    assert (t[:, 3] == -1).all()
    np.testing.assert_allclose(np.linalg.norm(t[:, :3], axis=1), 1.0, atol=1e-6)
    assert (np.sign(baked.streams["qtangents"][:, 3]) == -1).all()


def test_report_numbers() -> None:
    scene = scene_of(grid(50))
    baked = bake_scene(scene)
    r = bake_report(scene, baked)
    assert r["bytes_per_vertex"] == {"vectors": 48, "quat": 36, "packed": 24}
    assert r["vertices"] == 2500 and r["triangles"] == 2 * 49 * 49
    assert 0.0 < r["tbn_error_deg"]["mean"] <= r["tbn_error_deg"]["p99"] <= 0.25
    assert r["tbn_error_deg"]["max"] <= 0.25 and r["quat_error_deg"]["max"] < 0.01
    assert r["seconds"] > 0
    json.dumps(r)


@pytest.fixture
def fake_loader(monkeypatch: pytest.MonkeyPatch) -> None:
    """A stand-in for load_scene so these tests do not depend on the importer."""
    monkeypatch.setattr("vkpbr.bake.bake.load_scene", lambda path, strict=False, **_: scene_of(grid(8)))


def test_bake_file_and_cache(tmp_path: Path, fake_loader: None) -> None:
    src = tmp_path / "scene.gltf"
    src.write_text('{"asset": {"version": "2.0"}, "buffers": [{"uri": "scene.bin"}]}')
    (tmp_path / "scene.bin").write_bytes(b"1234")
    report = bake_file(src, tmp_path / "out.vkpbr", progress=False)
    assert read_baked(tmp_path / "out.vkpbr").source_files == ["scene.gltf", "scene.bin"]
    assert report["file_bytes"] == (tmp_path / "out.vkpbr").stat().st_size
    cache = tmp_path / "cache"
    first = cached_bake(src, cache)
    mtime = first.stat().st_mtime_ns
    assert cached_bake(src, cache) == first and first.stat().st_mtime_ns == mtime
    (tmp_path / "scene.bin").write_bytes(b"5678")  # a dependency changed: new key, new file
    assert cached_bake(src, cache) != first
    first.write_bytes(first.read_bytes()[:100])  # a broken cache entry is baked again


def test_cache_keys_are_remembered_by_file_stats(tmp_path: Path, fake_loader: None) -> None:
    """A source whose files kept their sizes and times is not hashed again (KEYS_FILE): the
    proof is a change the index cannot see (same size, time put back), which it misses; a
    time changed, or a file written within 2 s of the record, is hashed again."""
    src, dep = tmp_path / "scene.gltf", tmp_path / "scene.bin"
    src.write_text('{"asset": {"version": "2.0"}, "buffers": [{"uri": "scene.bin"}]}')
    dep.write_bytes(b"1234")
    old = time.time() - 3600
    for f in (src, dep):
        os.utime(f, (old, old))
    cache = tmp_path / "cache"
    first = cached_bake(src, cache)
    keys = json.loads((cache / KEYS_FILE).read_text())
    assert [rec["out"] for rec in keys.values()] == [str(first)]
    dep.write_bytes(b"5678")
    os.utime(dep, (old, old))  # unseen by size and time: the remembered bake
    assert cached_bake(src, cache) == first
    os.utime(dep, (old + 1, old + 1))  # its time changed: hashed, a new key
    second = cached_bake(src, cache)
    assert second != first and read_baked(second).source_key != read_baked(first).source_key
    now = time.time_ns()  # a file changed within a clock tick of its record keeps its stats
    dep.write_bytes(b"9abc")
    os.utime(dep, ns=(now, now))
    third = cached_bake(src, cache)
    dep.write_bytes(b"defg")
    os.utime(dep, ns=(now, now))  # same size, same time: only its recency says to hash it
    assert cached_bake(src, cache) not in (first, second, third)


def test_bake_command(tmp_path: Path, fake_loader: None, capsys: pytest.CaptureFixture) -> None:
    parser = argparse.ArgumentParser()
    bake_cmd.add_parser(parser.add_subparsers())
    src = tmp_path / "s.obj"
    src.write_text("v 0 0 0\n")
    args = parser.parse_args(["bake", str(src), "--out", str(tmp_path / "s.vkpbr"), "--report"])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "wrote" in out and "packed frame error" in out
    args = parser.parse_args(["bake", str(src), "-o", str(tmp_path / "s.vkpbr"), "--json"])
    assert bake_cmd.run(args) == 0
    assert json.loads(capsys.readouterr().out)["bytes_per_vertex"]["packed"] == 24


def test_embedded_textures_have_full_mip_chains(tmp_path: Path) -> None:
    from vkpbr.bake.bake import embed_images
    from vkpbr.scene.types import Image, TextureRef

    scene = scene_of(grid(4))
    scene.materials = [Material(base_color_texture=TextureRef(0))]
    scene.images = [Image("gen", pixels=np.full((5, 3, 4), 200, np.uint8))]
    baked = bake_scene(scene)
    embed_images(scene, baked)
    assert [lv.shape[:2] for lv in baked.images[0].levels] == [(5, 3), (2, 1), (1, 1)]
    assert (baked.images[0].levels[-1] == 200).all()  # sRGB round trip of a constant
    write_baked(tmp_path / "e.vkpbr", baked)
    assert len(read_baked(tmp_path / "e.vkpbr").images[0].levels) == 3


def test_bake_out_is_checked_before_baking(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from vkpbr.errors import UsageError

    def no_bake(*args: object, **kwargs: object) -> None:
        raise AssertionError("bake_file ran before --out was checked")

    monkeypatch.setattr("vkpbr.bake.bake.bake_file", no_bake)
    parser = argparse.ArgumentParser()
    bake_cmd.add_parser(parser.add_subparsers())
    src = tmp_path / "s.obj"  # never read: every case fails first
    (tmp_path / "dir.vkpbr").mkdir()
    cases = {
        "nowhere/s.vkpbr": "folder .*nowhere does not exist",
        "s.glb": "must be a .vkpbr file \\(got '.glb'\\)",
        "s": "must be a .vkpbr file \\(got 'no extension'\\)",
        "dir.vkpbr": "is a folder",
    }
    for out, message in cases.items():
        args = parser.parse_args(["bake", str(src), "--out", str(tmp_path / out)])
        with pytest.raises(UsageError, match=message) as info:
            bake_cmd.run(args)
        assert "\n" not in str(info.value) and str(info.value).startswith(f"--out {tmp_path / out}")
    assert bake_cmd.check_out(tmp_path / "ok.VKPBR") == tmp_path / "ok.VKPBR"  # case-insensitive


def test_bake_help_has_description_and_examples() -> None:
    parser = argparse.ArgumentParser(prog="vkpbr")
    bake_cmd.add_parser(parser.add_subparsers())
    (sub,) = parser._subparsers._group_actions[0].choices.values()  # noqa: SLF001
    text = sub.format_help()
    assert "examples:\n  vkpbr bake " in text and text.count("\n  vkpbr bake ") == 3
    assert "--embed-textures" in text and "--strict" in text and "docs/baked-format.md" in text


def test_an_animated_scene_bakes_its_rest_pose_with_one_warning(tmp_path: Path, assets: Path) -> None:
    """The baked format stores no animation: the bake says so in one line (docs/animation.md)."""
    import warnings

    source = assets / "CesiumMan" / "glTF" / "CesiumMan.gltf"
    if not source.is_file():
        pytest.skip(f"{source} not in the assets")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        bake_file(source, tmp_path / "man.vkpbr", progress=False)
    lines = [str(w.message) for w in caught if "not baked" in str(w.message)]
    assert len(lines) == 1 and "\n" not in lines[0] and "CesiumMan.gltf" in lines[0]
    assert "animations (1), skins (1, 1 skinned meshes)" in lines[0]
