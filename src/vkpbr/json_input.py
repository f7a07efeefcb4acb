"""The one reader of JSON inputs: every JSON file or chunk vkpbr reads (glTF and GLB, poses,
lights, semantic mappings, job files and their manifests, viewer scripts, a baked file's scene
JSON, the cache's frame-paths.json, `vkpbr bench --peers-json` rows) is decoded here, under one set of limits, so that a hostile or broken file
is one error line naming it (JsonError, which each reader words as its own error), not a
traceback or a decode that exhausts the stack or the memory.

The limits (`JSON_LIMITS`), and why:

- size: 128 MiB (134,217,728 bytes) of JSON. The real inputs are far smaller (the sample
  glTF files' JSON: at most 0.2 MiB; 100,000 poses as 4x4 matrices: 36 MiB); a .gltf with
  its buffers embedded as base64 is the largest kind, and one over the limit can be written
  as .glb (binary buffers outside the JSON). Decoded, JSON grows into Python objects: 4-8x
  its size for numbers, about 25x for a file of empty arrays, so 128 MiB bounds a decode
  near the 4 GiB the texture limits allow a scene (scene/limits.py). `read_json` refuses
  a regular file over the limit before reading it.
- nesting: 64 levels of arrays and objects. The deepest real files need about 10 (a glTF
  primitive's extension attributes: 8; a transforms.json frame's matrix rows: 5), plus
  whatever a glTF's `extras` hold. Python's decoder recurses once per level, and so can
  the code that walks the decoded document; 64 keeps both far from the interpreter's
  recursion limit (1,000).
- strings: 65,536 characters (keys and values), for every input but scene files. The
  longest real strings are paths (4,096 bytes at most on Linux) and names (glTF node and
  material names in a semantic mapping: tens of characters). A glTF's strings hold whole
  buffers and images as base64 `data:` URIs, so scene files' JSON (`SCENE_JSON_LIMITS`)
  bounds them only by the size; what they declare is checked by scene/limits.py.
- integers: 20 digits (2**64 - 1 has 20; the inputs need less: ids are 32-bit, glTF byte
  lengths below 2**53). CPython's int() takes time quadratic in the digits (its own limit
  is 4,300 digits for that reason), and float() of an integer over 308 digits overflows in
  the checks that convert it.

Text is UTF-8 (a byte-order mark is skipped), or UTF-16/32, as `json.loads` detects it.
NaN and Infinity are decoded as Python's json decodes them: no limit here concerns them.
"""

from __future__ import annotations

import errno
import json
import os
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from vkpbr.errors import JsonError

__all__ = ["JSON_LIMITS", "SCENE_JSON_LIMITS", "JsonLimits", "decode_json", "read_json"]


@dataclass(frozen=True)
class JsonLimits:
    """Bounds on one JSON input (the module docstring says why these values)."""

    max_bytes: int = 128 << 20
    max_depth: int = 64
    max_int_digits: int = 20
    max_string_chars: int | None = 65_536  # None: no bound but max_bytes (scene files)


JSON_LIMITS = JsonLimits()
# Scene files' JSON (a glTF's, a baked file's scene section): the same but for strings, which
# hold whole buffers and images as base64 data: URIs; their reader bounds what they declare
# (scene/limits.py).
SCENE_JSON_LIMITS = JsonLimits(max_string_chars=None)


class _LongInteger(ValueError):
    """Raised from inside the decoder (json's parse_int hook) to stop it at once."""


def _parse_int(text: str) -> int:
    # JSON integers are "-"? digits, no "+" and no leading zeros (the decoder checked).
    # (max_int_digits is the same in every JsonLimits: one hook serves them all.)
    if len(text) - text.startswith("-") > JSON_LIMITS.max_int_digits:
        raise _LongInteger
    return int(text)


