# The non-geometry half of the glTF loader (split from gltf.py to keep files small): images,
# samplers, materials (metallic-roughness core + KHR_texture_transform +
# KHR_materials_emissive_strength), the node hierarchy flattened into world matrices, cameras
# and KHR_lights_punctual lights. Everything here walks small JSON lists (materials, nodes),
# never per-vertex data. Reference: glTF 2.0 spec 3.5 (nodes), 3.8-3.9 (materials, textures).

from __future__ import annotations

import math
import warnings
from typing import TYPE_CHECKING

import numpy as np

from vkpbr.errors import SceneError
from vkpbr.scene.types import Camera, Image, Light, Material, Node, Sampler, Scene, TextureRef

if TYPE_CHECKING:
    from vkpbr.scene.gltf import _Loader

__all__ = [
    "build_materials",
    "build_nodes_cameras_lights",
    "check_index",
    "ext",
    "get",
    "load_images",
    "trs_matrix",
]

_WRAP = {10497: "repeat", 33071: "clamp", 33648: "mirror"}
_FILTER = {9728: "nearest", 9729: "linear"}
# minFilter -> (filter within a level, uses mipmaps)
_MIN_FILTER = {
    9728: ("nearest", False),
    9729: ("linear", False),
    9984: ("nearest", True),
    9985: ("linear", True),
    9986: ("nearest", True),
    9987: ("linear", True),
}
_ALPHA = {"OPAQUE": "opaque", "MASK": "mask", "BLEND": "blend"}


def get(obj: object, key: str, default: object = None) -> object:
    """Field of a pygltflib object or of a plain dict (pygltflib keeps some parts as dicts)."""
    value = obj.get(key) if isinstance(obj, dict) else getattr(obj, key, None)
    return default if value is None else value


