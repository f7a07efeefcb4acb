"""The fuzz suite's surfaces besides scene files (issue 35): lights files, semantic mappings,
poses files, Ray job files, manifests found in a job's out folder, environment panoramas
and command lines. tests/fuzzing.py runs them after the scene formats, one table row each.

Each case ends in one of:

  accepted  the input was taken (a mutation can leave a file valid; a command can succeed);
  clean     vkpbr's own error (VkpbrError), one line, naming the file (or, for a command
            line, exit status 1 or 2 with exactly one "vkpbr: error: ..." line on stderr);
  unclean   anything else: another exception, a traceback, a multi-line or anonymous
            message, another exit status, or a case still running after CASE_SECONDS.

Inputs: seed files of each kind mutated as JSON (types swapped, keys deleted, values made
evil) or as bytes, whole hostile documents (nested 100,000 deep, a 5,000-digit integer, a
100,000-character string, 1e400, NaN, UTF-16, invalid UTF-8, a bare value), and hostile
paths where a file is named: missing, a folder, /dev/zero, /dev/null, /proc/self/status, a
symlink loop, a name with a NUL byte, a 300-byte name, a 5,000-character path, a lone
surrogate. Output paths: under /proc, under a file, in a missing folder, a folder itself,
a NUL byte, a 250- and a 300-byte name, a 5,000-character path. FIFOs are left out: opening
one without a writer blocks, as it does for every program.

Command lines: every subcommand (render, view, bake, bench, info, batch), from a base line
that does little work (8x6 images, one frame), with 1-3 edits: an option's value replaced
by a hostile file, a hostile output path or an evil value (numbers of every kind, 5,000
digits, empty, NUL), an option of the subcommand added with such a value, or a word
dropped. Run in this process (`vkpbr.app.cli.main`), stderr captured, no display.
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import os
import random
import signal
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path

from fuzzing import _gltf_buffer, _gltf_doc, _png, mutate_bytes, mutate_json

CASE_SECONDS = 120  # a case running longer is a hang (unclean)

Case = tuple[Callable[[], object], str]  # (run it, what its error must name)

# --- seed documents -------------------------------------------------------------------------
LIGHTS = [{"type": "point", "position": [0, 2, 0], "intensity": 5, "color": [1, 0.9, 0.8]},
          {"type": "spot", "position": [0, 3, 0], "direction": [0, -1, 0], "range": 10,
           "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
          {"type": "directional", "direction": [0, -1, -1], "shadows": False}]
SEMANTICS = {"floor": 1, "sphere": "ball", "node 0": 7}
POSES = ["0.6,3.2,9,0.4,2.2,0", "9,2.5,0.5,0.4,2.2,0,0,1,0",
         {"name": "close-up", "eye": [2.0, 1.5, 3.0], "target": [0.4, 1.0, 0.0], "up": [0, 1, 0],
          "fov": 35},
         {"name": "opengl", "world_from_camera": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 5],
                                                  [0, 0, 0, 1]], "convention": "opengl"},
         {"K": [[50, 0, 32], [0, 50, 24], [0, 0, 1]], "size": [64, 48],
          "world_from_camera": [[1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 5], [0, 0, 0, 1]]}]
TRANSFORMS = {"camera_angle_x": 0.69, "w": 16, "h": 12,
              "frames": [{"file_path": "./r_0", "transform_matrix": [[1, 0, 0, 0], [0, 1, 0, 0],
                                                                     [0, 0, 1, 4], [0, 0, 0, 1]]},
                         {"file_path": "./r_1", "transform_matrix": [[0, 0, 1, 4], [0, 1, 0, 0],
                                                                     [-1, 0, 0, 0], [0, 0, 0, 1]]}]}

# Whole documents no reader should take, and none should crash on.
HOSTILE_JSON: list[bytes] = [
    b"[" * 100_000 + b"]" * 100_000,
    b'{"a":' * 70 + b"1" + b"}" * 70,
    b'{"x": ' + b"7" * 5000 + b"}",
    b"[-" + b"1" * 25 + b"]",
    json.dumps({"lights": ["a" * 100_000]}).encode(),
    json.dumps({"k" * 70_000: 1}).encode(),
    b"[1e400, -1e400]", b'{"a": NaN, "b": Infinity}', b"[NaN]",
    '{"a": "\u00e9"}'.encode("utf-16"), b'{"a": "\xff\xfe"}', b"\xef\xbb\xbf[]",
    b"", b" ", b"null", b"0", b'"x"', b"[]", b"{}", b"true", b"[[[[]]]]",
    b'{"a": 1, "a": {"b": []}}', b'["\\ud800", "\\u0000"]', b"[" + b"0," * 200_000 + b"0]",
]


def _hdr(width: int = 16, height: int = 8, pixels: int | None = None) -> bytes:
    """A flat (uncompressed) Radiance RGBE panorama declaring width x height, holding
    `pixels` pixels (all of them by default; fewer: a header that lies)."""
    head = f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n".encode()
    return head + bytes([128, 64, 32, 129]) * (width * height if pixels is None else pixels)


def _exr() -> bytes | None:
    try:
        import numpy as np

        from vkpbr.io import write_image
    except ImportError:  # pragma: no cover
        return None
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "e.exr"
        try:
            write_image(p, np.full((8, 16, 4), 0.5, np.float32))
        except Exception:  # noqa: BLE001 - OpenEXR missing: the .hdr seed alone
            return None
        return p.read_bytes()


def _animated_doc() -> dict:
    """The fuzz suite's glTF with one animation: node 0 moves 1 along x in 1 s (its times
    and translations in a data: URI buffer), for --time, --animation and --animate."""
    import base64

    import numpy as np

    doc = _gltf_doc("b.bin", "t.png")
    data = np.array([0, 1], np.float32).tobytes() + np.array([[0, 0, 0], [1, 0, 0]],
                                                             np.float32).tobytes()
    doc["buffers"].append({"uri": "data:application/octet-stream;base64,"
                                  + base64.b64encode(data).decode(), "byteLength": len(data)})
    doc["bufferViews"] += [{"buffer": 1, "byteOffset": 0, "byteLength": 8},
                           {"buffer": 1, "byteOffset": 8, "byteLength": 24}]
    doc["accessors"] += [{"bufferView": 4, "componentType": 5126, "count": 2, "type": "SCALAR",
                          "min": [0], "max": [1]},
                         {"bufferView": 5, "componentType": 5126, "count": 2, "type": "VEC3"}]
    doc["animations"] = [{"name": "slide", "samplers": [{"input": 4, "output": 5}],
                          "channels": [{"sampler": 0,
                                        "target": {"node": 0, "path": "translation"}}]}]
    return doc


# --- outcomes -------------------------------------------------------------------------------
class _Hang(BaseException):
    """Raised by SIGALRM in a case that ran past CASE_SECONDS."""


def _alarm(_signum: int, _frame: object) -> None:
    raise _Hang


@contextlib.contextmanager
def _deadline(seconds: int) -> object:
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def run_case(run: Callable[[], object], names: str) -> tuple[str, str]:
    """(outcome, detail) of one API case: accepted / clean / unclean."""
    from vkpbr.errors import VkpbrError

    try:
        with warnings.catch_warnings(), _deadline(CASE_SECONDS):
            warnings.simplefilter("ignore")
            run()
        return "accepted", ""
    except _Hang:
        return "unclean", f"still running after {CASE_SECONDS} s"
    except VkpbrError as exc:
        text = str(exc)
        if "\n" in text or names not in text:
            return "unclean", f"message: {text[:300]!r} (should name {names!r})"
        return "clean", ""
    except Exception as exc:  # noqa: BLE001 - the point of the suite
        return "unclean", f"{type(exc).__name__}: {str(exc)[:300]}"


def run_cli(argv: list[str]) -> tuple[str, str]:
    """(outcome, detail) of one command line run in this process."""
    from vkpbr.app.cli import main

    err, out = io.StringIO(), io.StringIO()
    shown = " ".join(a[:60] for a in argv)[:400]
    try:
        # In a scratch folder: an edit that turns a value into a relative path ("--out -1")
        # writes there, not into the checkout the tests run from.
        with tempfile.TemporaryDirectory() as scratch, contextlib.chdir(scratch), \
                contextlib.redirect_stderr(err), contextlib.redirect_stdout(out), \
                warnings.catch_warnings(), _deadline(CASE_SECONDS):
            code = main(argv)
    except _Hang:
        return "unclean", f"{shown!r}: still running after {CASE_SECONDS} s"
    except BaseException as exc:  # noqa: BLE001 - anything escaping main is a bug
        return "unclean", f"{shown!r}: {type(exc).__name__}: {str(exc)[:200]}"
    text = err.getvalue()
    errors = [line for line in text.splitlines() if line.startswith("vkpbr: error")]
    if "Traceback" in text:
        return "unclean", f"{shown!r}: traceback on stderr: {text[-300:]!r}"
    if code == 0:
        return "accepted", ""
    if code in (1, 2) and len(errors) == 1:
        return "clean", ""
    return "unclean", f"{shown!r}: exit {code}, stderr {text[-300:]!r}"


# --- hostile paths --------------------------------------------------------------------------
class Sandbox:
    """The files every surface points at: seeds, hostile documents, hostile paths."""

    def __init__(self, root: Path) -> None:
        self.root = root
        root.mkdir(parents=True, exist_ok=True)
        (root / "t.png").write_bytes(_png())
        (root / "b.bin").write_bytes(_gltf_buffer())
        (root / "s.gltf").write_text(json.dumps(_gltf_doc("b.bin", "t.png")))
        (root / "a.gltf").write_text(json.dumps(_animated_doc()))
        (root / "lights.json").write_text(json.dumps(LIGHTS))
        (root / "sem.json").write_text(json.dumps(SEMANTICS))
        (root / "poses.json").write_text(json.dumps(POSES))
        (root / "transforms.json").write_text(json.dumps(TRANSFORMS))
        (root / "sky.hdr").write_bytes(_hdr())
        exr = _exr()
        self.env_seeds = {".hdr": _hdr()} | ({".exr": exr} if exr else {})
        if exr:
            (root / "sky.exr").write_bytes(exr)
        (root / "adir").mkdir(exist_ok=True)
        (root / "afile").write_bytes(b"x")
        loop = root / "loop.json"
        if not loop.is_symlink():
            loop.symlink_to(loop)
        zero = root / "zero.json"
        if not zero.is_symlink():
            zero.symlink_to("/dev/zero")
        for i, doc in enumerate(HOSTILE_JSON):
            (root / f"hostile{i}.json").write_bytes(doc)
        (root / "garbage.json").write_bytes(bytes(range(256)) * 4)

    def hostile_files(self, suffix: str = ".json") -> list[str]:
        r = self.root
        return [str(r / f"missing{suffix}"), str(r / "adir"), "/dev/zero", "/dev/null",
                "/proc/self/status", str(r / "loop.json"), str(r / "zero.json"),
                str(r / f"a\0b{suffix}"), str(r / ("n" * 300 + suffix)),
                str(r / ("d/" * 2600 + f"x{suffix}")), str(r / f"\ud800{suffix}"),
                str(r / "afile" / f"x{suffix}"), str(r / "garbage.json"),
                *(str(r / f"hostile{i}.json") for i in range(len(HOSTILE_JSON)))]

    def hostile_outputs(self, suffix: str = ".png") -> list[str]:
        r = self.root  # (\udcff: how Python decodes the byte 0xff in a command line)
        return ["/proc/x" + suffix, "/proc/self/x" + suffix, str(r / "afile" / f"x{suffix}"),
                str(r / "missing-dir" / f"x{suffix}"), str(r / "adir"),
                str(r / f"a\0b{suffix}"), str(r / ("m" * 250 + suffix)),
                str(r / ("n" * 300 + suffix)), str(r / ("d/" * 2600 + f"x{suffix}")),
                str(r / f"\ud800{suffix}"), str(r / f"\udcff{suffix}")]


def _token(path: str) -> str:
    """What a message naming `path` must contain: its last characters as vkpbr shows them
    (long paths are cut in the middle; NUL bytes written as \\0)."""
    return path.replace("\0", "\\0")[-16:]


def _json_case(rng: random.Random, box: Sandbox, seed: object, name: str) -> tuple[Path, str]:
    """A file `name` in the sandbox holding a mutation of `seed` (or a hostile document), or
    a hostile path: (the path, what an error must name)."""
    r = rng.random()
    if r < 0.15:
        path = rng.choice(box.hostile_files())
        return Path(path), _token(path)
    if r < 0.3:
        data = rng.choice(HOSTILE_JSON)
    elif r < 0.45:
        data = mutate_bytes(json.dumps(seed).encode(), rng)
    else:
        doc = {"_": seed} if not isinstance(seed, dict) else seed
        mutated = mutate_json(copy.deepcopy(doc), rng)
        data = json.dumps(mutated["_"] if not isinstance(seed, dict) and "_" in mutated
                          else mutated).encode()
    path = box.root / name
    path.write_bytes(data)
    return path, name


# --- the surfaces ---------------------------------------------------------------------------
def lights_case(rng: random.Random, box: Sandbox) -> Case:
    from vkpbr.scene.lights import load_lights_file

    seed = LIGHTS if rng.random() < 0.7 else {"lights": LIGHTS}
    path, names = _json_case(rng, box, seed, "m_lights.json")
    return (lambda: load_lights_file(path)), names


def semantics_case(rng: random.Random, box: Sandbox) -> Case:
    from vkpbr.scene.semantics import load_semantic_mapping

    path, names = _json_case(rng, box, SEMANTICS, "m_sem.json")
    return (lambda: load_semantic_mapping(path)), names


def poses_case(rng: random.Random, box: Sandbox) -> Case:
    from vkpbr.scene.poses import load_poses

    seed = POSES if rng.random() < 0.6 else TRANSFORMS
    path, names = _json_case(rng, box, seed, "m_poses.json")
    return (lambda: load_poses(path)), names


def _job_doc(rng: random.Random, box: Sandbox, out: str) -> object:
    entry = {"scene": "s.gltf", "cameras": rng.choice(["poses.json", POSES[:3]]), "out": out,
             "size": "16x12", "outputs": ["depth", "instance"], "semantics": "sem.json",
             "options": {"view": "final"}, "batch": 4, "colmap": True}
    doc: object = [entry, dict(entry, scene=None, out=out + "-b", semantics="material")]
    if rng.random() < 0.3:
        doc = {"scenes": doc, "views_per_item": 2, "retries": 1}
    return doc


def job_case(rng: random.Random, box: Sandbox) -> Case:
    """A job file (mutated, hostile, or naming hostile files and out folders) through
    load_job and the driver's checks before any actor starts (check_job)."""
    from vkpbr.distributed import load_job
    from vkpbr.distributed.driver import check_job

    doc = _job_doc(rng, box, f"out{rng.randrange(4)}")
    entries = doc["scenes"] if isinstance(doc, dict) else doc
    if rng.random() < 0.3:  # a hostile file or out folder where the entry names one
        key = rng.choice(["scene", "cameras", "semantics", "out"])
        entries[0][key] = rng.choice(box.hostile_outputs("") if key == "out" else box.hostile_files())
        (box.root / "m_job.json").write_text(json.dumps(doc))
        path, names = box.root / "m_job.json", "m_job.json"
    else:
        path, names = _json_case(rng, box, doc, "m_job.json")

    def run() -> None:
        check_job(load_job(path))

    return run, names


