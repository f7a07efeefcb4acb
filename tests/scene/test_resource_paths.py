# Tests of the path policy (vkpbr.scene.resources, docs/security.md): every file a scene names
# (glTF buffers and images, OBJ mtllib and map_*, .comp5822mesh textures, .vkpbr external
# images) resolves only inside the scene's folder tree by default; anything else is a one-line
# SceneError naming the scene file (buffers, material libraries) or the missing-texture fallback
# with its one summary line (images). Only regular files are opened (a FIFO never blocks, a
# device is never read), at most the bytes the file declares are read, allow_outside_paths /
# --allow-outside-paths lifts the folder rule, and OS errors name the user's file.

from __future__ import annotations

import argparse
import errno
import json
import logging
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image as PILImage

from vkpbr.app.cli import main
from vkpbr.app.common import load_scene_arg
from vkpbr.bake.bake import bake_file
from vkpbr.errors import SceneError
from vkpbr.scene.comp5822 import read_comp5822mesh, write_comp5822mesh
from vkpbr.scene.loader import load_scene
from vkpbr.scene.resources import ResourceRefused, read_resource, resolve_resource
from vkpbr.scene.textures import decode_images

TRI = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
HINT = "pass --allow-outside-paths (allow_outside_paths=True) to read it"
TAIL = "rendering with default values (pass strict=True / --strict to make this an error)"
COLOUR = (9, 99, 199)


def write_gltf(path: Path, buffer_uri: str, image_uris: tuple[str, ...] = (),
               byte_length: int = TRI.nbytes) -> Path:
    """A one-triangle glTF whose positions are buffer 0 at `buffer_uri` (byteLength
    `byte_length`, the triangle's 36 bytes by default) and whose material uses `image_uris`."""
    slots = ["baseColorTexture", "normalTexture", "emissiveTexture"]
    material: dict = {"pbrMetallicRoughness": {}}
    for k in range(len(image_uris)):
        if k == 0:
            material["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
        else:
            material[slots[k]] = {"index": k}
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": byte_length, "uri": buffer_uri}],
        "bufferViews": [{"buffer": 0, "byteLength": TRI.nbytes}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "images": [{"uri": u} for u in image_uris],
        "textures": [{"source": k} for k in range(len(image_uris))],
        "materials": [material],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}],
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc))
    return path


@pytest.fixture
def tree(tmp_path: Path) -> tuple[Path, Path]:
    """(scene folder, a folder beside it) each holding tri.bin (the triangle) and t.png."""
    scene, outside = tmp_path / "scene", tmp_path / "outside"
    for folder in (scene, outside, scene / "sub"):
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "tri.bin").write_bytes(TRI.tobytes())
        PILImage.new("RGB", (4, 4), COLOUR).save(folder / "t.png")
    return scene, outside


def warnings_of(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records
            if r.name.startswith("vkpbr") and r.levelno >= logging.WARNING]


def one_line_refusal(exc: pytest.ExceptionInfo, scene: Path, reference: str) -> str:
    text = str(exc.value)
    assert "\n" not in text and text.startswith(f"{scene}: ") and reference in text
    return text


# -- glTF buffers -----------------------------------------------------------------------------

@pytest.mark.parametrize(("uri", "shown"), [
    ("../outside/tri.bin", "../outside/tri.bin"),
    ("%2e%2e/outside/tri.bin", "../outside/tri.bin"),
    ("%2E%2E%2Foutside%2Ftri.bin", "../outside/tri.bin"),
    ("sub/../../outside/tri.bin", "sub/../../outside/tri.bin"),
    ("ABSOLUTE", "ABSOLUTE"),
])
def test_gltf_buffer_outside_is_refused(tree: tuple[Path, Path], uri: str, shown: str) -> None:
    scene, outside = tree
    uri = uri.replace("ABSOLUTE", str(outside / "tri.bin"))
    shown = shown.replace("ABSOLUTE", str(outside / "tri.bin"))
    path = write_gltf(scene / "t.gltf", uri)
    with pytest.raises(ResourceRefused) as exc:
        load_scene(path)
    assert str(exc.value) == (f"{path}: buffer 0 refers to {shown} outside the scene's folder; "
                              f"{HINT}")
    loaded = load_scene(path, allow_outside_paths=True)  # the flag lifts it: the same triangle
    np.testing.assert_array_equal(loaded.meshes[0].positions, TRI)