def check_index(path: object, value: object, count: int, what: str) -> int:
    """`value` as an index into a list of `count` items, or SceneError."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < count:
        raise SceneError(path, f"{what} {value!r} out of range (0..{count - 1})")
    return value


_get = get


def ext(obj: object, name: str) -> dict:
    """The `name` extension object of a glTF object, {} if absent or not an object."""
    exts = get(obj, "extensions", {})
    value = exts.get(name) if isinstance(exts, dict) else None
    return value if isinstance(value, dict) else {}


def _floats(value: object, n: int, default: tuple[float, ...], what: str, path: object) -> tuple:
    """`n` finite floats from a JSON list, or SceneError."""
    if value is None:
        return default
    try:
        arr = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise SceneError(path, f"{what}: not a list of numbers") from exc
    if arr.shape != (n,) or not np.isfinite(arr).all():
        raise SceneError(path, f"{what}: expected {n} finite numbers, got {value!r}")
    return tuple(float(x) for x in arr)


def _float(value: object, default: float, what: str, path: object) -> float:
    return _floats(None if value is None else [value], 1, (default,), what, path)[0]


# -- images and textures ---------------------------------------------------------------------


def load_images(ld: _Loader) -> list[Image]:
    """glTF images -> Image list (same indices); encoded bytes or paths, never decoded here."""
    images = []
    for i, img in enumerate(ld.gltf.images or []):
        uri, mime = _get(img, "uri"), _get(img, "mimeType")
        if uri is not None:
            uri = str(uri)
            if uri.startswith("data:"):
                images.append(Image(name=f"image {i}", data=ld.read_uri(uri, f"image {i}"),
                                    mime_type=mime))  # fmt: skip
                continue
            file = ld.resolve_uri(uri)
            if not file.is_file():
                # Not fatal: textures.decode_images warns again and the renderer substitutes
                # a default texture, so a model with one missing texture still renders.
                warnings.warn(f"{ld.path}: image file {file.name} not found", stacklevel=4)
            images.append(Image(name=uri, path=file, mime_type=mime))
        elif _get(img, "bufferView") is not None:
            data, _ = ld.buffer_view(_get(img, "bufferView"))
            images.append(Image(name=f"image {i}", data=bytes(data), mime_type=mime))
        else:
            raise SceneError(ld.path, f"image {i} has neither uri nor bufferView")
    return images


def _sampler(ld: _Loader, index: object) -> Sampler:
    if index is None:
        return Sampler()
    samplers = ld.gltf.samplers or []
    s = samplers[check_index(ld.path, index, len(samplers), "sampler")]
    min_filter, mipmaps = _MIN_FILTER.get(_get(s, "minFilter"), ("linear", True))
    return Sampler(
        wrap_s=_WRAP.get(_get(s, "wrapS"), "repeat"),
        wrap_t=_WRAP.get(_get(s, "wrapT"), "repeat"),
        mag_filter=_FILTER.get(_get(s, "magFilter"), "linear"),
        min_filter=min_filter,
        mipmaps=mipmaps,
    )


def _texture_ref(ld: _Loader, info: object, n_images: int, channel: int = 0) -> TextureRef | None:
    """A textureInfo -> TextureRef (with KHR_texture_transform), None if absent or unusable."""
    if info is None:
        return None
    textures = ld.gltf.textures or []
    tex = textures[check_index(ld.path, _get(info, "index"), len(textures), "texture")]
    source = _get(tex, "source")
    if source is None:
        # e.g. only KHR_texture_basisu / EXT_texture_webp sources: render without the map.
        warnings.warn(f"{ld.path}: texture without a core image source ignored", stacklevel=5)
        return None
    image = check_index(ld.path, source, n_images, "image")
    texcoord = _get(info, "texCoord", 0)
    xf = ext(info, "KHR_texture_transform")
    texcoord = _get(xf, "texCoord", texcoord)
    if texcoord not in (0, 1):
        raise SceneError(ld.path, f"texCoord {texcoord!r} not supported (only 0 and 1)")
    return TextureRef(
        image=image,
        sampler=_sampler(ld, _get(tex, "sampler")),
        channel=channel,
        texcoord=texcoord,
        offset=_floats(_get(xf, "offset"), 2, (0.0, 0.0), "texture offset", ld.path),
        rotation=_float(_get(xf, "rotation"), 0.0, "texture rotation", ld.path),
        scale=_floats(_get(xf, "scale"), 2, (1.0, 1.0), "texture scale", ld.path),
    )


def build_materials(ld: _Loader, n_images: int) -> list[Material]:
    """glTF materials -> Material list (same indices)."""
    out = []
    p = ld.path
    for i, m in enumerate(ld.gltf.materials or []):
        if m is None:
            raise SceneError(p, f"material {i} is null")
        pbr = _get(m, "pbrMetallicRoughness", {})
        emissive = _floats(_get(m, "emissiveFactor"), 3, (0.0, 0.0, 0.0), "emissiveFactor", p)
        strength = _float(_get(ext(m, "KHR_materials_emissive_strength"),
                               "emissiveStrength"), 1.0, "emissiveStrength", p)  # fmt: skip
        mr = _get(pbr, "metallicRoughnessTexture")
        normal, occlusion = _get(m, "normalTexture"), _get(m, "occlusionTexture")
        alpha_mode = _get(m, "alphaMode", "OPAQUE")
        if alpha_mode not in _ALPHA:
            raise SceneError(p, f"material {i}: unknown alphaMode {alpha_mode!r}")
        out.append(
            Material(
                name=str(_get(m, "name", f"material {i}")),
                base_color_factor=_floats(
                    _get(pbr, "baseColorFactor"), 4, (1.0,) * 4, "baseColorFactor", p
                ),  # fmt: skip
                metallic_factor=_float(_get(pbr, "metallicFactor"), 1.0, "metallicFactor", p),
                roughness_factor=_float(_get(pbr, "roughnessFactor"), 1.0, "roughnessFactor", p),
                emissive_factor=tuple(e * strength for e in emissive),
                normal_scale=_float(_get(normal, "scale") if normal else None, 1.0, "scale", p),
                occlusion_strength=_float(
                    _get(occlusion, "strength") if occlusion else None, 1.0, "strength", p
                ),  # fmt: skip
                alpha_mode=_ALPHA[alpha_mode],
                alpha_cutoff=_float(_get(m, "alphaCutoff"), 0.5, "alphaCutoff", p),
                double_sided=bool(_get(m, "doubleSided", False)),
                base_color_texture=_texture_ref(ld, _get(pbr, "baseColorTexture"), n_images),
                # The packed texture: B = metalness, G = roughness (glTF spec 3.9.2).
                metallic_texture=_texture_ref(ld, mr, n_images, channel=2),
                roughness_texture=_texture_ref(ld, mr, n_images, channel=1),
                normal_texture=_texture_ref(ld, normal, n_images),
                occlusion_texture=_texture_ref(ld, occlusion, n_images),
                emissive_texture=_texture_ref(ld, _get(m, "emissiveTexture"), n_images),
            )
        )
    return out


# -- nodes, cameras, lights ------------------------------------------------------------------


def trs_matrix(t: tuple, r: tuple, s: tuple) -> np.ndarray:
    """T * R * S as a (4, 4) float64 matrix; r is a quaternion (x, y, z, w), renormalised."""
    x, y, z, w = r
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = (x / norm, y / norm, z / norm, w / norm) if norm > 1e-12 else (0, 0, 0, 1)
    rot = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    m = np.eye(4)
    m[:3, :3] = rot * np.asarray(s)  # scales columns: R @ diag(s)
    m[:3, 3] = t
    return m


def _local_matrix(ld: _Loader, i: int, node: object) -> np.ndarray:
    matrix = _get(node, "matrix")
    if matrix is not None and len(matrix) and list(matrix) != [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]:  # fmt: skip
        # glTF stores matrices column-major; numpy reshape is row-major, hence .T
        return np.asarray(_floats(matrix, 16, (), f"node {i} matrix", ld.path)).reshape(4, 4).T
    return trs_matrix(
        _floats(_get(node, "translation"), 3, (0.0, 0.0, 0.0), f"node {i} translation", ld.path),
        _floats(_get(node, "rotation"), 4, (0.0, 0.0, 0.0, 1.0), f"node {i} rotation", ld.path),
        _floats(_get(node, "scale"), 3, (1.0, 1.0, 1.0), f"node {i} scale", ld.path),
    )


def _root_nodes(ld: _Loader, n_nodes: int) -> list[object]:
    scenes = ld.gltf.scenes or []
    if scenes:
        chosen = _get(ld.doc, "scene", 0)
        return list(_get(scenes[check_index(ld.path, chosen, len(scenes), "scene")], "nodes", []))
    children = {c for n in ld.gltf.nodes or [] for c in (_get(n, "children", []) or [])}
    return [i for i in range(n_nodes) if i not in children]


def build_nodes_cameras_lights(ld: _Loader, scene: Scene) -> None:
    """Walk the displayed scene's node tree: fill scene.meshes/nodes/cameras/lights."""
    nodes = ld.gltf.nodes or []
    meshes = ld.gltf.meshes or []
    cameras = ld.gltf.cameras or []
    light_defs = ext(ld.doc, "KHR_lights_punctual").get("lights") or []
    mesh_prims: dict[int, list[int]] = {}  # glTF mesh -> indices of its primitives in scene.meshes
    pending_lights: list[tuple[dict, np.ndarray]] = []
    stack = [
        (check_index(ld.path, r, len(nodes), "root node"), np.eye(4))
        for r in _root_nodes(ld, len(nodes))
    ][::-1]  # reversed: the stack pops them in document order (nodes, lights keep file order)
    seen: set[int] = set()
    while stack:
        i, parent = stack.pop()
        if i in seen:
            raise SceneError(ld.path, f"node {i} is reached twice (cycle or shared child)")
        seen.add(i)
        node = nodes[i]
        world = parent @ _local_matrix(ld, i, node)
        name = str(_get(node, "name", f"node {i}"))
        for c in list(_get(node, "children", []) or [])[::-1]:
            stack.append((check_index(ld.path, c, len(nodes), f"node {i} child"), world))
        if _get(node, "mesh") is not None:
            m = check_index(ld.path, _get(node, "mesh"), len(meshes), f"node {i} mesh")
            if m not in mesh_prims:
                mesh_prims[m] = []
                for k, prim in enumerate(_get(meshes[m], "primitives", [])):
                    mesh_prims[m].append(len(scene.meshes))
                    scene.meshes.append(ld.primitive(m, k, prim))
            w32 = world.astype(np.float32)
            scene.nodes += [Node(mesh=j, matrix=w32.copy(), name=name) for j in mesh_prims[m]]
        if _get(node, "camera") is not None:
            cam = cameras[check_index(ld.path, _get(node, "camera"), len(cameras), "camera")]
            _add_camera(ld, scene, cam, world, name)
        ext_light = ext(node, "KHR_lights_punctual").get("light")
        if ext_light is not None:
            light = light_defs[check_index(ld.path, ext_light, len(light_defs), "light")]
            pending_lights.append((light, world))
    for light, world in pending_lights:  # after all meshes: directional lights need the bounds
        scene.lights.append(_light(ld, scene, light, world))
    _finish_cameras(scene)