def _manifest_lines(box: Sandbox, job: object) -> list[bytes]:
    """A real manifest of the job's first entry: its header and two done items, written by
    vkpbr.distributed.manifest itself."""
    from vkpbr.distributed.manifest import MANIFEST_NAME, Manifest, camera_record
    from vkpbr.scene.camera import Camera

    scene = job.scenes[0]
    folder = box.root / "seed-manifest"
    folder.mkdir(exist_ok=True)
    (folder / MANIFEST_NAME).unlink(missing_ok=True)
    for name in ("frame_00000.png", "frame_00001.png"):
        (folder / name).unlink(missing_ok=True)
    m = Manifest.open(folder, scene.fingerprint(), scene.where)
    for name in ("frame_00000.png", "frame_00001.png"):  # as the out folder will hold them
        (folder / name).write_bytes(_png())
    base = Camera(eye=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0))
    cams = [camera_record(p.camera(base)) for p in scene.poses[:2]]
    m.done([0], ["frame_00000.png"], cams[:1])
    m.done([1], ["frame_00001.png"], cams[1:2])
    m.failed([2], "boom", 3)
    m.close()
    return (folder / MANIFEST_NAME).read_bytes().splitlines(keepends=True)


def manifest_case(rng: random.Random, box: Sandbox) -> Case:
    """A job whose out folder already holds a manifest, mutated line by line (JSON edits,
    bytes, lines dropped, repeated or cut): read as a resumed run reads it (check_job, the
    done views, the cameras for transforms.json)."""
    from vkpbr.distributed import load_job
    from vkpbr.distributed.driver import _finish_entry, check_job
    from vkpbr.distributed.manifest import MANIFEST_NAME

    job_path = box.root / "manifest-job.json"
    if not hasattr(box, "manifest_seed"):
        job_path.write_text(json.dumps([{"scene": "s.gltf", "cameras": POSES[:3],
                                         "out": "mf-out", "size": "16x12"}]))
        box.manifest_seed = _manifest_lines(box, load_job(job_path))  # type: ignore[attr-defined]
    lines = list(box.manifest_seed)  # type: ignore[attr-defined]
    for _ in range(rng.randint(1, 3)):
        i = rng.randrange(len(lines))
        r = rng.random()
        if r < 0.5:
            try:
                rec = json.loads(lines[i])
                lines[i] = json.dumps(mutate_json({"_": rec}, rng)["_"]).encode() + b"\n"
            except (ValueError, KeyError, RecursionError):  # a line an earlier edit broke
                lines[i] = mutate_bytes(lines[i], rng)
        elif r < 0.65:
            lines[i] = mutate_bytes(lines[i], rng)
        elif r < 0.75:
            del lines[i]
            lines = lines or [b"\n"]
        elif r < 0.85:
            lines.insert(i, lines[i])
        elif r < 0.95:
            lines[i] = rng.choice(HOSTILE_JSON)[:100_000] + b"\n"
        else:
            lines[i] = lines[i][: rng.randrange(len(lines[i]) + 1)]
    out = box.root / "mf-out"
    out.mkdir(exist_ok=True)
    (out / MANIFEST_NAME).write_bytes(b"".join(lines))
    for name in ("frame_00000.png", "frame_00001.png"):
        (out / name).write_bytes(_png())

    def run() -> None:
        job = load_job(job_path)
        for scene, manifest in zip(job.scenes, check_job(job), strict=True):
            manifest.done_views()
            _finish_entry(scene, manifest)
            manifest.close()

    return run, MANIFEST_NAME


