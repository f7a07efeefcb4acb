# The one JSON reader (vkpbr/json_input.py) and every public entry that reads JSON through it:
# over-size, over-deep, huge-integer and malformed inputs end in one line of the entry's own
# error class naming the file, never a traceback or a hang. No GPU.

from __future__ import annotations

import json
import struct
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vkpbr.app.script import load_script
from vkpbr.distributed import Manifest, load_job
from vkpbr.errors import JsonError, SceneError, UsageError, VkpbrError
from vkpbr.json_input import JSON_LIMITS, decode_json, read_json
from vkpbr.scene.lights import load_lights_file
from vkpbr.scene.loader import load_scene
from vkpbr.scene.poses import load_poses
from vkpbr.scene.semantics import load_semantic_mapping

SRC = Path(__file__).resolve().parents[2] / "src"
DEPTH = JSON_LIMITS.max_depth
DIGITS = JSON_LIMITS.max_int_digits


def nested(levels: int) -> bytes:
    return b"[" * levels + b"]" * levels


# (name, the file's bytes, what the message says); the over-size file is made sparse below.
BAD = [
    ("deep", nested(DEPTH + 1), f"nested deeper than {DEPTH} levels"),
    ("very-deep", nested(100_000), f"nested deeper than {DEPTH} levels"),
    ("deep-object", b'{"a":' * (DEPTH + 1) + b"1" + b"}" * (DEPTH + 1),
     f"nested deeper than {DEPTH} levels"),
    ("long-int", b"[" + b"9" * (DIGITS + 1) + b"]", f"an integer of more than {DIGITS} digits"),
    ("huge-int", b'{"x": -' + b"7" * 5000 + b"}", f"an integer of more than {DIGITS} digits"),
    ("malformed", b"{nope", "Expecting property name enclosed in double quotes: line 1"),
    ("empty", b"", "Expecting value: line 1 column 1 (char 0)"),
    ("latin1", b'["\xff\xfe\xfa"]', "codec can't decode"),
    ("oversize", b"", f"more than the {JSON_LIMITS.max_bytes:,} vkpbr reads"),
]


def bad_file(folder: Path, name: str, data: bytes, suffix: str = ".json") -> Path:
    path = folder / f"{name}{suffix}"
    path.write_bytes(data)
    if name == "oversize":  # a sparse file: its size is over the limit, its disk use nothing
        with open(path, "r+b") as f:
            f.truncate(JSON_LIMITS.max_bytes + 1)
    return path


def glb(json_chunk: bytes) -> bytes:
    """A GLB container holding `json_chunk` as its JSON chunk (glTF 2.0 section 4.4)."""
    json_chunk += b" " * (-len(json_chunk) % 4)
    body = struct.pack("<II", len(json_chunk), 0x4E4F534A) + json_chunk
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


# Public entry -> (error class, how its message starts for `path`, what it says before the
# problem). Each keeps the wording it had before the reader was shared.
ENTRIES: dict[str, tuple[Callable[[Path], object], type[VkpbrError], Callable[[Path], str]]] = {
    "lights": (load_lights_file, UsageError, lambda p: f"{p}: not a JSON lights file: "),
    "semantics": (load_semantic_mapping, UsageError, lambda p: f"semantic mapping {p}: not JSON ("),
    "poses": (load_poses, UsageError, lambda p: f"{p}: not valid JSON ("),
    "job": (load_job, UsageError, lambda p: f"{p}: not valid JSON ("),
    "script": (load_script, UsageError, lambda p: f"--script {p}: not valid JSON ("),
    "gltf": (load_scene, SceneError, lambda p: f"{p}: malformed JSON: "),
}


def check_one_line(exc: BaseException, cls: type, start: str, problem: str) -> None:
    text = str(exc)
    assert type(exc) is cls, f"{type(exc).__name__}: {text}"
    assert text.startswith(start) and problem in text, text
    assert "\n" not in text and len(text) < 400, text
    assert exc.__cause__ is None or isinstance(exc.__cause__, VkpbrError)