def _add_camera(ld: _Loader, scene: Scene, cam: object, world: np.ndarray, name: str) -> None:
    if _get(cam, "type") != "perspective" or _get(cam, "perspective") is None:
        warnings.warn(f"{ld.path}: {_get(cam, 'type')} camera {name!r} ignored", stacklevel=5)
        return
    persp = _get(cam, "perspective")
    yfov = _float(_get(persp, "yfov"), 0.8, "camera yfov", ld.path)
    znear = _float(_get(persp, "znear"), 0.1, "camera znear", ld.path)
    zfar = _get(persp, "zfar")
    if not (0 < yfov < math.pi) or znear <= 0:
        raise SceneError(ld.path, f"camera {name!r}: bad yfov/znear {yfov}/{znear}")
    eye = world[:3, 3]
    forward = -world[:3, 2] / max(np.linalg.norm(world[:3, 2]), 1e-12)  # cameras look down -Z
    up = world[:3, 1] / max(np.linalg.norm(world[:3, 1]), 1e-12)
    scene.cameras.append(
        Camera(
            eye=tuple(map(float, eye)),
            target=tuple(map(float, eye + forward)),
            up=tuple(map(float, up)),
            yfov_deg=math.degrees(yfov),
            znear=znear,
            # zfar absent = infinite projection; -1 marks it until the scene size is known.
            zfar=_float(zfar, -1.0, "camera zfar", ld.path) if zfar is not None else -1.0,
            name=name,
        )
    )


