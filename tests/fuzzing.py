"""vkpbr's fuzz suite (issue 11): seeded mutations of every input format, run through
`load_scene` as a user's file would be. Each input ends in one of:

  loaded   the scene loaded (a mutation can leave a file valid);
  clean    vkpbr's own error (VkpbrError) in one line naming the user's file;
  unclean  anything else: another exception, a multi-line message, or a message that does
           not name the file. (A hang is caught by the quick tier's test timeout.)

The quick tier (tests/fuzz/test_fuzz_quick.py) runs a few hundred inputs in CI; the long tier
is `scripts/fuzz.sh N` (this file as a script), which prints one table per format.

Formats and mutations: glTF JSON (types, missing keys, out-of-range indices, counts, offsets,
node cycles), glTF and GLB bytes, OBJ and MTL bytes, .comp5822mesh bytes, .vkpbr bytes (the
checksums catch them) and .vkpbr scene JSON re-packed with fresh checksums (intact files with
invalid contents), texture bytes, bombs (textures declaring 12000x12000 pixels, accessors
declaring 2^31 elements), and path tricks: a glTF buffer or image, an OBJ mtllib, an MTL map,
a .comp5822mesh texture or a .vkpbr external image named as `../` chains, absolute paths,
percent-encoded `%2e%2e/`, `file:` URIs, symlinks leading out, a FIFO, /dev/zero, a folder,
over-long names. An audit hook (PathGuard) makes any open of a file outside the scene's folder
(without --allow-outside-paths) or of a non-regular file an unclean outcome, and stops it.
"""

from __future__ import annotations

import base64
import collections
import copy
import json
import os
import random
import stat
import struct
import sys
import time
import warnings
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

SEED = 1111
# The rows of the scene formats' part of the table (Corpus.formats' keys)
FORMAT_NAMES = ("gltf json", "gltf bytes", "glb bytes", "obj bytes", "mtl bytes",
                "comp5822mesh bytes", "vkpbr bytes", "vkpbr json (checksums fixed)",
                "texture bytes and bombs", "count bombs", "path tricks",
                "codec payloads (Draco, meshopt, KTX2, WebP)")
N_FORMATS = len(FORMAT_NAMES)

_EVIL = [1e30, 1e308, -1, 2**31, 2**32, 2**64, -(2**40), 0, 7, float("nan"), float("inf"), "x",
         "../../etc/passwd", None, [], {}, True, 3.5, [1, 2], [1e30] * 3, {"a": 1}]  # fmt: skip


# --- mutators -------------------------------------------------------------------------------
def _paths(value: object, prefix: tuple = ()) -> Iterator[tuple]:
    yield prefix
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _paths(v, (*prefix, i))


def mutate_json(doc: dict, rng: random.Random) -> dict:
    """1-3 structural edits: a value replaced by an evil one, a key deleted, an index pushed
    out of range, a list emptied or repeated, a node made its own ancestor."""
    doc = json.loads(json.dumps(doc))
    for _ in range(rng.randint(1, 3)):
        paths = [p for p in _paths(doc) if p]
        if not paths:  # an earlier edit deleted everything
            break
        path = rng.choice(paths)
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        key, r = path[-1], rng.random()
        value = parent[key]
        if isinstance(parent, dict) and r < 0.2:
            del parent[key]
        elif isinstance(value, int) and not isinstance(value, bool) and r < 0.45:
            parent[key] = value + rng.choice([1, 2, 100, 2**31, -value - 1])  # indices, counts
        elif isinstance(value, list) and value and r < 0.55:
            # Copies, not the same objects again: a later edit inside one must not reach the
            # others (or, through a shared evil value, make a Python cycle json cannot write).
            parent[key] = [] if rng.random() < 0.5 else [copy.deepcopy(v) for v in value * rng.randint(2, 5)]
        elif key == "children" and r < 0.65 and isinstance(value, list):
            parent[key] = [0]  # a cycle through the root node
        else:
            parent[key] = copy.deepcopy(rng.choice(_EVIL))
    return doc


