# Wavefront OBJ/MTL -> vkpbr Scene, with the COMP5822M PBR extensions to MTL: map_Pm
# (metalness), map_Pr (roughness), Pm/Pr factors, norm (normal map) and map_d (alpha mask).
#
# The OBJ is parsed by tinyobjloader (C++, pinned: TINYOBJLOADER_VERSION); the MTL files by
# parse_mtl below, which knows the course's keys and reads every file through the path policy
# (tinyobjloader gets a stand-in library of the material names only, so it never opens a
# file). Around it, vkpbr keeps what the reader always promised: the limits checked before
# anything is built, every face index checked, a word or a short line in v/vt/vn data an error
# (tinyobjloader reads them as 0: such files take the exact NumPy parse of those statements),
# nan/inf vertices dropped with their faces. Polygons are fan-triangulated and (v, vt, vn)
# corners welded with np.unique; texture coordinates are flipped (v' = 1 - v) to glTF's
# top-left origin. One Mesh per run of faces with one group (g/o) and one material.
# Speed (a 22.6 MB, 262k-triangle Sponza OBJ, 2 shared cores): 0.8-1.1 s, was 2.8-3.4 s
# with the regex parser alone (BENCHMARKS.md, benchmarks/bench_obj.py).
# Reference: Wavefront "Object Files (.obj)" and "MTL" specifications (Appendix B1/B2).

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np

from vkpbr.errors import SceneError
from vkpbr.scene.geometry import drop_nonfinite, ensure_normals, normalize_mesh_arrays, polygon_fan
from vkpbr.scene.limits import limits
from vkpbr.scene.resources import (
    ResourcePolicy,
    ResourceRefused,
    is_regular_file,
    read_error,
    read_resource,
)
from vkpbr.scene.types import Image, Material, Mesh, Node, Sampler, Scene, TextureRef

__all__ = ["TINYOBJLOADER_VERSION", "load_obj", "parse_mtl"]

TINYOBJLOADER_VERSION = "2.0.0rc13"  # pinned in pyproject.toml: wheels for CPython 3.11/3.12

_STATEMENT = re.compile(rb"^[ \t]*(vt|vn|v|f|usemtl|g|o)(?=[ \t])", re.M)
_MAX_TOKEN = 256  # longer "numbers" are garbage; also bounds the NumPy bytes-array width


def _rows(data: bytes, keyword: bytes) -> list[bytes]:
    """The argument text of every `keyword` line, in file order (comments cut off)."""
    return re.findall(rb"^[ \t]*" + keyword + rb"[ \t]+([^\r\n#]*)", data, re.M)