def _finish_cameras(scene: Scene) -> None:
    """Give infinite cameras a finite zfar: beyond the farthest scene corner, >= 1000 znear."""
    lo, hi = scene.bounds()
    for cam in scene.cameras:
        if cam.zfar <= cam.znear:
            corners = np.stack([lo, hi])
            far = float(np.linalg.norm(corners - np.asarray(cam.eye), axis=1).max())
            cam.zfar = max(1000.0 * cam.znear, 2.0 * far)


def _light(ld: _Loader, scene: Scene, light: dict, world: np.ndarray) -> Light:
    """KHR_lights_punctual -> point Light; spot and directional are approximated (warned)."""
    kind = _get(light, "type", "point")
    color = _floats(_get(light, "color"), 3, (1.0, 1.0, 1.0), "light color", ld.path)
    intensity = _float(_get(light, "intensity"), 1.0, "light intensity", ld.path)
    light_range = _float(_get(light, "range"), 0.0, "light range", ld.path)
    position = world[:3, 3]
    if kind == "spot":
        warnings.warn(f"{ld.path}: spot light approximated by a point light", stacklevel=4)
    elif kind == "directional":
        # Sun -> a far point light along -direction: at distance d an inverse-square light of
        # intensity lux * d^2 (cd) gives the same illuminance lux at the scene's centre.
        lo, hi = scene.bounds()
        centre = (lo + hi) / 2
        d = 10.0 * max(float(np.linalg.norm(hi - lo)), 1.0)
        direction = -world[:3, 2] / max(np.linalg.norm(world[:3, 2]), 1e-12)
        position = centre - direction * d
        intensity *= d * d
        light_range = 0.0
        warnings.warn(
            f"{ld.path}: directional light approximated by a far point light", stacklevel=4
        )
    elif kind != "point":
        raise SceneError(ld.path, f"unknown light type {kind!r}")
    return Light(
        position=tuple(map(float, position)),
        color=color,
        intensity=intensity,
        falloff="inverse_square",
        range=light_range,
    )