def mutate_bytes(data: bytes, rng: random.Random) -> bytes:
    data = bytearray(data)
    kind = rng.random()
    if kind < 0.2:
        return bytes(data[: rng.randrange(max(len(data), 1))])
    if kind < 0.3:
        at = rng.randrange(max(len(data), 1))
        return bytes(data[:at] + bytes(rng.randrange(256) for _ in range(rng.randint(1, 8))) + data[at:])
    if not data:  # nothing to flip (an earlier edit emptied it): a few bytes instead
        return bytes(rng.randrange(256) for _ in range(rng.randint(1, 8)))
    for _ in range(rng.randint(1, 6)):
        at = rng.randrange(len(data))
        data[at] = rng.choice([0, 0xFF, 0x7F, 0x80, rng.randrange(256), data[at] ^ (1 << rng.randrange(8))])
    return bytes(data)


def png_header_only(width: int, height: int) -> bytes:
    """A PNG that declares width x height RGBA pixels and holds almost nothing (a bomb)."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64))
            + chunk(b"IEND", b""))


# --- seed inputs ----------------------------------------------------------------------------
def _png(rgba: tuple[int, int, int, int] = (200, 120, 60, 255)) -> bytes:
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.new("RGBA", (8, 8), rgba).save(buf, format="PNG")
    return buf.getvalue()


def _gltf_doc(buffer_uri: str, image_uri: str) -> dict:
    """A two-node glTF: one textured triangle pair with normals and UVs, a camera, a light."""
    return {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "children": [1], "translation": [0, 0, 0]},
                  {"mesh": 0, "camera": 0, "scale": [1, 2, 1]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 3}]}},
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                    "indices": 3, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                "metallicFactor": 0.2}, "doubleSided": True}],
        "textures": [{"source": 0, "sampler": 0}], "samplers": [{"magFilter": 9729, "wrapS": 33071}],
        "images": [{"uri": image_uri}],
        "buffers": [{"uri": buffer_uri, "byteLength": 140}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 96, "byteLength": 32},
                        {"buffer": 0, "byteOffset": 128, "byteLength": 12}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}],
    }


def _gltf_buffer() -> bytes:
    pos = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
    nrm = np.tile(np.array([0, 0, 1], np.float32), (4, 1))
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    idx = np.array([0, 1, 2, 0, 2, 3], np.uint16)
    return pos.tobytes() + nrm.tobytes() + uv.tobytes() + idx.tobytes()


def _glb(doc: dict, binary: bytes) -> bytes:
    doc = json.loads(json.dumps(doc))
    doc["buffers"] = [{"byteLength": len(binary)}]
    doc["images"] = [{"bufferView": 4, "mimeType": "image/png"}]
    png = _png()
    doc["bufferViews"].append({"buffer": 0, "byteOffset": len(binary), "byteLength": len(png)})
    binary = binary + png
    binary += b"\0" * (-len(binary) % 4)
    doc["buffers"][0]["byteLength"] = len(binary)
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = (struct.pack("<I4s", len(text), b"JSON") + text
            + struct.pack("<I4s", len(binary), b"BIN\0") + binary)
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


_OBJ = (b"mtllib f.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
        b"usemtl m\nf 1/1/1 2/2/1 3/3/1\ng two\nusemtl n\nf 1 3 4\nf -1 -2 -3 -4\n")
_MTL = b"newmtl m\nKd 1 0 0\nPm 0.5\nmap_Kd -s 2 2 t.png\nmap_d t.png\nnewmtl n\nPr 0.2\nnorm t.png\n"


class Corpus:
    """Seed files in `folder` and, per format, a function that writes one mutated input and
    returns the path to load (and the file an error should name)."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        f = folder
        (f / "t.png").write_bytes(_png())
        (f / "b.bin").write_bytes(_gltf_buffer())
        self.gltf_doc = _gltf_doc("b.bin", "t.png")
        (f / "s.gltf").write_text(json.dumps(self.gltf_doc))
        self.gltf_bytes = (f / "s.gltf").read_bytes()
        self.glb = _glb(self.gltf_doc, _gltf_buffer())
        inline = dict(self.gltf_doc, buffers=[{
            "uri": "data:application/octet-stream;base64," + base64.b64encode(_gltf_buffer()).decode(),
            "byteLength": 140}])
        self.inline_doc = inline
        (f / "f.obj").write_bytes(_OBJ)
        (f / "f.mtl").write_bytes(_MTL)
        from vkpbr.bake.bake import bake_file
        from vkpbr.scene.baked_file import read_sections
        from vkpbr.scene.comp5822 import write_comp5822mesh
        from vkpbr.scene.loader import load_scene

        write_comp5822mesh(load_scene(f / "s.gltf"), f / "s.comp5822mesh")
        self.comp = (f / "s.comp5822mesh").read_bytes()
        bake_file(f / "s.gltf", f / "s.vkpbr", progress=False)
        self.vkpbr = (f / "s.vkpbr").read_bytes()
        self.sections = read_sections(f / "s.vkpbr")

    def formats(self) -> dict[str, Callable[[random.Random], tuple[Path, str]]]:
        f = self.folder

        def bytes_of(name: str, data: bytes) -> Callable[[random.Random], tuple[Path, str]]:
            def make(rng: random.Random) -> tuple[Path, str]:
                (f / f"m_{name}").write_bytes(mutate_bytes(data, rng))
                return f / f"m_{name}", f"m_{name}"
            return make

        def gltf_json(rng: random.Random) -> tuple[Path, str]:
            doc = mutate_json(self.inline_doc if rng.random() < 0.3 else self.gltf_doc, rng)
            (f / "m.gltf").write_text(json.dumps(doc))
            return f / "m.gltf", "m.gltf"

        def mtl(rng: random.Random) -> tuple[Path, str]:
            (f / "mm.mtl").write_bytes(mutate_bytes(_MTL, rng))
            (f / "mm.obj").write_bytes(_OBJ.replace(b"f.mtl", b"mm.mtl"))
            return f / "mm.obj", "mm."  # an error may name the .obj or the .mtl

        def texture(rng: random.Random) -> tuple[Path, str]:
            png = png_header_only(12000, 12000) if rng.random() < 0.2 else mutate_bytes(_png(), rng)
            (f / "mt.png").write_bytes(png)
            (f / "mt.gltf").write_text(json.dumps(dict(self.gltf_doc, images=[{"uri": "mt.png"}])))
            return f / "mt.gltf", "mt."

        def vkpbr_json(rng: random.Random) -> tuple[Path, str]:
            from vkpbr.scene.baked_file import write_sections

            out = []
            for name, data in self.sections:
                if name == "scene":
                    data = json.dumps(mutate_json(json.loads(data), rng)).encode()
                elif rng.random() < 0.05:
                    data = mutate_bytes(data, rng)
                out.append((name, data))
            write_sections(f / "mj.vkpbr", out)
            return f / "mj.vkpbr", "mj.vkpbr"

        tricks = PathTrickCorpus(f / "pt", self)
        cases = tricks.cases()
        rng_cases = random.Random(SEED)
        rng_cases.shuffle(cases)
        state = {"i": 0}

        def path_trick(rng: random.Random) -> tuple[PathTrickCorpus, str, dict]:
            # Round-robin over the shuffled (target, trick) cases; one in four with
            # --allow-outside-paths (the regular-file rule must still hold).
            target, _, ref = cases[state["i"] % len(cases)]
            state["i"] += 1
            return tricks, target, {"ref": ref, "allow_outside": rng.random() < 0.25}

        def bomb(rng: random.Random) -> tuple[Path, str]:
            doc = json.loads(json.dumps(self.gltf_doc))
            acc = rng.choice(doc["accessors"])
            acc["count"] = rng.choice([2**31 - 1, 2**30, 10**9, 2**24])
            (f / "mb.gltf").write_text(json.dumps(doc))
            return f / "mb.gltf", "mb.gltf"

        codec_seeds = _codec_seeds()

        def codec_payload(rng: random.Random) -> tuple[Path, str, bool, bool]:
            # issue 18: a Draco / meshopt / KTX2 / WebP payload with its bytes mutated, or its
            # glTF's JSON (counts, strides, modes, ids) mutated; textures decoded too.
            name = rng.choice(sorted(codec_seeds))
            build, payload = codec_seeds[name]
            if rng.random() < 0.6:
                doc, binary = build(mutate_bytes(payload, rng))
            else:
                doc, binary = build(payload)
                doc = mutate_json(doc, rng)
            (f / "mc.glb").write_bytes(_plain_glb(doc, binary))
            return f / "mc.glb", "mc.glb", False, True

        return {
            "gltf json": gltf_json,
            "gltf bytes": bytes_of("s.gltf", self.gltf_bytes),
            "glb bytes": bytes_of("s.glb", self.glb),
            "obj bytes": bytes_of("f.obj", _OBJ),
            "mtl bytes": mtl,
            "comp5822mesh bytes": bytes_of("s.comp5822mesh", self.comp),
            "vkpbr bytes": bytes_of("s.vkpbr", self.vkpbr),
            "vkpbr json (checksums fixed)": vkpbr_json,
            "texture bytes and bombs": texture,
            "count bombs": bomb,
            "path tricks": path_trick,
            "codec payloads (Draco, meshopt, KTX2, WebP)": codec_payload,
        }


