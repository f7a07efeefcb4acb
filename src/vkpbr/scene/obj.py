# Wavefront OBJ/MTL -> vkpbr Scene, with the COMP5822M PBR extensions to MTL: map_Pm
# (metalness), map_Pr (roughness), Pm/Pr factors, norm (normal map) and map_d (alpha mask).
#
# Speed: the file is scanned by a handful of C-level regex passes (one per statement kind),
# numbers are converted by NumPy in bulk, polygons are fan-triangulated and (v, vt, vn) corners
# welded with np.unique; Python only loops over MTL lines and over meshes. Texture coordinates
# are flipped (v' = 1 - v) to glTF's top-left origin. One Mesh per group/usemtl run.
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

__all__ = ["load_obj", "parse_mtl"]

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


def _corners(path: Path, toks: np.ndarray) -> np.ndarray:
    """Face corners 'v', 'v/vt', 'v//vn', 'v/vt/vn' -> (K, 3) int64, 0 where absent."""
    if not len(toks):
        return np.zeros((0, 3), np.int64)
    slashes = np.char.count(toks, b"/")
    if slashes.max() > 2:
        raise SceneError(path, "face corner with more than two '/'")
    # Rewrite every form to v/vt/vn with 0 for "absent" (OBJ indices start at 1).
    full = np.char.add(
        np.char.replace(toks, b"//", b"/0/"), np.array([b"/0/0", b"/0", b""])[slashes]
    )
    try:
        return np.array(b"/".join(full.tolist()).split(b"/")).astype(np.int64).reshape(-1, 3)
    except (ValueError, OverflowError) as exc:
        raise SceneError(path, f"bad face index ({exc})") from exc


def _resolve(path: Path, idx: np.ndarray, defined: np.ndarray, total: int, what: str) -> np.ndarray:
    """OBJ 1-based / negative (relative to the elements defined so far) -> 0-based, -1 absent."""
    out = np.where(idx > 0, idx - 1, defined + idx)
    out[idx == 0] = -1
    bad = (idx != 0) & ((out < 0) | (out >= total))
    if bad.any():
        raise SceneError(path, f"face refers to {what} {int(idx[bad][0])}, only {total} defined")
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


def _parse(path: Path, data: bytes, policy: ResourcePolicy) -> Scene:
    """load_obj's body: `data` is the whole file."""
    data = re.sub(rb"\\\r?\n", b" ", data)  # line continuations
    # One byte string per statement (CPython shares the 1-byte ones): ~9 bytes a statement.
    order = np.array(_STATEMENT.findall(data) or [b""])
    _check_counts(path, order)  # before any per-vertex or per-face array is built
    face_rows = _rows(data, b"f")
    _check_corners(path, face_rows)
    v = _floats(path, _rows(data, b"v"), 3, 3, "v")
    vt = _floats(path, _rows(data, b"vt"), 2, 1, "vt")
    vn = _floats(path, _rows(data, b"vn"), 3, 3, "vn")
    vt[:, 1] = 1.0 - vt[:, 1]  # OBJ's origin is bottom-left, glTF's (ours) top-left
    toks, _, counts = _tokens(path, face_rows, "f")
    del face_rows
    if not len(counts):
        raise SceneError(path, "no faces")
    if counts.min() < 3:
        raise SceneError(path, "face with fewer than 3 corners")
    face_at = np.flatnonzero(order == b"f")  # statement number of each face
    if len(face_at) != len(counts):
        raise SceneError(path, "inconsistent face statements")
    corner_at = np.repeat(face_at, counts)
    raw = _corners(path, toks)
    cols = []
    for k, (kw, arr, name) in enumerate(((b"v", v, "vertex"), (b"vt", vt, "texcoord"), (b"vn", vn, "normal"))):  # fmt: skip
        defined = np.cumsum(order == kw)[corner_at]  # elements defined before each corner
        cols.append(_resolve(path, raw[:, k], defined, len(arr), name))
    corners = np.stack(cols, axis=1)

    # Runs: a new one starts at every usemtl/g/o statement; each face remembers its material.
    mtl_names = [r.strip().decode("utf-8", "replace") for r in _rows(data, b"usemtl")]
    grp_names = [r.strip().decode("utf-8", "replace") for r in _rows(data, rb"[go]")]
    boundary = np.isin(order, [b"usemtl", b"g", b"o"])
    run_of_face = np.cumsum(boundary)[face_at]
    mat_of_face = np.searchsorted(np.flatnonzero(order == b"usemtl"), face_at) - 1
    grp_of_face = np.searchsorted(np.flatnonzero(np.isin(order, [b"g", b"o"])), face_at) - 1

    scene = Scene(name=path.stem, source=path)
    mat_index: dict[str, int] = {}
    for lib in _rows(data, b"mtllib"):
        lib_name = lib.strip().decode("utf-8", "replace")
        lib_path = policy.resolve(lib_name, "material library")  # outside: SceneError
        if not is_regular_file(lib_path):
            warnings.warn(f"{path}: material library {lib_name} not found", stacklevel=2)
            continue
        for name, mat in parse_mtl(lib_path, scene.images, policy).items():
            mat_index[name] = len(scene.materials)
            scene.materials.append(mat)

    tris = polygon_fan(counts)  # (T, 3) into the corner list
    tri_face = np.repeat(np.arange(len(counts)), counts - 2)
    tri_run = run_of_face[tri_face]
    sort = np.argsort(tri_run, kind="stable")
    run_ids, run_starts = np.unique(tri_run[sort], return_index=True)
    for r, chunk in zip(run_ids, np.split(sort, run_starts[1:]), strict=True):
        face = int(tri_face[chunk[0]])
        mname = mtl_names[mat_of_face[face]] if mat_of_face[face] >= 0 else None
        if mname is not None and mname not in mat_index:
            warnings.warn(f"{path}: material {mname!r} not defined in any MTL", stacklevel=2)
            mat_index[mname] = -1
        gname = grp_names[grp_of_face[face]] if grp_of_face[face] >= 0 else path.stem
        mesh = _run_mesh(corners[tris[chunk].reshape(-1)], v, vt, vn, f"{gname}/{r}")
        mesh.material = mat_index.get(mname, -1) if mname else -1
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