def test_gltf_buffer_etc_passwd_is_refused(tree: tuple[Path, Path]) -> None:
    path = write_gltf(tree[0] / "t.gltf", "/etc/passwd")
    with pytest.raises(SceneError) as exc:
        load_scene(path)
    assert one_line_refusal(exc, path, "/etc/passwd").endswith(HINT)


@pytest.mark.parametrize("uri", ["tri.bin", "sub/tri.bin", "sub/../tri.bin", "%73ub/tri.bin",
                                 "./sub/./tri.bin"])
def test_gltf_buffer_inside_loads(tree: tuple[Path, Path], uri: str) -> None:
    scene = load_scene(write_gltf(tree[0] / "t.gltf", uri))
    np.testing.assert_array_equal(scene.meshes[0].positions, TRI)


def test_symlinks_leading_out_are_refused(tree: tuple[Path, Path]) -> None:
    scene, outside = tree
    (scene / "link.bin").symlink_to(outside / "tri.bin")
    (scene / "linkdir").symlink_to(outside, target_is_directory=True)
    for uri in ("link.bin", "linkdir/tri.bin"):
        path = write_gltf(scene / "t.gltf", uri)
        with pytest.raises(ResourceRefused) as exc:
            load_scene(path)
        assert str(exc.value) == (f"{path}: buffer 0 refers to {uri}, which resolves outside "
                                  f"the scene's folder; {HINT}")
        np.testing.assert_array_equal(
            load_scene(path, allow_outside_paths=True).meshes[0].positions, TRI)
    # A symlink that stays inside the tree is fine.
    (scene / "inner.bin").symlink_to(scene / "sub" / "tri.bin")
    load_scene(write_gltf(scene / "t.gltf", "inner.bin"))


def test_scene_reached_through_a_symlinked_folder(tree: tuple[Path, Path], tmp_path: Path) -> None:
    """The tree is the scene's folder after resolving symlinks: a scene opened through a
    symlinked folder still reads its own files."""
    write_gltf(tree[0] / "t.gltf", "sub/tri.bin")
    (tmp_path / "alias").symlink_to(tree[0], target_is_directory=True)
    load_scene(tmp_path / "alias" / "t.gltf")


@pytest.mark.timeout(20)
def test_fifo_buffer_and_image_never_block(tree: tuple[Path, Path],
                                           caplog: pytest.LogCaptureFixture) -> None:
    scene = tree[0]
    os.mkfifo(scene / "fifo.bin")
    os.mkfifo(scene / "fifo.png")
    path = write_gltf(scene / "t.gltf", "fifo.bin")
    for allow in (False, True):  # the flag never lifts the regular-file rule
        with pytest.raises(ResourceRefused) as exc:
            load_scene(path, allow_outside_paths=allow)
        assert str(exc.value) == (f"{path}: buffer 0 fifo.bin is not a regular file; vkpbr "
                                  "reads only regular files")
    path = write_gltf(scene / "t.gltf", "tri.bin", ("fifo.png", "t.png"))
    loaded = load_scene(path)
    assert warnings_of(caplog) == [
        f"1 of 2 textures of {path} not regular files (first: fifo.png); {TAIL}"]
    pixels = decode_images(loaded)
    assert pixels[0] is None and pixels[1][0, 0].tolist() == [*COLOUR, 255]
    with pytest.raises(SceneError, match=r"t.gltf: 1 of 2 textures not regular files \(first: "
                                         r"fifo.png\)$"):
        load_scene(path, strict=True)
    # read_resource itself refuses a FIFO (a file swapped for one after the load), at once.
    with pytest.raises(OSError, match="not a regular file"):
        read_resource(scene / "fifo.png")
    # And so does load_scene for the scene file itself.
    os.mkfifo(scene / "pipe.gltf")
    with pytest.raises(SceneError, match=r"pipe.gltf: is not a regular file"):
        load_scene(scene / "pipe.gltf")