def environment_case(rng: random.Random, box: Sandbox) -> Case:
    from vkpbr.scene.environment import load_panorama

    r = rng.random()
    if r < 0.15:
        path = rng.choice(box.hostile_files(rng.choice([".hdr", ".exr"])))
        return (lambda: load_panorama(path)), _token(path)
    suffix = rng.choice(sorted(box.env_seeds))
    seed = box.env_seeds[suffix]
    if r < 0.25:
        data = _hdr(rng.choice([1, 2, 3, 0, 2**15, 70000]), rng.choice([1, 0, 2**14, 35000]),
                    pixels=rng.choice([0, 1, 128]))  # sizes the bytes do not back
        suffix = ".hdr"
    else:
        data = mutate_bytes(seed, rng)
    path = box.root / f"m_env{suffix}"
    path.write_bytes(data)
    return (lambda: load_panorama(path)), path.name


# --- command lines --------------------------------------------------------------------------
_FILE_OPTIONS = {"scene", "--cameras", "--light", "--semantics", "--env", "--script",
                 "--sponza", "--peers-json", "job", "--cache"}
_OUT_OPTIONS = {"--out", "--screenshot", "--poses-dir"}
# Options whose valid values scale the work (frames, pixels, views): given only invalid or
# small values, so that an accepted case stays a short one.
_COUNTS = {"--frames", "--size", "--batch", "--shadow-resolution", "--views", "--batch-views",
           "--actors", "--msaa", "--camera-index", "--fps", "--duration", "--num-gpus"}