def _plain_glb(doc: dict, binary: bytes) -> bytes:
    """A GLB of `doc` with `binary` as its BIN chunk, as given (unlike _glb: no image added)."""
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    binary = binary + b"\0" * (-len(binary) % 4)
    body = (struct.pack("<I4s", len(text), b"JSON") + text
            + struct.pack("<I4s", len(binary), b"BIN\0") + binary)
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def _codec_seeds() -> dict[str, tuple[Callable[[bytes], tuple[dict, bytes]], bytes]]:
    """name -> (payload -> (glTF JSON, GLB binary), seed payload) for each compressed form
    whose encoder is installed (WebP always: Pillow)."""
    import io

    import numpy as np
    from gltf_files import GltfFile, grid_mesh
    from PIL import Image as PILImage

    g = grid_mesh(4)
    seeds: dict = {}

    def finish(f: GltfFile) -> tuple[dict, bytes]:
        doc = json.loads(json.dumps(f.doc))
        doc["buffers"] = [{"byteLength": len(f.buffers[0])}]
        return doc, bytes(f.buffers[0])

    def textured(mime: str, ext: str) -> Callable[[bytes], tuple[dict, bytes]]:
        def build(payload: bytes) -> tuple[dict, bytes]:
            f = GltfFile()
            f.used(ext, required=True)
            f.doc["images"] = [{"bufferView": f.view(payload), "mimeType": mime}]
            f.doc["textures"] = [{"extensions": {ext: {"source": 0}}}]
            f.doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
            f.node(mesh=f.mesh({"POSITION": f.accessor(g["POSITION"]),
                                "TEXCOORD_0": f.accessor(g["TEXCOORD_0"])},
                               f.accessor(g["indices"]), material=0))
            return finish(f)
        return build

    px = np.random.default_rng(0).integers(0, 256, (8, 8, 4), np.uint8)
    buf = io.BytesIO()
    PILImage.fromarray(px, "RGBA").save(buf, "WEBP")
    seeds["webp"] = (textured("image/webp", "EXT_texture_webp"), buf.getvalue())
    try:
        from gltf_files import ktx2_bytes

        # With its mips: the BC7 transcode (a GPU with BC7) reads the mutated levels too.
        seeds["ktx2"] = (textured("image/ktx2", "KHR_texture_basisu"), ktx2_bytes(px, mipmaps=True))
    except ImportError:  # alktx2 (the test extra) absent
        pass
    try:
        import DracoPy

        draco = DracoPy.encode(g["POSITION"], g["indices"].reshape(-1, 3), preserve_order=True)
        n = len(g["POSITION"])

        def build_draco(payload: bytes) -> tuple[dict, bytes]:
            f = GltfFile()
            f.used("KHR_draco_mesh_compression", required=True)
            view = f.view(payload)
            pos = f.accessor(None, ctype=5126, ncomp=3, count=n)
            ind = f.accessor(None, ctype=5125, ncomp=1, count=len(g["indices"]))
            f.node(mesh=f.mesh({"POSITION": pos}, ind, extensions={
                "KHR_draco_mesh_compression": {"bufferView": view, "attributes": {"POSITION": 0}}}))
            return finish(f)

        seeds["draco"] = (build_draco, draco)
    except ImportError:
        pass
    try:
        import meshoptimizer as mo

        pos = np.ascontiguousarray(g["POSITION"])
        vert = mo.encode_vertex_buffer(pos.view(np.uint8).reshape(len(pos), 12), len(pos), 12)
        idx = mo.encode_index_buffer(g["indices"], len(g["indices"]))

        def build_meshopt(payload: bytes) -> tuple[dict, bytes]:
            f = GltfFile()
            f.used("EXT_meshopt_compression", required=True)
            fallback = f.add_buffer(None, fallback=True)
            cut = min(len(vert), len(payload))  # the mutated bytes: vertex stream, then index
            parts = [(payload[:cut], len(pos), 12, "ATTRIBUTES"),
                     (payload[cut:], len(g["indices"]), 4, "TRIANGLES")]
            views = []
            for data, count, stride, mode in parts:
                offset = f.append(0, data)
                views.append(f.view(bytes(count * stride), stride if mode == "ATTRIBUTES" else None,
                                    buffer=fallback, EXT_meshopt_compression={
                                        "buffer": 0, "byteOffset": offset, "byteLength": len(data),
                                        "byteStride": stride, "count": count, "mode": mode}))
            a = f.accessor(None, views[0], ctype=5126, ncomp=3, count=len(pos))
            i = f.accessor(None, views[1], ctype=5125, ncomp=1, count=len(g["indices"]))
            f.node(mesh=f.mesh({"POSITION": a}, i))
            doc, binary = finish(f)
            doc["buffers"].append({"byteLength": f.placeholder_lengths[fallback],
                                   "extensions": {"EXT_meshopt_compression": {"fallback": True}}})
            return doc, binary

        seeds["meshopt"] = (build_meshopt, vert + idx)
    except ImportError:
        pass
    return seeds


