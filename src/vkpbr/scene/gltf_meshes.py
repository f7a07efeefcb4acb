# glTF primitives -> Mesh: attributes through the document's accessor decoder, indices
# resolved (strips and fans turned into lists), flat normals where NORMAL is absent, triangles
# touching non-finite positions dropped with a warning (geometry.drop_nonfinite).
# KHR_draco_mesh_compression primitives are decoded through gltf_codecs (DracoPy); without it a
# primitive whose accessors keep uncompressed fallback data loads from those.
# Reference: glTF 2.0 spec 3.7.2 (meshes), 3.7.2.1 (attributes); KHR_draco_mesh_compression.

from __future__ import annotations

import numpy as np

from vkpbr.errors import SceneError
from vkpbr.scene.geometry import (
    drop_nonfinite,
    ensure_normals,
    fan_triangles,
    normalize_mesh_arrays,
    strip_triangles,
)
from vkpbr.scene.gltf_codecs import decode_draco, missing_codec
from vkpbr.scene.gltf_document import GltfDocument, check_index, ext, floats, get, to_float
from vkpbr.scene.limits import MAX_MORPH_TARGETS
from vkpbr.scene.types import Mesh

__all__ = ["MAX_MORPH_TARGETS", "primitive"]

_MORPHED = ("POSITION", "NORMAL", "TANGENT")  # the morphable attributes vkpbr applies

_MODES = {0: "POINTS", 1: "LINES", 2: "LINE_LOOP", 3: "LINE_STRIP"}


def primitive(ld: GltfDocument, mesh_index: int, prim_index: int, prim: object) -> Mesh:
    """One triangle primitive -> Mesh (indices resolved, flat normals if NORMAL is absent)."""
    name = f"{get(ld.gltf.meshes[mesh_index], 'name', f'mesh {mesh_index}')}/{prim_index}"
    mode = get(prim, "mode", 4)
    if mode in _MODES:
        raise SceneError(
            ld.path, f"mesh {name}: primitive mode {_MODES[mode]} is not triangles"
        )
    if mode not in (4, 5, 6):
        raise SceneError(ld.path, f"mesh {name}: unknown primitive mode {mode!r}")
    attrs = get(prim, "attributes", {})
    attrs = attrs if isinstance(attrs, dict) else getattr(attrs, "__dict__", None)
    if not isinstance(attrs, dict):
        raise SceneError(ld.path, f"mesh {name}: attributes is not an object")
    if attrs.get("POSITION") is None:
        raise SceneError(ld.path, f"mesh {name}: primitive has no POSITION")
    draco = _draco(ld, name, prim, attrs, mode)

    def attribute(key: str, ncomps: tuple[int, ...]) -> np.ndarray:
        if draco is not None and key in draco[1]:
            arr = draco[1][key]
            if arr.shape[1] not in ncomps:
                raise SceneError(ld.path, f"mesh {name} {key}: Draco gives {arr.shape[1]} "
                                          f"components, expected {ncomps}")
            return arr
        return ld.attribute(attrs[key], ncomps, f"mesh {name} {key}")

    positions = attribute("POSITION", (3,))
    n = len(positions)

    def optional(key: str, ncomps: tuple[int, ...]) -> np.ndarray | None:
        if attrs.get(key) is None:
            return None
        arr = attribute(key, ncomps)
        if len(arr) != n:
            raise SceneError(ld.path, f"mesh {name}: {key} has {len(arr)} items, not {n}")
        return arr

    colors = optional("COLOR_0", (3, 4))
    if colors is not None and colors.shape[1] == 3:
        colors = np.concatenate([colors, np.ones((n, 1), np.float32)], axis=1)
    index_acc = get(prim, "indices")
    if draco is not None:
        indices = draco[0]
    elif index_acc is None:
        indices = np.arange(n, dtype=np.uint32)
    else:
        arr, _ = ld.accessor(index_acc)
        if arr.dtype.kind != "u" or arr.shape[1] != 1:
            raise SceneError(ld.path, f"mesh {name}: indices must be unsigned scalars")
        indices = arr.reshape(-1).astype(np.uint32)
        if len(indices) and int(indices.max()) >= n:
            raise SceneError(
                ld.path, f"mesh {name}: index {int(indices.max())} >= vertex count {n}"
            )
    if mode == 5:
        indices = strip_triangles(indices)
    elif mode == 6:
        indices = fan_triangles(indices)
    elif len(indices) % 3:
        raise SceneError(
            ld.path, f"mesh {name}: {len(indices)} indices is not a multiple of 3"
        )
    material = get(prim, "material", -1)
    if material != -1:
        material = check_index(ld.path, material, len(ld.gltf.materials or []), "material")
    mesh = Mesh(
        name=name,
        positions=positions,
        indices=indices,
        normals=optional("NORMAL", (3,)),
        texcoords=optional("TEXCOORD_0", (2,)),
        texcoords1=optional("TEXCOORD_1", (2,)),
        tangents=optional("TANGENT", (4,)),
        colors=colors,
        material=material,
        morph_targets=_morph_targets(ld, name, prim, attrs, n),
        morph_weights=_morph_weights(ld, mesh_index, prim),
    )
    if draco is None:  # Draco primitives keep their skin in the payload: not read (yet)
        mesh.joints, mesh.weights = _skin_attributes(ld, name, attrs, n)
    return normalize_mesh_arrays(ensure_normals(drop_nonfinite(mesh, ld.path)))