@pytest.mark.timeout(20)
def test_dev_zero_as_buffer_and_image(tree: tuple[Path, Path],
                                      caplog: pytest.LogCaptureFixture) -> None:
    path = write_gltf(tree[0] / "t.gltf", "/dev/zero")
    with pytest.raises(ResourceRefused, match="outside the scene's folder"):
        load_scene(path)
    with pytest.raises(ResourceRefused, match="/dev/zero is not a regular file"):
        load_scene(path, allow_outside_paths=True)  # a device is never opened
    path = write_gltf(tree[0] / "t.gltf", "tri.bin", ("/dev/zero",))
    loaded = load_scene(path, allow_outside_paths=True)
    assert warnings_of(caplog) == [
        f"1 of 1 textures of {path} not regular files (first: /dev/zero); {TAIL}"]
    assert decode_images(loaded) == [None]


@pytest.mark.timeout(20)
def test_buffer_reads_only_byte_length(tree: tuple[Path, Path]) -> None:
    """A 4 GiB (sparse) file named as a 36-byte buffer: 36 bytes are read, not 4 GiB."""
    huge = tree[0] / "huge.bin"
    with open(huge, "wb") as f:
        f.write(TRI.tobytes())
        f.truncate(4 << 30)
    scene = load_scene(write_gltf(tree[0] / "t.gltf", "huge.bin"))
    np.testing.assert_array_equal(scene.meshes[0].positions, TRI)
    assert read_resource(huge, 36) == TRI.tobytes()
    assert len(read_resource(huge, 1000)) == 1000
    # A file shorter than byteLength is an error naming the scene file.
    path = write_gltf(tree[0] / "t.gltf", "tri.bin", byte_length=1000)
    with pytest.raises(SceneError, match=r"t.gltf: buffer 0 truncated: 36 bytes, byteLength "
                                         "says 1000$"):
        load_scene(path)
    with pytest.raises(OSError, match="shorter than declared"):
        read_resource(tree[0] / "tri.bin", 1000, exact=True)


# -- glTF images --------------------------------------------------------------------------------

def test_gltf_images_outside_are_missing_textures(tree: tuple[Path, Path],
                                                  caplog: pytest.LogCaptureFixture) -> None:
    scene, outside = tree
    uris = ("../outside/t.png", "t.png", "%2e%2e%2foutside/t.png", "/etc/passwd", "gone.png")
    path = write_gltf(scene / "t.gltf", "tri.bin", uris[:3])
    loaded = load_scene(path)
    assert [img.refused for img in loaded.images] == [
        "outside the scene's folder", None, "outside the scene's folder"]
    assert warnings_of(caplog) == [
        f"2 of 3 textures of {path} outside the scene's folder (first: ../outside/t.png; pass "
        f"--allow-outside-paths (allow_outside_paths=True) to read them); {TAIL}"]
    pixels = decode_images(loaded)
    assert pixels[0] is None and pixels[2] is None and pixels[1] is not None
    # The flag reads them: the same pixels as the file inside.
    loaded = load_scene(path, allow_outside_paths=True)
    assert all(p[0, 0].tolist() == [*COLOUR, 255] for p in decode_images(loaded))
    # Both kinds at once: still one line, each kind counted, and strict names the scene.
    caplog.clear()
    path = write_gltf(scene / "t.gltf", "tri.bin", (uris[4], uris[3], uris[1]))
    load_scene(path)
    assert warnings_of(caplog) == [
        f"1 of 3 textures not found next to {path} (first: gone.png), 1 of 3 textures of {path} "
        "outside the scene's folder (first: /etc/passwd; pass --allow-outside-paths "
        f"(allow_outside_paths=True) to read them); {TAIL}"]
    with pytest.raises(SceneError) as exc:
        load_scene(path, strict=True)
    assert str(exc.value) == (
        f"{path}: 1 of 3 textures not found (first: gone.png), 1 of 3 textures outside the "
        "scene's folder (first: /etc/passwd; pass --allow-outside-paths "
        "(allow_outside_paths=True) to read them)")