def _shape_problem(doc: Any, limits: JsonLimits) -> str | None:
    """Whether arrays and objects nest more than `max_depth` levels (the top one is level 1)
    or a string (a key or a value) is longer than `max_string_chars`: the problem, or None.
    A loop, not recursion: the check itself must not run out of stack."""
    depth_limit, chars = limits.max_depth, limits.max_string_chars
    too_deep = f"nested deeper than {depth_limit} levels"

    def long_string(value: Any) -> str | None:
        if chars is not None and isinstance(value, str) and len(value) > chars:
            return (f"a string of {len(value):,} characters ({value[:20]!r}...), more than "
                    f"the {chars:,} vkpbr reads")
        return None

    if not isinstance(doc, dict | list):
        return long_string(doc)
    stack: list[tuple[Any, int]] = [(doc, 1)]
    while stack:
        value, depth = stack.pop()
        if isinstance(value, dict):
            if chars is not None:
                for key in value:
                    if (problem := long_string(key)) is not None:
                        return problem
            children = value.values()
        else:
            children = value
        for child in children:
            if isinstance(child, dict | list):
                if depth >= depth_limit:
                    return too_deep
                stack.append((child, depth + 1))
            elif chars is not None and (problem := long_string(child)) is not None:
                return problem
    return None


def decode_json(data: bytes, where: str | os.PathLike[str],
                limits: JsonLimits = JSON_LIMITS) -> Any:
    """The JSON document in `data`, checked against `JSON_LIMITS`.

    Parameters
    ----------
    data : the JSON text as bytes (UTF-8, or UTF-16/32 as `json.loads` detects it).
    where : what error messages name: the file, or the file and the part ("x.glb: JSON chunk").
    limits : JSON_LIMITS for every input but scene files, which pass SCENE_JSON_LIMITS.

    Returns
    -------
    The decoded value: dict, list, str, int, float, bool or None.

    Raises
    ------
    JsonError : one line, "WHERE: PROBLEM": over the size, nesting, integer or string limit, not
        text in a Unicode encoding, or not JSON (the decoder's message with line and column).
    """
    if len(data) > limits.max_bytes:
        raise JsonError(where, f"{len(data):,} bytes of JSON, more than the {limits.max_bytes:,} "
                               "vkpbr reads")
    try:
        doc = json.loads(data, parse_int=_parse_int)
    except _LongInteger:
        raise JsonError(where, f"an integer of more than {limits.max_int_digits} digits") from None
    except RecursionError:  # deeper than the interpreter's stack allows: over the limit too
        raise JsonError(where, f"nested deeper than {limits.max_depth} levels") from None
    except ValueError as exc:  # JSONDecodeError, UnicodeDecodeError
        problem = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise JsonError(where, problem) from None
    problem = _shape_problem(doc, limits)
    if problem is not None:
        raise JsonError(where, problem)
    return doc


def read_json(path: str | os.PathLike[str], limits: JsonLimits = JSON_LIMITS) -> Any:
    """The JSON document in the file `path`, checked against `JSON_LIMITS` (`decode_json`).

    A regular file over the size limit is refused before it is read; anything else (a pipe,
    /dev/stdin) is read up to the limit and one byte more.

    Raises
    ------
    OSError : the file cannot be opened or read, or `path` can name no file (a NUL byte, a
        name over NAME_MAX: vkpbr.user_paths.path_problem); left to the caller, whose message
        says what the file was for.
    JsonError : as `decode_json`, naming `path`.
    """
    from vkpbr.user_paths import path_problem

    p = Path(path)
    problem = path_problem(p)
    if problem is not None:  # open() would raise ValueError (a NUL byte) or a bare OSError
        code = errno.ENAMETOOLONG if "long" in problem or "more than" in problem else errno.EINVAL
        raise OSError(code, f"the path {problem}", str(p))
    limit = limits.max_bytes
    with open(p, "rb") as f:
        st = os.fstat(f.fileno())
        if stat.S_ISREG(st.st_mode) and st.st_size > limit:
            raise JsonError(p, f"{st.st_size:,} bytes of JSON, more than the {limit:,} vkpbr "
                               "reads")
        data = f.read(limit + 1)
    if len(data) > limit:  # a pipe or device: its full length is unknown, so say "more than"
        raise JsonError(p, f"more than {limit:,} bytes of JSON, the most vkpbr reads")
    return decode_json(data, p, limits)