def _draco(ld: GltfDocument, name: str, prim: object, attrs: dict,
           mode: object) -> tuple[np.ndarray, dict[str, np.ndarray]] | None:
    """The decoded KHR_draco_mesh_compression of a primitive: (indices, attribute name ->
    float32 array) for the attributes the extension lists; None when the primitive has none,
    or when DracoPy is absent and the accessors keep uncompressed fallback data.

    Each decoded attribute must match its accessor's count and component count (the
    extension's rule); integer attributes are dequantised as the accessor says (normalized)."""
    info = ext(prim, "KHR_draco_mesh_compression")
    if not info:
        return None
    what = f"mesh {name}"
    package = missing_codec("KHR_draco_mesh_compression")
    if package is not None:
        accessors = ld.gltf.accessors or []
        used = [a for a in [*attrs.values(), get(prim, "indices")] if a is not None]
        if all(isinstance(a, int) and 0 <= a < len(accessors)
               and get(accessors[a], "bufferView") is not None for a in used):
            return None  # the uncompressed fallback
        raise SceneError(ld.path, f"{what} is KHR_draco_mesh_compression data without a "
                                  f"fallback; it needs the {package} package")
    if mode != 4:
        raise SceneError(ld.path, f"{what}: KHR_draco_mesh_compression with primitive mode "
                                  f"{mode!r} (only triangles are supported)")
    data, _ = ld.buffer_view(get(info, "bufferView"))
    faces, decoded = decode_draco(ld.path, what, data)
    ids = get(info, "attributes", {})
    if not isinstance(ids, dict):
        raise SceneError(ld.path, f"{what}: KHR_draco_mesh_compression attributes is not an object")
    out: dict[str, np.ndarray] = {}
    accessors = ld.gltf.accessors or []
    for key, uid in ids.items():
        if key not in attrs or attrs[key] is None:
            continue  # a Draco attribute the primitive does not use
        if isinstance(uid, bool) or not isinstance(uid, int) or uid not in decoded:
            raise SceneError(ld.path, f"{what}: Draco attribute id {uid!r} for {key} is not in "
                                      "the payload")
        arr = decoded[uid]
        acc = accessors[check_index(ld.path, attrs[key], len(accessors), f"{what} {key} accessor")]
        count = get(acc, "count")
        if count != len(arr):
            raise SceneError(ld.path, f"{what}: {key} accessor count {count!r} != {len(arr)} "
                                      "decoded Draco points")
        out[key] = to_float(arr, bool(get(acc, "normalized", False)))
    if "POSITION" not in out:
        raise SceneError(ld.path, f"{what}: KHR_draco_mesh_compression lacks POSITION")
    index_acc = get(prim, "indices")
    if index_acc is not None:
        acc = accessors[check_index(ld.path, index_acc, len(accessors), f"{what} indices")]
        if get(acc, "count") != len(faces):
            raise SceneError(ld.path, f"{what}: indices accessor count {get(acc, 'count')!r} != "
                                      f"{len(faces)} decoded Draco indices")
    return faces, out