_EVIL_VALUES = ["-1", "0", "1", "nan", "inf", "-inf", "1e308", "x", "", "\0", "1,2", "1,2,3",
                "a:b:c", "none", "on", "off", "-5,0.6,-0.9", "0x0", "-8x6", "99999x99999",
                "9" * 5000, "point:0,1,0:color=1,1,1:intensity=nan", "spot:0,1,0:0,-1,0:outer=400",
                "dir:0,0,0", "1,2,3,4,5,6,7,8,9,10"]
_SAFE_COUNTS = ["-1", "0", "1", "2", "x", "", "nan", "inf", "1e9", "1e308", "9" * 5000, "0x0", "-8x6"]

_BASES = {
    "render": lambda b: ["render", str(b.root / "s.gltf"), "--size", "8x6", "--out",
                         str(b.root / "cli" / "r.png")],
    "render-animate": lambda b: ["render", str(b.root / "a.gltf"), "--size", "8x6", "--animate",
                                 "--fps", "2", "--out", str(b.root / "cli" / "anim")],
    "render-time": lambda b: ["render", str(b.root / "a.gltf"), "--size", "8x6", "--time", "0.5",
                              "--animation", "slide", "--out", str(b.root / "cli" / "t.png")],
    "view": lambda b: ["view", str(b.root / "s.gltf"), "--offscreen", "--frames", "1",
                       "--size", "8x6"],
    "bake": lambda b: ["bake", str(b.root / "s.gltf"), "--out", str(b.root / "cli" / "s.vkpbr"),
                       "--no-progress"],
    # bench's file options, each where its scenario reads it (elsewhere bench ignores them
    # and measures for seconds): --sponza in a Sponza scenario, --poses-dir in a batch one.
    "bench": lambda b: ["bench", "--frames", "1", "--scenario", "sponza-480p", "--sponza",
                        str(b.root / "garbage.json")],
    "bench-batch": lambda b: ["bench", "--frames", "1", "--views", "1", "--batch-views", "1",
                              "--scenario", "batch-helmet-128", "--poses-dir",
                              str(b.root / "afile" / "poses")],
    "info": lambda b: ["info", "--json"],
    "batch": lambda b: ["batch", str(b.root / "manifest-job.json")],
}