def test_refused_image_is_never_opened(tree: tuple[Path, Path],
                                       monkeypatch: pytest.MonkeyPatch) -> None:
    path = write_gltf(tree[0] / "t.gltf", "tri.bin", ("../outside/t.png",))
    loaded = load_scene(path)
    opened = []
    real_open = os.open
    monkeypatch.setattr(os, "open", lambda p, *a, **k: opened.append(p) or real_open(p, *a, **k))
    assert decode_images(loaded) == [None] and opened == []


# -- OS errors ----------------------------------------------------------------------------------

def test_name_too_long_is_a_missing_texture(tree: tuple[Path, Path],
                                            caplog: pytest.LogCaptureFixture) -> None:
    long = "a" * 297 + ".png"  # 301 characters: ENAMETOOLONG on Linux (NAME_MAX 255)
    path = write_gltf(tree[0] / "t.gltf", "tri.bin", (long, "t.png"))
    loaded = load_scene(path)
    assert warnings_of(caplog) == [
        f"1 of 2 textures not found next to {path} (first: {long}); {TAIL}"]
    pixels = decode_images(loaded)
    assert pixels[0] is None and pixels[1] is not None
    with pytest.raises(SceneError, match=r"t.gltf: 1 of 2 textures not found \(first: a+\.png\)$"):
        load_scene(path, strict=True)
    # As a buffer it is an error, naming the scene file and the buffer, saying what to do.
    path = write_gltf(tree[0] / "t.gltf", long)
    with pytest.raises(SceneError) as exc:
        load_scene(path)
    assert str(exc.value) == (f"{path}: buffer 0 {long}: cannot read (File name too long); "
                              "check that the file exists next to the scene and is readable")


def test_folder_named_as_buffer(tree: tuple[Path, Path]) -> None:
    path = write_gltf(tree[0] / "t.gltf", "sub")
    with pytest.raises(SceneError, match=r"t.gltf: buffer 0 sub is not a regular file"):
        load_scene(path)


def test_resolve_resource_rejects_nul(tree: tuple[Path, Path]) -> None:
    with pytest.raises(ResourceRefused, match="not a valid file name"):
        resolve_resource(tree[0] / "t.gltf", "a\0b.png", allow_outside=True)


# -- OBJ / MTL ----------------------------------------------------------------------------------