@pytest.mark.timeout(60)
@pytest.mark.parametrize("entry", ENTRIES)
@pytest.mark.parametrize(("name", "data", "problem"), BAD, ids=[b[0] for b in BAD])
def test_every_entry_refuses_bad_json_in_one_line(tmp_path: Path, entry: str, name: str,
                                                 data: bytes, problem: str) -> None:
    read, cls, start = ENTRIES[entry]
    path = bad_file(tmp_path, name, data, ".gltf" if entry == "gltf" else ".json")
    with pytest.raises(VkpbrError) as info:
        read(path)
    check_one_line(info.value, cls, start(path), problem)


IN_MEMORY = [b for b in BAD if b[0] != "oversize"]  # a GLB's chunk is read with the file


@pytest.mark.timeout(60)
@pytest.mark.parametrize(("name", "data", "problem"), IN_MEMORY, ids=[b[0] for b in IN_MEMORY])
def test_glb_json_chunks_are_read_the_same_way(tmp_path: Path, name: str, data: bytes,
                                               problem: str) -> None:
    path = tmp_path / f"{name}.glb"
    path.write_bytes(glb(data))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    check_one_line(info.value, SceneError, f"{path}: malformed JSON: ", problem)


def test_manifest_lines_are_read_the_same_way(tmp_path: Path) -> None:
    from vkpbr.distributed.manifest import MANIFEST_NAME

    (tmp_path / MANIFEST_NAME).write_bytes(nested(DEPTH + 1) + b"\n")
    with pytest.raises(UsageError) as info:
        Manifest.open(tmp_path, {}, "job.json")
    check_one_line(info.value, UsageError, "job.json: ", "line 1 is not JSON; the manifest is damaged")


CHARS = JSON_LIMITS.max_string_chars
NOT_SCENES = [e for e in ENTRIES if e != "gltf"]


@pytest.mark.parametrize("entry", NOT_SCENES)
@pytest.mark.parametrize("where", ["value", "key"])
def test_every_input_but_scenes_refuses_a_long_string(tmp_path: Path, entry: str,
                                                      where: str) -> None:
    """A string (a value or a key) of max_string_chars + 1 characters is one error line from
    every reader of JSON inputs; scene files are bounded by their size alone."""
    text = "s" * (CHARS + 1)
    doc = {"a": [1, {"b": text}]} if where == "value" else {"a": {text: 1}}
    path = tmp_path / "long.json"
    path.write_text(json.dumps(doc))
    read, cls, start = ENTRIES[entry]
    with pytest.raises(VkpbrError) as info:
        read(path)
    check_one_line(info.value, cls, start(path),
                   f"a string of {CHARS + 1:,} characters ('ssssssssssssssssssss'...), more "
                   f"than the {CHARS:,} vkpbr reads")
    assert decode_json(json.dumps({"a": "s" * CHARS}).encode(), "x") == {"a": "s" * CHARS}


def test_scene_json_takes_long_strings(tmp_path: Path) -> None:
    """A glTF's buffers and images may be data: URIs of many megabytes: no string limit."""
    from vkpbr.json_input import SCENE_JSON_LIMITS

    long = "x" * (4 * CHARS)
    assert decode_json(json.dumps([long]).encode(), "x", SCENE_JSON_LIMITS) == [long]
    with pytest.raises(JsonError, match="a string of 262,144 characters"):
        decode_json(json.dumps([long]).encode(), "x")


def test_paths_no_file_can_have_are_os_errors_callers_word(tmp_path: Path) -> None:
    """read_json refuses a NUL byte or an over-long name as an OSError (which every reader
    words as its own one-line error), not open()'s ValueError."""
    for path, problem in ((f"{tmp_path}/a\0b.json", "holds a NUL byte"),
                          (tmp_path / ("n" * 300 + ".json"), "has a name of 305 bytes"),
                          (tmp_path / ("d/" * 2100 + "x.json"), "more than the 4,096")):
        with pytest.raises(OSError, match=problem):
            read_json(path)
        for entry in NOT_SCENES:
            read, cls, _ = ENTRIES[entry]
            with pytest.raises(VkpbrError) as info:
                read(path)
            text = str(info.value)
            assert type(info.value) is cls and problem in text and "\n" not in text
            assert "\0" not in text, text  # shown as \\0