# --- path tricks ----------------------------------------------------------------------------
class Forbidden(BaseException):
    """Raised by PathGuard inside an open() it forbids: a BaseException, so that no loader's
    `except Exception` can swallow it and carry on."""


class PathGuard:
    """An audit hook (sys.addaudithook; installed once per process, idle until armed) that
    forbids, while armed, every open of

    - a file under `guard_root` but outside `scene_dir` (unless `allow_outside`),
    - a system file a scene might name (/etc/passwd, /proc/..., /dev/...) (unless
      `allow_outside`; devices are not regular files, so they are forbidden always),
    - anything that exists and is not a regular file (a FIFO, a device, a folder), always.

    The open is stopped (Forbidden) and recorded in `violations`."""

    _installed: PathGuard | None = None
    SYSTEM = ("/etc/", "/proc/", "/dev/", "/sys/")

    def __init__(self) -> None:
        self.armed = False
        self.guard_root = self.scene_dir = ""
        self.allow_outside = False
        self.violations: list[str] = []

    @classmethod
    def get(cls) -> PathGuard:
        if cls._installed is None:
            cls._installed = PathGuard()
            sys.addaudithook(cls._installed._hook)
        return cls._installed

    def arm(self, guard_root: Path, scene_dir: Path, allow_outside: bool) -> None:
        self.guard_root = os.path.realpath(guard_root)
        self.scene_dir = os.path.realpath(scene_dir)
        self.allow_outside, self.violations, self.armed = allow_outside, [], True

    def disarm(self) -> list[str]:
        self.armed = False
        return self.violations

    @staticmethod
    def _under(path: str, folder: str) -> bool:
        return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)

    def _hook(self, event: str, args: tuple) -> None:
        if event != "open" or not self.armed or isinstance(args[0], int):
            return
        try:
            real = os.path.realpath(os.fsdecode(args[0]))
            mode = os.stat(real).st_mode
        except (OSError, ValueError, TypeError):
            return  # the open fails by itself: nothing is read
        why = None
        if not stat.S_ISREG(mode):
            why = "a file that is not regular"
        elif not self.allow_outside and (
                (self._under(real, self.guard_root) and not self._under(real, self.scene_dir))
                or real.startswith(self.SYSTEM)):
            why = "a file outside the scene's folder"
        if why:
            self.violations.append(f"opened {why}: {real}")
            raise Forbidden(real)