def write_obj(folder: Path, mtllib: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "m.obj"
    path.write_text(f"mtllib {mtllib}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                    "usemtl red\nf 1/1 2/2 3/3\n")
    return path


def test_obj_mtllib_outside_is_refused(tree: tuple[Path, Path]) -> None:
    scene, outside = tree
    (outside / "m.mtl").write_text("newmtl red\nKd 1 0 0\n")
    path = write_obj(scene, "../outside/m.mtl")
    with pytest.raises(ResourceRefused) as exc:
        load_scene(path)
    assert str(exc.value) == (f"{path}: material library refers to ../outside/m.mtl outside "
                              f"the scene's folder; {HINT}")
    loaded = load_scene(path, allow_outside_paths=True)
    assert loaded.materials[0].base_color_factor == (1.0, 0.0, 0.0, 1.0)


def test_obj_map_outside_is_a_missing_texture(tree: tuple[Path, Path],
                                              caplog: pytest.LogCaptureFixture) -> None:
    scene, _ = tree
    (scene / "mtl").mkdir()
    # Maps are relative to the MTL's folder; ../t.png from mtl/ is still inside the OBJ's tree.
    (scene / "mtl" / "m.mtl").write_text(
        "newmtl red\nmap_Kd /etc/hostname\nmap_Ke ../t.png\nnorm ../../outside/t.png\n")
    path = write_obj(scene, "mtl/m.mtl")
    loaded = load_scene(path)
    assert [img.refused for img in loaded.images] == [
        "outside the scene's folder", None, "outside the scene's folder"]
    assert warnings_of(caplog) == [
        f"2 of 3 textures of {path} outside the scene's folder (first: /etc/hostname; pass "
        f"--allow-outside-paths (allow_outside_paths=True) to read them); {TAIL}"]
    pixels = decode_images(loaded)
    assert pixels[0] is None and pixels[2] is None and pixels[1][0, 0].tolist() == [*COLOUR, 255]
    loaded = load_scene(path, allow_outside_paths=True)
    assert [img.refused for img in loaded.images] == [None, None, None]
    assert decode_images(loaded)[2][0, 0].tolist() == [*COLOUR, 255]


# -- .comp5822mesh and .vkpbr ---------------------------------------------------------------------

def test_comp5822mesh_texture_outside(tree: tuple[Path, Path],
                                      caplog: pytest.LogCaptureFixture) -> None:
    scene, outside = tree
    (outside / "m.mtl").write_text("newmtl red\nmap_Kd t.png\n")
    source = load_scene(write_obj(outside, "m.mtl"))
    mesh = scene / "m.comp5822mesh"
    write_comp5822mesh(source, mesh)  # stores ../outside/t.png
    assert read_comp5822mesh(mesh).images[0].refused == "outside the scene's folder"
    load_scene(mesh)
    assert warnings_of(caplog) == [
        f"1 of 1 textures of {mesh} outside the scene's folder (first: ../outside/t.png; pass "
        f"--allow-outside-paths (allow_outside_paths=True) to read them); {TAIL}"]
    loaded = load_scene(mesh, allow_outside_paths=True)
    assert decode_images(loaded)[0][0, 0].tolist() == [*COLOUR, 255]


def test_vkpbr_external_image_outside(tree: tuple[Path, Path],
                                      caplog: pytest.LogCaptureFixture) -> None:
    scene, outside = tree
    src = write_gltf(outside / "s.gltf", "tri.bin", ("t.png",))
    out = scene / "s.vkpbr"
    # Only an external-references bake keeps a path, and one outside its folder only when
    # asked to (a plain bake stores the texture inside: test_bake_embeds_source_bytes).
    with pytest.raises(SceneError, match="lies outside"):
        bake_file(src, out, progress=False, textures="external")
    bake_file(src, out, progress=False, textures="external", allow_outside_paths=True)
    caplog.clear()
    assert load_scene(out).images[0].refused == "outside the scene's folder"
    assert len(warnings_of(caplog)) == 1 and "outside the scene's folder" in warnings_of(caplog)[0]
    loaded = load_scene(out, allow_outside_paths=True)
    assert decode_images(loaded)[0][0, 0].tolist() == [*COLOUR, 255]


def test_bake_refuses_outside_buffer_and_flag_lifts_it(tree: tuple[Path, Path]) -> None:
    scene, _ = tree
    src = write_gltf(scene / "t.gltf", "../outside/tri.bin")
    with pytest.raises(ResourceRefused, match="outside the scene's folder"):
        bake_file(src, scene / "t.vkpbr", progress=False)
    assert not (scene / "t.vkpbr").exists()
    bake_file(src, scene / "t.vkpbr", progress=False, allow_outside_paths=True)
    np.testing.assert_array_equal(load_scene(scene / "t.vkpbr").meshes[0].positions, TRI)


def test_cache_bake_reads_textures_beside_the_source(tree: tuple[Path, Path], tmp_path: Path,
                                                     caplog: pytest.LogCaptureFixture) -> None:
    """--cache writes the bake into the cache folder; its textures lie beside the source,
    which is the tree the policy checks them against (not the cache's folder)."""
    src = write_gltf(tree[0] / "t.gltf", "tri.bin", ("t.png", "../outside/t.png"))
    args = argparse.Namespace(scene=str(src), cache=str(tmp_path / "cache"), strict=False,
                              allow_outside_paths=False)
    loaded = load_scene_arg(args)
    assert loaded is not None and Path(loaded.source).parent == tmp_path / "cache"
    assert [img.refused for img in loaded.images] == [None, "outside the scene's folder"]
    assert decode_images(loaded)[0][0, 0].tolist() == [*COLOUR, 255]
    args.allow_outside_paths = True
    loaded = load_scene_arg(args)
    assert [img.refused for img in loaded.images] == [None, None]


# -- the command line ---------------------------------------------------------------------------

def test_cli_refusal_is_one_line_and_flag_is_documented(tree: tuple[Path, Path],
                                                        capsys: pytest.CaptureFixture) -> None:
    path = write_gltf(tree[0] / "t.gltf", "%2e%2e/outside/tri.bin")
    for command in (["render", str(path), "--out", str(tree[0] / "o.png")],
                    ["bake", str(path), "--out", str(tree[0] / "o.vkpbr")]):
        assert main(command) == 1
        err = capsys.readouterr().err
        assert err == (f"vkpbr: error: {path}: buffer 0 refers to ../outside/tri.bin outside "
                       f"the scene's folder; {HINT}\n")
    assert main(["bake", str(path), "--out", str(tree[0] / "o.vkpbr"), "--allow-outside-paths",
                 "--no-progress"]) == 0
    capsys.readouterr()
    # A bake that keeps textures outside its folder (asked for) says, in its result line,
    # what loading it will need; a plain bake stores them inside.
    src = write_gltf(tree[1] / "s.gltf", "tri.bin", ("t.png",))
    assert main(["bake", str(src), "--out", str(tree[0] / "s.vkpbr"), "--no-progress",
                 "--textures", "external", "--allow-outside-paths"]) == 0
    assert ("1 texture external (1 outside the .vkpbr's folder: loading it needs "
            "--allow-outside-paths)") in capsys.readouterr().out
    assert main(["bake", str(src), "--out", str(tree[0] / "s.vkpbr"), "--no-progress"]) == 0
    assert "1 texture embedded)" in capsys.readouterr().out
    for command in ("render", "view", "bake"):
        assert main([command, "--help"]) == 0
        assert "--allow-outside-paths" in capsys.readouterr().out


def test_cli_os_error_without_filename_names_the_output(tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch,
                                                        capsys: pytest.CaptureFixture) -> None:
    from vkpbr.app import bake_cmd

    def fail(args: argparse.Namespace) -> int:
        raise OSError(errno.EFBIG, "File too large")

    monkeypatch.setattr(bake_cmd, "run", fail)
    src = write_gltf(tmp_path / "t.gltf", "tri.bin")
    assert main(["bake", str(src), "--out", str(tmp_path / "o.vkpbr")]) == 1
    assert capsys.readouterr().err == (
        f"vkpbr: error: while writing {tmp_path / 'o.vkpbr'}: File too large (the file size "
        "limit (ulimit -f) is too low)\n")


@pytest.mark.timeout(60)
def test_failed_bake_names_the_output_not_its_temporary(tree: tuple[Path, Path]) -> None:
    """Under a 256-byte file-size limit the bake's write fails (EFBIG): the one line names the
    user's --out path, never the temporary file, and no temporary file is left."""
    scene, _ = tree
    src = write_gltf(scene / "t.gltf", "tri.bin")
    out = scene / "o.vkpbr"
    code = ("import resource, sys; resource.setrlimit(resource.RLIMIT_FSIZE, (256, 256)); "
            "from vkpbr.app.cli import main; sys.exit(main(sys.argv[1:]))")
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[2] / "src")}
    proc = subprocess.run([sys.executable, "-c", code, "bake", str(src), "--out", str(out),
                           "--no-progress", "--embed-textures"],
                          capture_output=True, text=True, env=env, timeout=50)
    assert proc.returncode == 1, proc.stderr
    assert proc.stderr == (f"vkpbr: error: {out}: cannot write: File too large (the file size limit "
                           "(ulimit -f) is too low)\n")
    assert not out.exists() and not list(scene.glob(".*.tmp"))