def test_limits_are_inclusive() -> None:
    """Exactly at each limit decodes; one past it does not."""
    assert depth(decode_json(nested(DEPTH), "x")) == DEPTH
    n = int("9" * DIGITS)
    assert decode_json(f"[{n}, {-n}]".encode(), "x") == [n, -n]
    # A float is not an integer: a 400-digit mantissa is read as the float it is.
    assert decode_json(b"[0." + b"1" * 400 + b"]", "x") == [float("0." + "1" * 400)]
    size = JSON_LIMITS.max_bytes
    assert decode_json(b" " * (size - 2) + b"[]", "x") == []
    with pytest.raises(JsonError, match=f"^x: {size + 1:,} bytes of JSON, more than the {size:,}"):
        decode_json(b" " * (size - 1) + b"[]", "x")


@pytest.mark.timeout(60)
def test_a_stream_is_read_up_to_the_limit() -> None:
    """/dev/zero never ends: read_json stops one byte past the limit and says so."""
    with pytest.raises(JsonError, match=f"^/dev/zero: more than {JSON_LIMITS.max_bytes:,} bytes"):
        read_json("/dev/zero")


def test_read_json_names_the_file_and_leaves_os_errors(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        read_json(tmp_path / "missing.json")
    with pytest.raises(IsADirectoryError):
        read_json(tmp_path)
    path = tmp_path / "a.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps({"a": [1, 2.5, None]}).encode())  # with a BOM
    assert read_json(path) == {"a": [1, 2.5, None]}
    path.write_bytes(b"[1,")
    with pytest.raises(JsonError, match=rf"^{path}: Expecting value: line 1 column 4") as info:
        read_json(path)
    assert isinstance(info.value, ValueError) and info.value.problem.startswith("Expecting")


json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-(10**DIGITS) + 1, 10**DIGITS - 1)
    | st.floats(allow_nan=False) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=4), inner,
                                                                max_size=4),
    max_leaves=30)


def depth(value: object) -> int:
    if isinstance(value, dict):
        return 1 + max(map(depth, value.values()), default=0)
    if isinstance(value, list):
        return 1 + max(map(depth, value), default=0)
    return 0


@settings(max_examples=150, deadline=None)
@given(json_values)
def test_what_json_writes_is_read_back(value: object) -> None:
    assert decode_json(json.dumps(value).encode(), "x") == value


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 3 * DEPTH), st.booleans())
def test_depth_is_counted_exactly(levels: int, arrays: bool) -> None:
    text = "[" * levels + "]" * levels if arrays else '{"k":' * levels + "0" + "}" * levels
    assert depth(json.loads(text)) == levels
    if levels <= DEPTH:
        assert depth(decode_json(text.encode(), "x")) == levels
    else:
        with pytest.raises(JsonError, match=f"^x: nested deeper than {DEPTH} levels$"):
            decode_json(text.encode(), "x")


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=200) | st.text(alphabet='[]{}":,0123456789-.eE tfnrul\\', max_size=200)
       .map(str.encode))
def test_any_bytes_decode_or_give_one_json_error(data: bytes) -> None:
    try:
        decode_json(data, "x.json")
    except JsonError as exc:
        assert str(exc).startswith("x.json: ") and "\n" not in str(exc)


@settings(max_examples=100, deadline=None)
@given(st.text(alphabet='[]{}":,0123456789-. eyt', max_size=120))
def test_any_poses_text_gives_one_usage_error(tmp_path_factory: pytest.TempPathFactory,
                                              text: str) -> None:
    path = tmp_path_factory.mktemp("poses") / "poses.json"
    path.write_text(text)
    try:
        load_poses(path)
    except UsageError as exc:
        assert type(exc) is UsageError and "\n" not in str(exc) and str(path) in str(exc)


def test_one_json_reader_in_src() -> None:
    """Every JSON input goes through vkpbr/json_input.py: no other module decodes JSON."""
    bad = [f"{p.relative_to(SRC)}: {needle}" for p in sorted(SRC.rglob("*.py"))
           if p.name != "json_input.py"
           for needle in ("json.load(", "json.loads(", "JSONDecoder(", "raw_decode(")
           if needle in p.read_text(encoding="utf-8")]
    assert bad == []