# (name, reference): {e} is the extension of the file the reference is for, {out} the absolute
# outside folder (holding a valid secret.{e}: read, it would load).
PATH_TRICKS = (
    ("dotdot", "../outside/secret.{e}"),
    ("dotdot chain", "../" * 12 + "etc/passwd"),
    ("dotdot through a subfolder", "sub/../../outside/secret.{e}"),
    ("absolute", "{out}/secret.{e}"),
    ("absolute system file", "/etc/passwd"),
    ("proc", "/proc/self/environ"),
    ("percent-encoded dotdot", "%2e%2e/outside/secret.{e}"),
    ("percent-encoded, upper case", "%2E%2E%2Foutside%2Fsecret.{e}"),
    ("percent-encoded absolute", "%2Fetc%2Fpasswd"),
    ("file URI", "file://{out}/secret.{e}"),
    ("file URI, system file", "file:///etc/passwd"),
    ("file: relative", "file:../outside/secret.{e}"),
    ("backslashes", "..\\outside\\secret.{e}"),
    ("symlink to a file outside", "link.{e}"),
    ("symlink to a folder outside", "linkdir/secret.{e}"),
    ("FIFO", "fifo.{e}"),
    ("/dev/zero", "/dev/zero"),
    ("symlink to /dev/zero", "zero.{e}"),
    ("folder", "dir.{e}"),
    ("dot", "."),
    ("empty", ""),
    ("name of 300 characters", "a" * 300 + ".{e}"),
    ("path of 5,000 characters", "/".join(["b" * 200] * 25) + ".{e}"),
    ("NUL byte", "ok\0.{e}"),
    ("inside (control: loads)", "sub/../ok.{e}"),
)
# (name, extension of the named file): what names the file.
PATH_TARGETS = (("glTF buffer", "bin"), ("glTF image", "png"), ("OBJ mtllib", "mtl"),
                ("MTL map", "png"), (".comp5822mesh texture", "png"), (".vkpbr image", "png"))