def test_atomic_writer_errors_name_the_target(tmp_path: Path) -> None:
    from vkpbr.atomic import atomic_writer
    from vkpbr.errors import OutputError

    target = tmp_path / "out.bin"
    with pytest.raises(OSError) as exc, atomic_writer(target) as f:
        f.write(b"x")
        raise OSError(errno.ENOSPC, "No space left on device")  # a write error: no filename
    assert exc.value.errno == errno.ENOSPC and exc.value.filename == str(target)
    assert not list(tmp_path.iterdir())
    missing = tmp_path / "no" / "out.bin"  # mkstemp fails: named as the target, not a .tmp
    with pytest.raises(OutputError) as exc, atomic_writer(missing):
        pass
    assert exc.value.filename == str(missing) and exc.value.errno == errno.ENOENT
    assert str(exc.value) == f"{missing}: cannot write: No such file or directory"
    assert isinstance(exc.value, OSError)  # what callers of the OSError days still catch
    other = OSError(errno.EIO, "I/O error", "/some/source")  # another file's error stays its own
    with pytest.raises(OSError) as exc, atomic_writer(target):
        raise other
    assert exc.value is other


def test_unreadable_material_library_names_the_obj(tree: tuple[Path, Path],
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """An OSError reading an MTL (EACCES here, faked: tests may run as root) names the OBJ
    the user asked for, the library, the OS's reason and what to do."""
    import vkpbr.scene.obj as obj

    (tree[0] / "m.mtl").write_text("newmtl red\nKd 1 0 0\n")
    path = write_obj(tree[0], "m.mtl")

    def denied(file: object, *args: object) -> bytes:
        if str(file).endswith(".mtl"):
            raise PermissionError(errno.EACCES, "Permission denied", str(file))
        return read_resource(file, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(obj, "read_resource", denied)
    with pytest.raises(SceneError) as exc:
        load_scene(path)
    assert str(exc.value) == (f"{path}: material library m.mtl: cannot read (Permission "
                              "denied); check that the file exists next to the scene and is "
                              "readable")


def test_nul_in_an_image_name_is_a_refused_texture(tree: tuple[Path, Path],
                                                   caplog: pytest.LogCaptureFixture) -> None:
    path = write_gltf(tree[0] / "t.gltf", "tri.bin", ("a%00b.png", "/x%00y.png"))
    loaded = load_scene(path)
    assert [img.refused for img in loaded.images] == ["not valid file names"] * 2
    assert warnings_of(caplog) == [
        f"2 of 2 textures of {path} not valid file names (first: a\\0b.png); {TAIL}"]
    assert decode_images(loaded) == [None, None]
    with pytest.raises(SceneError, match="not a valid file name"):
        load_scene(write_gltf(tree[0] / "t.gltf", "tri%00.bin"))


def test_a_loads_folder_cache_resolves_as_realpath_does(tmp_path: Path) -> None:
    """ResourcePolicy keeps its folders' realpaths for one load (scene/resources.py `_real`):
    every name resolves exactly as os.path.realpath resolves it, the same policy asked
    again included: linked folders, linked files (in and out), links to links, dangling
    links, `..`, missing names, names that a link in the middle redirects."""
    from vkpbr.scene.resources import ResourcePolicy, _real

    scene_dir, outside = tmp_path / "scene", tmp_path / "outside"
    (scene_dir / "tex" / "deep").mkdir(parents=True)
    outside.mkdir()
    (scene_dir / "tex" / "a.png").write_bytes(b"a")
    (outside / "secret.png").write_bytes(b"s")
    (scene_dir / "linked").symlink_to(scene_dir / "tex", target_is_directory=True)
    (scene_dir / "out").symlink_to(outside, target_is_directory=True)
    (scene_dir / "tex" / "leak.png").symlink_to(outside / "secret.png")
    (scene_dir / "tex" / "chain.png").symlink_to(scene_dir / "tex" / "leak.png")
    (scene_dir / "tex" / "dangling.png").symlink_to(tmp_path / "nowhere.png")
    (scene_dir / "tex" / "up").symlink_to(tmp_path, target_is_directory=True)
    names = ["tex/a.png", "linked/a.png", "out/secret.png", "tex/leak.png", "tex/chain.png",
             "tex/dangling.png", "tex/missing.png", "tex/deep/../a.png", "tex/..", "..",
             "tex/up/outside/secret.png", "linked/deep/../../out/secret.png", ".", "tex/",
             "linked/leak.png", "../outside/secret.png"]
    policy = ResourcePolicy(scene_dir / "scene.gltf")
    for _ in range(2):  # the second time from the cache
        for name in names:
            path = scene_dir / name
            assert _real(path, policy.folders) == Path(os.path.realpath(path)), name
    refused = set()
    for name in names:
        try:
            policy.resolve(name)
        except ResourceRefused:
            refused.add(name)
    # refused: what lies outside, and folders (not regular files); missing names resolve
    outside_names = {n for n in names if not Path(os.path.realpath(scene_dir / n)).is_relative_to(
        os.path.realpath(scene_dir))}
    folder_names = {n for n in names if (scene_dir / n).is_dir()}
    assert refused == outside_names | folder_names