def _options(command: str) -> list[tuple[str, object]]:
    """(option string, argparse action) of every option and positional of `command`."""
    from vkpbr.app.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.choices and command in a.choices)
    out = []
    for action in sub.choices[command]._actions:
        if action.dest in ("help", "version"):
            continue
        name = action.option_strings[-1] if action.option_strings else action.dest
        out.append((name, action))
    return out


_INVALID = ["-1", "x", "", "nan", "9" * 5000, "\0", "0x0", "1,2,3,4,5,6,7,8,9,10"]


def _value(rng: random.Random, box: Sandbox, name: str, action: object,
           invalid_only: bool = False) -> str:
    if name in _OUT_OPTIONS:
        return rng.choice(box.hostile_outputs(rng.choice([".png", ".exr", ".vkpbr", ""])))
    if name in _FILE_OPTIONS:
        return rng.choice(box.hostile_files(rng.choice([".json", ".gltf", ".hdr", ".obj"])))
    if invalid_only:
        return rng.choice(_INVALID)
    choices = getattr(action, "choices", None)
    if choices and rng.random() < 0.5:
        return str(rng.choice(list(choices)))
    return rng.choice(_SAFE_COUNTS if name in _COUNTS else _EVIL_VALUES)


def cli_case(rng: random.Random, box: Sandbox) -> list[str]:
    """A command line: a subcommand's base line with 1-3 hostile edits. `vkpbr bench` gets
    only edits that name hostile files or invalid values: each run it accepts renders
    1080p frames for several seconds on a CPU."""
    base = rng.choice(sorted(_BASES))
    argv = _BASES[base](box)
    command = argv[0]
    options = _options(command)
    bench = command == "bench"
    if bench:
        options = [(n, a) for n, a in options if getattr(a, "nargs", None) != 0]
    for _ in range(rng.randint(1, 3)):
        r = rng.random()
        valued = [i for i, a in enumerate(argv) if i > 1 and argv[i - 1].startswith("--")]
        if r < 0.4 and valued:  # replace a value
            i = rng.choice(valued)
            if bench and argv[i - 1] == "--scenario":
                continue  # another scenario would ignore the hostile file
            action = next((a for n, a in options if n == argv[i - 1]), None)
            argv[i] = _value(rng, box, argv[i - 1], action, bench)
        elif r < 0.55 and command in ("render", "view", "bake", "batch") and not base.startswith(
                "render-"):  # the file itself
            argv[1] = rng.choice(box.hostile_files(rng.choice([".gltf", ".json", ".obj", ".vkpbr"])))
        elif r < 0.9 or bench:  # add an option
            name, action = rng.choice(options)
            if not name.startswith("-"):
                continue
            argv.append(name)
            if getattr(action, "nargs", None) != 0:
                argv.append(_value(rng, box, name, action, bench))
        elif len(argv) > 2:  # drop a word
            del argv[rng.randrange(1, len(argv))]
    return argv


SURFACES: dict[str, Callable[[random.Random, Sandbox], object]] = {
    "lights files (--light FILE.json)": lights_case,
    "semantic mappings (--semantics FILE.json)": semantics_case,
    "poses files (--cameras)": poses_case,
    "job files (vkpbr batch)": job_case,
    "manifests in an out folder": manifest_case,
    "environment files (--env)": environment_case,
    "command lines (every subcommand)": cli_case,
}


def run_surface(name: str, rng: random.Random, box: Sandbox) -> tuple[str, str]:
    made = SURFACES[name](rng, box)
    if isinstance(made, list):
        return run_cli(made)
    return run_case(*made)


@contextlib.contextmanager
def no_display() -> object:
    """No window system for `vkpbr view` (it must say so in one line, not open a window)."""
    saved = {k: os.environ.pop(k) for k in ("DISPLAY", "WAYLAND_DISPLAY") if k in os.environ}
    try:
        yield
    finally:
        os.environ.update(saved)