class PathTrickCorpus:
    """A scene folder `root/scene` (ok.bin, ok.png, ok.mtl, sub/, dir.*/, fifo.*, link.* and
    zero.* symlinks, linkdir/) beside `root/outside` (valid secret.bin, secret.png, secret.mtl),
    and one scene file per (target, trick) naming the trick's reference."""

    def __init__(self, root: Path, corpus: Corpus) -> None:
        self.root, self.scene_dir, self.outside = root, root / "scene", root / "outside"
        self.scene_dir.mkdir(parents=True)
        (self.scene_dir / "sub").mkdir()
        self.outside.mkdir()
        mtl = b"newmtl m\nKd 0 1 0\n"
        for folder, stem in ((self.scene_dir, "ok"), (self.outside, "secret")):
            (folder / f"{stem}.bin").write_bytes(_gltf_buffer())
            (folder / f"{stem}.png").write_bytes(_png((255, 0, 255, 255)))
            (folder / f"{stem}.mtl").write_bytes(mtl)
        for ext in ("bin", "png", "mtl"):
            os.symlink(self.outside / f"secret.{ext}", self.scene_dir / f"link.{ext}")
            os.symlink("/dev/zero", self.scene_dir / f"zero.{ext}")
            os.mkfifo(self.scene_dir / f"fifo.{ext}")
            (self.scene_dir / f"dir.{ext}").mkdir()
        os.symlink(self.outside, self.scene_dir / "linkdir")
        self.gltf_doc = _gltf_doc("ok.bin", "ok.png")
        self.comp = corpus.comp  # its one texture is "t.png" (6 bytes with the NUL)
        from vkpbr.bake.bake import bake_file
        from vkpbr.scene.baked_file import read_sections

        base = self.scene_dir / "base.gltf"
        base.write_text(json.dumps(self.gltf_doc))
        # External references: the trick replaces the image record's path.
        bake_file(base, self.scene_dir / "base.vkpbr", progress=False, textures="external")
        self.sections = read_sections(self.scene_dir / "base.vkpbr")
        base.unlink()
        (self.scene_dir / "base.vkpbr").unlink()

    def reference(self, trick: str, ext: str) -> str:
        return trick.replace("{e}", ext).replace("{out}", self.outside.as_posix())

    def write(self, target: str, ref: str) -> Path:
        """The scene file of `target` naming `ref`; every one is called pt.* (errors must
        name it: "pt." is in no other name)."""
        f = self.scene_dir
        if target in ("glTF buffer", "glTF image"):
            doc = json.loads(json.dumps(self.gltf_doc))
            if target == "glTF buffer":
                doc["buffers"][0]["uri"] = ref
            else:
                doc["images"][0]["uri"] = ref
            (f / "pt.gltf").write_text(json.dumps(doc))
            return f / "pt.gltf"
        if target in ("OBJ mtllib", "MTL map"):
            lib = ref if target == "OBJ mtllib" else "pt.mtl"
            (f / "pt.mtl").write_bytes(b"newmtl m\nKd 1 1 1\nmap_Kd " + os.fsencode(ref) + b"\n")
            (f / "pt.obj").write_bytes(b"mtllib " + os.fsencode(lib) + b"\nusemtl m\nv 0 0 0\n"
                                       b"v 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n")
            return f / "pt.obj"
        if target == ".comp5822mesh texture":
            raw = os.fsencode(ref) + b"\0"
            old = struct.pack("<I", 6) + b"t.png\0"
            assert self.comp.count(old) == 1
            (f / "pt.comp5822mesh").write_bytes(
                self.comp.replace(old, struct.pack("<I", len(raw)) + raw))
            return f / "pt.comp5822mesh"
        from vkpbr.scene.baked_file import write_sections

        out = []
        for name, data in self.sections:
            if name == "scene":
                scene = json.loads(data)
                scene["images"][0]["path"] = ref
                data = json.dumps(scene).encode()
            out.append((name, data))
        write_sections(f / "pt.vkpbr", out)
        return f / "pt.vkpbr"

    def cases(self) -> list[tuple[str, str, str]]:
        """Every (target, trick name, reference)."""
        return [(target, name, self.reference(trick, ext))
                for target, ext in PATH_TARGETS for name, trick in PATH_TRICKS]