def _skin_attributes(ld: GltfDocument, name: str, attrs: dict, n: int
                     ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """JOINTS_0/1 and WEIGHTS_0/1 as (n, 8) uint16 joints and (n, 8) float32 weights.

    Set 0 fills columns 0-3, set 1 columns 4-7 (zeros where absent; sets from 2 on are
    ignored). Weights are dequantised as `normalized` says, then each row is divided by its
    sum (the spec lets a loader renormalise); a row summing to 0 gets weight 1 on its first
    joint. Joints whose weight is 0 are set to 0, so that none of them can index past the
    skin's joint list. Negative or non-finite weights are errors."""
    sets = [k for k in (0, 1) if attrs.get(f"JOINTS_{k}") is not None]
    for k in (0, 1):
        if (attrs.get(f"JOINTS_{k}") is None) != (attrs.get(f"WEIGHTS_{k}") is None):
            raise SceneError(ld.path, f"mesh {name}: JOINTS_{k} and WEIGHTS_{k} come in pairs")
    if not sets:
        return None, None
    joints = np.zeros((n, 8), np.uint16)
    weights = np.zeros((n, 8), np.float32)
    for k in sets:
        arr, _ = ld.accessor(attrs[f"JOINTS_{k}"])
        if arr.dtype.kind != "u" or arr.dtype.itemsize > 2 or arr.shape[1] != 4:
            raise SceneError(ld.path, f"mesh {name}: JOINTS_{k} must be VEC4 unsigned byte or "
                                      "short")
        w = ld.attribute(attrs[f"WEIGHTS_{k}"], (4,), f"mesh {name} WEIGHTS_{k}")
        if len(arr) != n or len(w) != n:
            raise SceneError(ld.path, f"mesh {name}: JOINTS_{k}/WEIGHTS_{k} have {len(arr)}/"
                                      f"{len(w)} items, not {n}")
        joints[:, 4 * k:4 * k + 4] = arr
        weights[:, 4 * k:4 * k + 4] = w
    if not np.isfinite(weights).all() or (weights < 0).any():
        raise SceneError(ld.path, f"mesh {name}: skin weights must be finite and >= 0")
    total = weights.sum(axis=1, dtype=np.float64)
    empty = total <= 0
    weights[empty, 0] = 1.0
    total[empty] = 1.0
    weights = (weights / total[:, None]).astype(np.float32)
    joints[weights == 0] = 0
    return joints, weights


def _morph_targets(ld: GltfDocument, name: str, prim: object, attrs: dict,
                   n: int) -> dict[str, np.ndarray]:
    """The primitive's `targets` as {attribute: (T, n, 3) float32 displacements}.

    POSITION, NORMAL and TANGENT (xyz: targets do not move the handedness) are read where the
    primitive has the base attribute; a target that lacks an attribute another target gives
    displaces it by 0. Other morphed attributes (texture coordinates, colours) are ignored."""
    targets = get(prim, "targets")
    if not targets:
        return {}
    if not isinstance(targets, list) or not all(isinstance(t, dict) for t in targets):
        raise SceneError(ld.path, f"mesh {name}: targets must be a list of objects")
    if len(targets) > MAX_MORPH_TARGETS:
        raise SceneError(ld.path, f"mesh {name}: {len(targets)} morph targets, more than "
                                  f"vkpbr's budget of {MAX_MORPH_TARGETS}")
    out: dict[str, np.ndarray] = {}
    for key in _MORPHED:
        if attrs.get(key) is None or not any(t.get(key) is not None for t in targets):
            continue
        d = np.zeros((len(targets), n, 3), np.float32)
        for i, t in enumerate(targets):
            if t.get(key) is None:
                continue
            arr = ld.attribute(t[key], (3,), f"mesh {name} target {i} {key}")
            if len(arr) != n:
                raise SceneError(ld.path, f"mesh {name}: target {i} {key} has {len(arr)} items, "
                                          f"not {n}")
            d[i] = arr
        if not np.isfinite(d).all():
            raise SceneError(ld.path, f"mesh {name}: morph target {key} has non-finite values")
        out[key] = d
    return out


def _morph_weights(ld: GltfDocument, mesh_index: int, prim: object) -> np.ndarray | None:
    """The glTF mesh's default morph weights (T,), zeros when it gives none; None without
    targets. Its length must match the primitive's target count (as must every primitive's)."""
    targets = get(prim, "targets")
    if not targets:
        return None
    given = get(ld.doc["meshes"][mesh_index], "weights")  # pygltflib's default is []
    if given is None:
        return np.zeros(len(targets))
    if not isinstance(given, list) or len(given) != len(targets):
        raise SceneError(ld.path, f"mesh {mesh_index}: weights must be {len(targets)} numbers "
                                  "(one per morph target)")
    return np.asarray(floats(given, len(targets), (), f"mesh {mesh_index} weights", ld.path),
                      np.float64)