def _tokens(path: Path, rows: list[bytes], what: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split rows into whitespace tokens without a Python loop per row.

    Returns
    -------
    tokens : (K,) bytes array; row : (K,) int64 row of each token; counts : (R,) tokens per row
    """
    if not rows:
        return np.zeros(0, "S1"), np.zeros(0, np.int64), np.zeros(0, np.int64)
    # A "|" marker between rows lets one split() do all rows; cumsum of markers = row number.
    parts = b" | ".join(rows).split()
    if max(map(len, parts), default=0) > _MAX_TOKEN:
        raise SceneError(path, f"absurdly long token in {what} data")
    toks = np.array(parts)
    marker = toks == b"|"
    if int(marker.sum()) != len(rows) - 1:
        raise SceneError(path, f"stray '|' in {what} data")
    row = np.cumsum(marker)[~marker]
    return toks[~marker], row, np.bincount(row, minlength=len(rows))


def _floats(path: Path, rows: list[bytes], take: int, need: int, what: str) -> np.ndarray:
    """First `take` numbers of each row as (R, take) float64; rows need >= `need` numbers."""
    toks, row, counts = _tokens(path, rows, what)
    if len(rows) and counts.min() < need:
        raise SceneError(path, f"{what} line {int(np.argmin(counts)) + 1} has too few numbers")
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    col = np.arange(len(toks)) - first[row]
    sel = col < take
    out = np.zeros((len(rows), take), np.float64)
    try:
        out[row[sel], col[sel]] = toks[sel].astype(np.float64)
    except ValueError as exc:
        raise SceneError(path, f"bad number in {what} data ({exc})") from exc
    return out


def _check_counts(path: Path, order: np.ndarray) -> None:
    """Refuse a file with more v/vt/vn statements than the vertex limit, or more faces than
    the triangle limit (each face is at least one triangle), from the statement list alone:
    a 1,000,000-face file fails here in a few MiB, not after building ~0.7 GiB of arrays."""
    cap = limits()
    for kw, what in ((b"v", "vertex positions"), (b"vt", "texture coordinates"),
                     (b"vn", "normals")):
        n = int(np.count_nonzero(order == kw))
        if n > cap.max_vertices:
            raise SceneError(path, f"{n:,} {what} ({kw.decode()} statements) are over the "
                                   f"limit of {cap.max_vertices:,} vertices; raise it with "
                                   "VKPBR_MAX_VERTICES")
    faces = int(np.count_nonzero(order == b"f"))
    if faces > cap.max_triangles:
        raise SceneError(path, f"{faces:,} faces are over the limit of {cap.max_triangles:,} "
                               "triangles; raise it with VKPBR_MAX_TRIANGLES")


def _check_corners(path: Path, rows: list[bytes]) -> None:
    """Refuse faces whose fan triangulation (corners - 2 per face) exceeds the triangle
    limit, counting corners as word starts in the rows' bytes (one byte of work space per
    byte of face text) before they are split into Python objects."""
    if not rows:
        return
    text = np.frombuffer(b" ".join(rows), np.uint8)
    blank = (text == 0x20) | (text == 0x09) | (text == 0x0B) | (text == 0x0C)
    corners = int(np.count_nonzero(~blank[1:] & blank[:-1])) + int(not blank[0])
    triangles = corners - 2 * len(rows)
    cap = limits().max_triangles
    if triangles > cap:
        raise SceneError(path, f"{len(rows):,} faces of {corners:,} corners make "
                               f"{triangles:,} triangles, over the limit of {cap:,}; raise it "
                               "with VKPBR_MAX_TRIANGLES")


def load_obj(path: str | Path, policy: ResourcePolicy | None = None) -> Scene:
    """Load a Wavefront OBJ file and the MTL libraries it names.

    `policy` says where the MTL and texture files may lie (default: the OBJ's folder tree;
    an MTL library outside it is a SceneError, a texture outside it a missing texture).

    Returns
    -------
    Scene with one Mesh (and one identity Node) per group/usemtl run of faces; positions (N, 3),
    texcoords (N, 2) flipped to the top-left origin, normals (N, 3) (flat when the file has
    none), indices (M,) uint32.

    Raises
    ------
    SceneError : naming the file, on unreadable/malformed data or out-of-range indices.
    """
    path = Path(path)
    try:
        data = read_resource(path)
    except OSError as exc:
        raise SceneError(path, f"cannot read: {exc.strerror or exc}") from exc
    with np.errstate(all="ignore"):  # overflowing numbers become inf, then drop_nonfinite
        return _parse(path, data, policy or ResourcePolicy(path))


def _early_limits(path: Path, data: bytes) -> None:
    """The limits, before tinyobjloader builds anything: a file of L lines has at most L
    v/vt/vn/f statements and at most len/2 corners, so a file under both bounds passes at the
    cost of one byte count; only a larger one is counted statement by statement."""
    cap = limits()
    lines = data.count(b"\n") + 1
    if lines <= min(cap.max_vertices, cap.max_triangles) and len(data) // 2 <= cap.max_triangles:
        return
    # One byte string per statement (CPython shares the 1-byte ones): ~9 bytes a statement.
    _check_counts(path, np.array(_STATEMENT.findall(data) or [b""]))
    _check_corners(path, _rows(data, b"f"))


_BLANK = np.zeros(256, bool)
_BLANK[list(b" \t\r\n\v\f")] = True
_NUMBER = _BLANK.copy()
_NUMBER[list(b"0123456789+-.eE")] = True


def _plain_vertex_lines(data: bytes) -> bool:
    """Whether every v/vt/vn statement is plain numbers, enough of them, at the start of its
    line: then tinyobjloader's values are the file's. Anything else (a comment, nan or inf, a
    word, too few numbers, leading blanks) goes to the exact parse, which reads and reports
    it as the reader always has (tinyobjloader reads a word or a missing number as 0).

    Vectorised over the blocks of consecutive vertex lines (the bytes of other lines are
    never looked at): a block is plain when its only bytes outside numbers and blanks are the
    keywords' letters, and every line has enough tokens. (A "number" of only + - . e E
    characters passes: tinyobjloader reads it as 0.)"""
    b = np.frombuffer(data, np.uint8)
    if not len(b):
        return True
    newlines = np.flatnonzero(b == 0x0A)
    starts = np.concatenate(([0], newlines + 1))
    ends = np.concatenate((newlines, [len(b)]))
    keep = starts < len(b)
    starts, ends = starts[keep], ends[keep]
    padded = np.concatenate((b, np.zeros(2, np.uint8)))
    first, second, third = padded[starts], padded[starts + 1], padded[starts + 2]
    if (_BLANK[first] & (first != 0x0A) & (first != 0x0D)).any():
        return False  # a statement may follow the blanks (rare): the exact parse decides
    is_v = first == ord("v")
    kind = np.full(len(starts), -1)
    kind[is_v & _BLANK[second]] = 0
    kind[is_v & (second == ord("t")) & _BLANK[third]] = 1
    kind[is_v & (second == ord("n")) & _BLANK[third]] = 2
    lines = np.flatnonzero(kind >= 0)
    if not len(lines):
        return True
    letters = np.where(kind == 0, 1, 2)  # "v", "vt", "vn": the keyword's letters
    need = np.array([4, 2, 4])[kind]  # tokens: v x y z, vt u, vn x y z
    cut = np.flatnonzero(np.diff(lines) != 1) + 1
    for block in np.split(lines, cut):
        lo, hi = starts[block[0]], ends[block[-1]]
        chunk = b[lo:hi]
        if np.count_nonzero(~_NUMBER[chunk]) != letters[block].sum():
            return False
        solid = ~_BLANK[chunk]
        token = solid.copy()
        token[1:] &= ~solid[:-1]
        per_line = np.add.reduceat(token, starts[block] - lo, dtype=np.int64)
        if (per_line < need[block]).any():
            return False
    return True


def _tinyobj() -> object:
    try:
        import tinyobjloader
    except ImportError:
        return None
    return tinyobjloader


def _mtllib_names(data: bytes) -> list[str]:
    """The libraries of every `mtllib` statement: found with bytes.find (a few per file),
    not a regex pass over the whole file."""
    names, at = [], data.find(b"mtllib")
    while at >= 0:
        line_start = data.rfind(b"\n", 0, at) + 1
        line_end = data.find(b"\n", at)
        line = data[line_start: len(data) if line_end < 0 else line_end]
        m = re.match(rb"[ \t]*mtllib[ \t]+([^\r\n#]*)", line)
        if m and data[line_start:at].strip(b" \t") == b"":
            names.append(m.group(1).strip().decode("utf-8", "replace"))
        at = data.find(b"mtllib", at + 6)
    return names


def _face_error(path: Path, data: bytes, message: str) -> SceneError:
    """The SceneError for a face line tinyobjloader refused ("... Line 7)."): that line's
    corners checked here, to say what is wrong as the reader always has."""
    m = re.search(r"Line (\d+)", message)
    first_line = message.strip().splitlines()[0] if message.strip() else "parse error"
    if m is None:
        return SceneError(path, f"malformed OBJ ({first_line})")
    number = int(m.group(1))
    lines = data.split(b"\n")
    if not 0 < number <= len(lines):
        return SceneError(path, f"malformed OBJ ({first_line})")
    line = lines[number - 1]
    names = ((b"v", "vertex"), (b"vt", "texcoord"), (b"vn", "normal"))
    for corner in line.split(b"#", 1)[0].split()[1:]:
        parts = corner.split(b"/")
        if len(parts) > 3:
            return SceneError(path, f"line {number}: face corner with more than two '/'")
        for k, part in enumerate(parts):
            if not part and k:
                continue  # v//vn, v/vt/
            try:
                index = int(part)
            except ValueError:
                return SceneError(path, f"line {number}: bad face index ({part[:40]!r})")
            if index == 0:
                return SceneError(path, f"line {number}: face index 0 (OBJ counts from 1)")
            if index < 0:
                kw, name = names[k]
                before = b"\n".join(lines[: number - 1])
                defined = len(re.findall(rb"^[ \t]*" + kw + rb"[ \t]", before, re.M))
                if defined + index < 0:
                    return SceneError(path, f"line {number}: face refers to {name} {index}, "
                                            f"only {defined} defined")
    return SceneError(path, f"line {number}: malformed face ({first_line})")


def _parse(path: Path, data: bytes, policy: ResourcePolicy) -> Scene:
    """load_obj's body: `data` is the whole file."""
    tinyobj = _tinyobj()
    if tinyobj is None:
        raise SceneError(path, f"reading OBJ files needs tinyobjloader: pip install "
                               f"tinyobjloader=={TINYOBJLOADER_VERSION}")
    data = re.sub(rb"\\\r?\n", b" ", data)  # line continuations (tinyobjloader has none)
    _early_limits(path, data)

    scene = Scene(name=path.stem, source=path)
    mat_index: dict[str, int] = {}
    for lib_name in _mtllib_names(data):
        lib_path = policy.resolve(lib_name, "material library")  # outside: SceneError
        if not is_regular_file(lib_path):
            warnings.warn(f"{path}: material library {lib_name} not found", stacklevel=2)
            continue
        for name, mat in parse_mtl(lib_path, scene.images, policy).items():
            mat_index[name] = len(scene.materials)
            scene.materials.append(mat)

    # tinyobjloader reads the OBJ; vkpbr reads the MTL files (the course's PBR keys, the path
    # policy). It gets a stand-in library of the material names alone, so its material ids
    # index `names`. Text goes in as Latin-1, one character per byte, whatever the encoding.
    names = list(mat_index)
    stand_in = "".join(f"newmtl {n.encode('utf-8').decode('latin-1')}\n" for n in names)
    reader = tinyobj.ObjReader()
    config = tinyobj.ObjReaderConfig()
    config.triangulate = False  # fans made below, as before (polygon_fan)
    if not reader.ParseFromString(data.decode("latin-1"), stand_in, config):
        raise _face_error(path, data, reader.Error())
    notes = reader.Warning()
    if "Degenerated face" in notes:
        raise SceneError(path, "face with fewer than 3 corners")
    attrib = reader.GetAttrib()
    # The list accessors, not numpy_*(): rc13's arrays have stride 0 under NumPy 2.
    if _plain_vertex_lines(data):
        v = np.array(attrib.vertices, np.float64).reshape(-1, 3)
        vt = np.array(attrib.texcoords, np.float64).reshape(-1, 2)
        vn = np.array(attrib.normals, np.float64).reshape(-1, 3)
    else:  # the exact parse: nan/inf kept (then dropped below), words and short lines refused
        v = _floats(path, _rows(data, b"v"), 3, 3, "v")
        vt = _floats(path, _rows(data, b"vt"), 2, 1, "vt")
        vn = _floats(path, _rows(data, b"vn"), 3, 3, "vn")
        if (len(v), len(vt), len(vn)) != (len(attrib.vertices) // 3,
                                           len(attrib.texcoords) // 2, len(attrib.normals) // 3):
            raise SceneError(path, "malformed v/vt/vn statements (counts disagree)")
    vt[:, 1] = 1.0 - vt[:, 1]  # OBJ's origin is bottom-left, glTF's (ours) top-left

    shapes = [s for s in reader.GetShapes() if s.mesh.num_face_vertices]
    if not shapes:
        raise SceneError(path, "no faces")
    cols = [np.concatenate([np.array(getattr(s.mesh, f)(), np.int64) for s in shapes])
            for f in ("vertex_indices", "texcoord_indices", "normal_indices")]
    corners = np.stack(cols, axis=1)  # (K, 3): v, vt, vn; -1 absent
    counts = np.concatenate([np.array(s.mesh.num_face_vertices, np.int64) for s in shapes])
    material_of_face = np.concatenate([np.array(s.mesh.material_ids, np.int64) for s in shapes])
    shape_of_face = np.repeat(np.arange(len(shapes)), [len(s.mesh.num_face_vertices) for s in shapes])
    for k, (arr, name) in enumerate(((v, "vertex"), (vt, "texcoord"), (vn, "normal"))):
        bad = corners[:, k] >= len(arr)
        if bad.any():
            raise SceneError(path, f"face refers to {name} {int(corners[bad, k][0]) + 1}, only "
                                   f"{len(arr)} defined")
    for undefined in dict.fromkeys(re.findall(r"material \[ '(.*?)' \] not found", notes)):
        name = undefined.encode("latin-1", "replace").decode("utf-8", "replace")
        warnings.warn(f"{path}: material {name!r} not defined in any MTL", stacklevel=3)

    # Runs: a new one wherever the group (g/o) or the material changes.
    change = np.ones(len(counts), bool)
    change[1:] = (shape_of_face[1:] != shape_of_face[:-1]) | (material_of_face[1:] != material_of_face[:-1])
    run_of_face = np.cumsum(change) - 1
    tris = polygon_fan(counts)  # (T, 3) into the corner list
    tri_face = np.repeat(np.arange(len(counts)), counts - 2)
    tri_run = run_of_face[tri_face]
    sort = np.argsort(tri_run, kind="stable")
    run_ids, run_starts = np.unique(tri_run[sort], return_index=True)
    for r, chunk in zip(run_ids, np.split(sort, run_starts[1:]), strict=True):
        face = int(tri_face[chunk[0]])
        shape_name = shapes[shape_of_face[face]].name
        gname = shape_name.encode("latin-1", "replace").decode("utf-8", "replace") or path.stem
        mesh = _run_mesh(corners[tris[chunk].reshape(-1)], v, vt, vn, f"{gname}/{r}")
        mid = int(material_of_face[face])
        mesh.material = mat_index[names[mid]] if 0 <= mid < len(names) else -1
        mesh = normalize_mesh_arrays(ensure_normals(drop_nonfinite(mesh, path)))
        scene.nodes.append(Node(mesh=len(scene.meshes), name=gname))
        scene.meshes.append(mesh)
    return scene


def _run_mesh(c: np.ndarray, v: np.ndarray, vt: np.ndarray, vn: np.ndarray, name: str) -> Mesh:
    """Weld the (K, 3) corner triples of one run into unique vertices + indices."""
    dims = [len(v) + 1, len(vt) + 1, len(vn) + 1]
    if dims[0] * dims[1] * dims[2] < 2**62:
        key = ((c[:, 0] + 1) * dims[1] + (c[:, 1] + 1)) * dims[2] + (c[:, 2] + 1)
        _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
        uniq = c[first]
    else:
        uniq, inverse = np.unique(c, axis=0, return_inverse=True)
    tex = vt[np.maximum(uniq[:, 1], 0)] if (uniq[:, 1] >= 0).any() else None
    if tex is not None:
        tex[uniq[:, 1] < 0] = 0.0  # corners without vt in a textured run
    # Normals only if every corner has one; otherwise the run gets flat normals.
    normals = vn[uniq[:, 2]] if (uniq[:, 2] >= 0).all() else None
    return Mesh(
        name=name,
        positions=v[uniq[:, 0]],
        indices=inverse.reshape(-1).astype(np.uint32),
        normals=normals,
        texcoords=tex,
    )


_OPT_ARGS = {b"-blendu": 1, b"-blendv": 1, b"-boost": 1, b"-mm": 2, b"-texres": 1,
             b"-clamp": 1, b"-bm": 1, b"-imfchan": 1, b"-type": 1, b"-cc": 1}  # fmt: skip


def _map(line: list[bytes], folder: Path, images: list[Image], cache: dict[Path, int],
         channel: int = 0, policy: ResourcePolicy | None = None) -> tuple[TextureRef, float]:  # fmt: skip
    """An MTL map statement's options and file -> (TextureRef, -bm bump multiplier)."""
    i, opts = 0, {}
    while i < len(line) and line[i].startswith(b"-"):
        name = line[i]
        n = _OPT_ARGS.get(name)
        if n is None:  # -o/-s/-t take 1 to 3 numbers
            n = 0
            while n < 3 and i + 1 + n < len(line) and re.fullmatch(rb"[-+.\deE]+", line[i + 1 + n]):
                n += 1
        opts[name] = line[i + 1 : i + 1 + n]
        i += 1 + n
    file_name = b" ".join(line[i:]).decode("utf-8", "replace").replace("\\", "/")
    if not file_name:
        raise ValueError("map statement without a file name")
    refused = None
    try:
        file = (policy or ResourcePolicy(folder / "_.mtl")).resolve(file_name, "texture", folder)
    except ResourceRefused as exc:  # reported and replaced like a missing file
        file, refused = exc.file or folder / file_name, exc.reason
    if file not in cache:  # a missing file: load_scene reports all of them in one line
        cache[file] = len(images)
        images.append(Image(name=file_name, path=file, refused=refused))
    clamp = opts.get(b"-clamp", [b"off"])[:1] == [b"on"]
    wrap = "clamp" if clamp else "repeat"
    o = [float(x) for x in opts.get(b"-o", [])] + [0.0, 0.0]
    s = [float(x) for x in opts.get(b"-s", [])] + [1.0, 1.0]
    ref = TextureRef(image=cache[file], sampler=Sampler(wrap_s=wrap, wrap_t=wrap), channel=channel,
                     offset=(o[0], o[1]), scale=(s[0], s[1]))  # fmt: skip
    return ref, float(opts.get(b"-bm", [1.0])[0])


def parse_mtl(path: Path, images: list[Image],
              policy: ResourcePolicy | None = None) -> dict[str, Material]:
    """Parse an MTL file; new images are appended to `images` (deduplicated by path).

    Factors without their map default as glTF does, except metalness: an OBJ material with no
    Pm/map_Pm is a dielectric (0). Roughness without Pr/map_Pr comes from the Phong exponent
    Ns by the usual r = sqrt(2 / (Ns + 2)) (Walter et al. 2007, eq. 33 inverted for r = alpha^.5).
    """
    try:
        lines = read_resource(path).splitlines()
    except OSError as exc:  # named as the user's scene file, then the library
        if policy is None:
            raise SceneError(path, f"cannot read: {exc.strerror or exc}") from exc
        raise read_error(policy.scene, "material library", path.name, exc) from exc
    cache = {img.path: i for i, img in enumerate(images) if img.path is not None}
    out: dict[str, Material] = {}
    name: str | None = None
    props: dict[bytes, list[bytes]] = {}
    try:
        for line in [*lines, b"newmtl"]:  # the sentinel flushes the last material
            parts = line.split(b"#", 1)[0].split()
            if not parts:
                continue
            if parts[0] == b"newmtl":
                if name is not None:
                    out[name] = _material(name, props, path.parent, images, cache, policy)
                name, props = b" ".join(parts[1:]).decode("utf-8", "replace"), {}
            elif name is not None:
                props[parts[0].lower()] = parts[1:]  # MTL keywords are case-insensitive
    except (ValueError, IndexError) as exc:
        raise SceneError(path, f"bad material {name!r}: {exc}") from exc
    return out


def _material(name: str, p: dict[bytes, list[bytes]], folder: Path, images: list[Image],
              cache: dict[Path, int], policy: ResourcePolicy | None = None) -> Material:  # fmt: skip
    """One MTL material's statements (keywords lower-cased) -> Material."""

    def tex(line: list[bytes]) -> tuple[TextureRef, float]:
        return _map(line, folder, images, cache, policy=policy)

    def num(key: bytes, n: int, default: tuple[float, ...]) -> tuple[float, ...]:
        if key not in p:
            return default
        vals = [float(x) for x in p[key][:n]]
        if not vals or not all(np.isfinite(vals)):
            raise ValueError(f"{key.decode()} needs finite numbers")
        return tuple(vals + vals[-1:] * (n - len(vals)))  # "Kd 0.5" means grey

    kd = num(b"kd", 3, (1.0, 1.0, 1.0))
    alpha = num(b"d", 1, (1.0,))[0] if b"d" in p else 1.0 - num(b"tr", 1, (0.0,))[0]
    mat = Material(
        name=name, base_color_factor=(*kd, alpha), emissive_factor=num(b"ke", 3, (0.0,) * 3)
    )
    mat.metallic_factor = num(b"pm", 1, (1.0 if b"map_pm" in p else 0.0,))[0]
    ns = num(b"ns", 1, (0.0,))[0]
    rough_default = (
        1.0 if b"map_pr" in p or b"ns" not in p else float(np.sqrt(2.0 / (max(ns, 0.0) + 2.0)))
    )
    mat.roughness_factor = num(b"pr", 1, (rough_default,))[0]
    if b"map_kd" in p:
        mat.base_color_texture = tex(p[b"map_kd"])[0]
    if b"map_pm" in p:
        mat.metallic_texture = tex(p[b"map_pm"])[0]
    if b"map_pr" in p:
        mat.roughness_texture = tex(p[b"map_pr"])[0]
    if b"map_ke" in p:
        mat.emissive_texture = tex(p[b"map_ke"])[0]
    bump = next((p[k] for k in (b"norm", b"map_bump", b"bump") if k in p), None)
    if bump is not None:
        mat.normal_texture, mat.normal_scale = tex(bump)
    if b"map_d" in p:
        # The course's masked foliage: cut-out, no back-face culling (renderer-spec section 3).
        mat.alpha_texture = tex(p[b"map_d"])[0]
        mat.alpha_mode, mat.alpha_cutoff, mat.double_sided = "mask", 0.5, True
    elif alpha < 1.0:
        mat.alpha_mode = "blend"
    return mat