def run_path_trick(tricks: PathTrickCorpus, target: str, ref: str,
                   allow_outside: bool = False) -> tuple[str, str]:
    """Load the scene of (target, ref) under the PathGuard, decoding its textures too when
    it loads (the image path is read then); (outcome, detail) as `run_one`."""
    path = tricks.write(target, ref)
    guard = PathGuard.get()
    guard.arm(tricks.root, tricks.scene_dir, allow_outside)
    try:
        outcome, detail = run_one(path, "pt.", allow_outside_paths=allow_outside, decode=True)
    finally:
        violations = guard.disarm()
    if violations:
        return "unclean", f"{target} {ref[:80]!r}: {violations[0]}"
    return outcome, detail and f"{target} {ref[:80]!r}: {detail}"


# --- running --------------------------------------------------------------------------------
def run_one(path: Path, names: str, allow_outside_paths: bool = False,
            decode: bool = False) -> tuple[str, str]:
    """(outcome, detail) of loading `path`: loaded / clean / unclean. `decode`: decode the
    loaded scene's textures too (as the renderer would)."""
    from vkpbr.errors import VkpbrError
    from vkpbr.scene.loader import load_scene

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene = load_scene(path, allow_outside_paths=allow_outside_paths)
            if decode:
                from vkpbr.scene.textures import decode_images

                decode_images(scene, workers=1, blocks="bc7", block_levels={})  # BC7 too
        outcome, detail = "loaded", ""
    except Forbidden as exc:
        outcome, detail = "unclean", f"forbidden open: {exc}"
    except VkpbrError as exc:
        text = str(exc)
        ok = "\n" not in text and names in text
        outcome, detail = ("clean", "") if ok else ("unclean", f"message: {text[:200]!r}")
    except Exception as exc:  # noqa: BLE001 - the point of the suite
        outcome, detail = "unclean", f"{type(exc).__name__}: {str(exc)[:200]}"
    return outcome, detail


def fuzz(folder: Path, per_format: int, seed: int = SEED,
         only: tuple[str, ...] = ()) -> tuple[dict, list[str]]:
    """Run `per_format` inputs of every format (or of those whose names start with one of
    `only`); returns (counts, unclean details). Each format's counter holds its time too
    ("seconds")."""
    corpus = Corpus(folder)
    rng = random.Random(seed)
    counts: dict[str, collections.Counter] = {}
    failures: list[str] = []
    import logging

    logger = logging.getLogger("vkpbr")
    level = logger.level
    logger.setLevel(logging.CRITICAL)  # the loaders' one-line warnings, restored after
    try:
        for name, make in corpus.formats().items():
            if only and not name.startswith(only):
                continue
            c = counts[name] = collections.Counter()
            t0 = time.perf_counter()
            for i in range(per_format):
                made = make(rng)
                if isinstance(made[0], PathTrickCorpus):
                    outcome, detail = run_path_trick(made[0], made[1], **made[2])
                else:
                    outcome, detail = run_one(*made)
                c["tried"] += 1
                c[outcome] += 1
                if outcome == "unclean":
                    failures.append(f"{name} #{i}: {detail}")
            c["seconds"] = time.perf_counter() - t0  # type: ignore[assignment]
    finally:
        logger.setLevel(level)
    return counts, failures


def fuzz_surfaces(folder: Path, per_surface: int | dict[str, int], seed: int = SEED,
                  only: tuple[str, ...] = ()) -> tuple[dict, list[str]]:
    """Run `per_surface` cases of every surface of tests/fuzz_surfaces.py (lights,
    semantics, poses, job files, manifests, environments, command lines), or of those whose
    names start with one of `only`; returns (counts, unclean details) as `fuzz` does. An
    accepted case counts as "loaded"."""
    import logging

    import fuzz_surfaces as fs

    box = fs.Sandbox(folder)
    rng = random.Random(seed)
    counts: dict[str, collections.Counter] = {}
    failures: list[str] = []
    logger = logging.getLogger("vkpbr")
    level = logger.level
    logger.setLevel(logging.CRITICAL)
    try:
        with fs.no_display():
            for name in fs.SURFACES:
                if only and not name.startswith(only):
                    continue
                n = per_surface if isinstance(per_surface, int) else per_surface.get(name, 0)
                c = counts[name] = collections.Counter()
                t0 = time.perf_counter()
                for i in range(n):
                    outcome, detail = fs.run_surface(name, rng, box)
                    c["tried"] += 1
                    c["loaded" if outcome == "accepted" else outcome] += 1
                    if outcome == "unclean":
                        failures.append(f"{name} #{i}: {detail}")
                c["seconds"] = time.perf_counter() - t0  # type: ignore[assignment]
    finally:
        logger.setLevel(level)
    return counts, failures


def table(counts: dict) -> str:
    lines = ["| format or surface | tried | clean errors | loaded or accepted | unclean | s |",
             "|---|---:|---:|---:|---:|---:|"]
    total = collections.Counter()
    for name, c in counts.items():
        lines.append(f"| {name} | {c['tried']} | {c['clean']} | {c['loaded']} | {c['unclean']} "
                     f"| {c['seconds']:.0f} |")
        total.update(c)
    lines.append(f"| all | {total['tried']} | {total['clean']} | {total['loaded']} | "
                 f"{total['unclean']} | {total['seconds']:.0f} |")
    return "\n".join(lines)


def surface_count() -> int:
    import fuzz_surfaces as fs

    return len(fs.SURFACES)


if __name__ == "__main__":
    import tempfile

    n = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else SEED
    only = tuple(sys.argv[3:])  # names (prefixes) of formats or surfaces: only those
    per = max(1, n // (N_FORMATS + surface_count()))
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        counts, failures = {}, []
        if not only or any(name.startswith(only) for name in FORMAT_NAMES):
            (Path(tmp) / "formats").mkdir()
            counts, failures = fuzz(Path(tmp) / "formats", per, seed, only)
        more, more_failures = fuzz_surfaces(Path(tmp) / "surfaces", per, seed, only)
        counts.update(more)
        failures += more_failures
        print(table(counts))
        print(f"\n{sum(c['tried'] for c in counts.values())} inputs in {time.perf_counter() - t0:.0f} s")
        for line in failures[:40]:
            print("UNCLEAN", line)
    sys.exit(1 if failures else 0)
