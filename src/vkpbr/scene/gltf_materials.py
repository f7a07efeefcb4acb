# glTF images, samplers, textures and materials -> Image, Sampler, TextureRef, Material:
# the metallic-roughness core, KHR_texture_transform, KHR_materials_emissive_strength, _unlit,
# _ior, _specular, _clearcoat, _sheen, _transmission and _volume (factors and textures),
# KHR_materials_pbrSpecularGlossiness (converted: `_specular_glossiness`), and
# KHR_materials_variants (`apply_variant`: the chosen variant's materials replace the
# primitives' before the meshes are built).
# Images stay encoded (decoding is textures.py's job, in parallel); a missing image file is
# not an error here (load_scene reports all of them in one line). Reference: glTF 2.0 spec
# 3.8 (textures, images, samplers), 3.9 (materials). Which property fills which Material field,
# its default and its range: scene/material_table.py (a row per parameter and texture slot).

from __future__ import annotations

import warnings

from vkpbr.errors import SceneError
from vkpbr.scene.gltf_document import GltfDocument, check_index, ext, floats, get, scalar
from vkpbr.scene.limits import limits
from vkpbr.scene.material_table import EXTENSIONS, PARAMS, TEXTURES, MaterialParam
from vkpbr.scene.resources import ResourceRefused
from vkpbr.scene.types import Image, Material, Sampler, TextureRef

__all__ = ["apply_variant", "build_materials", "load_images", "MATERIAL_EXTENSIONS"]

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
_PROPERTY = {prm.name: prm.gltf_property for prm in PARAMS}  # messages' names, computed once
# The material extensions read here (for the loader's list of supported extensions).
MATERIAL_EXTENSIONS = EXTENSIONS


def load_images(ld: GltfDocument) -> list[Image]:
    """glTF images -> Image list (same indices); encoded bytes or paths, never decoded here."""
    images = []
    for i, img in enumerate(ld.gltf.images or []):
        uri, mime = get(img, "uri"), get(img, "mimeType")
        if uri is not None:
            uri = str(uri)
            if uri.startswith("data:"):
                images.append(Image(name=f"image {i}", data=ld.read_uri(uri, f"image {i}"),
                                    mime_type=mime))  # fmt: skip
                continue
            # A missing file is not an error here: load_scene reports every missing texture
            # in one line (or raises with strict), and the renderer binds a default.
            images.append(policy_image(ld, uri, mime))
        elif get(img, "bufferView") is not None:
            data, _ = ld.buffer_view(get(img, "bufferView"))
            images.append(Image(name=f"image {i}", data=bytes(data), mime_type=mime))
        else:
            raise SceneError(ld.path, f"image {i} has neither uri nor bufferView")
    return images


def policy_image(ld: GltfDocument, uri: str, mime: object) -> Image:
    """The Image of a file URI; one the path policy refuses keeps its name and the reason
    (`Image.refused`), and is then reported and replaced like a missing file."""
    try:
        return Image(name=uri, path=ld.resolve_uri(uri, "image"), mime_type=mime)
    except ResourceRefused as exc:
        return Image(name=uri, path=exc.file, mime_type=mime, refused=exc.reason)


def _sampler(ld: GltfDocument, index: object) -> Sampler:
    if index is None:
        return Sampler()
    samplers = ld.gltf.samplers or []
    s = samplers[check_index(ld.path, index, len(samplers), "sampler")]
    min_filter, mipmaps = _MIN_FILTER.get(get(s, "minFilter"), ("linear", True))
    return Sampler(
        wrap_s=_WRAP.get(get(s, "wrapS"), "repeat"),
        wrap_t=_WRAP.get(get(s, "wrapT"), "repeat"),
        mag_filter=_FILTER.get(get(s, "magFilter"), "linear"),
        min_filter=min_filter,
        mipmaps=mipmaps,
    )


def _texture_ref(ld: GltfDocument, info: object, n_images: int, channel: int = 0) -> TextureRef | None:
    """A textureInfo -> TextureRef (with KHR_texture_transform), None if absent or unusable."""
    if info is None:
        return None
    textures = ld.gltf.textures or []
    tex = textures[check_index(ld.path, get(info, "index"), len(textures), "texture")]
    source = get(tex, "source")
    if source is None:
        # e.g. only KHR_texture_basisu / EXT_texture_webp sources: render without the map.
        warnings.warn(f"{ld.path}: texture without a core image source ignored", stacklevel=5)
        return None
    image = check_index(ld.path, source, n_images, "image")
    texcoord = get(info, "texCoord", 0)
    xf = ext(info, "KHR_texture_transform")
    texcoord = get(xf, "texCoord", texcoord)
    if texcoord not in (0, 1):
        raise SceneError(ld.path, f"texCoord {texcoord!r} not supported (only 0 and 1)")
    return TextureRef(
        image=image,
        sampler=_sampler(ld, get(tex, "sampler")),
        channel=channel,
        texcoord=texcoord,
        offset=floats(get(xf, "offset"), 2, (0.0, 0.0), "texture offset", ld.path),
        rotation=scalar(get(xf, "rotation"), 0.0, "texture rotation", ld.path),
        scale=floats(get(xf, "scale"), 2, (1.0, 1.0), "texture scale", ld.path),
    )


def build_materials(ld: GltfDocument, n_images: int) -> list[Material]:
    """glTF materials -> Material list (same indices)."""
    out = []
    p = ld.path
    cap = limits().max_materials
    if len(ld.gltf.materials) > cap:  # before ~60 us of reading each
        raise SceneError(p, f"{len(ld.gltf.materials):,} materials are over the limit of "
                            f"{cap:,} (VKPBR_MAX_MATERIALS)")
    for i, m in enumerate(ld.gltf.materials or []):
        alpha_mode = get(m, "alphaMode", "OPAQUE")
        if alpha_mode not in _ALPHA:
            raise SceneError(p, f"material {i}: unknown alphaMode {alpha_mode!r}")
        fields = {
            **{prm.name: _parameter(ld, i, m, prm) for prm in PARAMS},
            **{f"{slot.name}_texture": _texture_ref(ld, _find(m, slot.gltf), n_images, slot.channel)
               for slot in TEXTURES if slot.gltf is not None},
        }
        extensions = get(m, "extensions", {})
        if isinstance(get(extensions, _SG), dict):
            fields.update(_specular_glossiness(ld, i, get(extensions, _SG), n_images))
        out.append(
            Material(
                name=str(get(m, "name", f"material {i}")),
                alpha_mode=_ALPHA[alpha_mode],
                double_sided=bool(get(m, "doubleSided", False)),
                unlit=isinstance(get(extensions, "KHR_materials_unlit"), dict),
                **fields,
            )
        )
    return out


_SG = "KHR_materials_pbrSpecularGlossiness"
# The dielectric F0 of ior 1.5 (the core's, ((1.5 - 1) / (1.5 + 1))^2): the specular colour
# factor that makes vkpbr's dielectric F0 (shade.glsl dielectric_f0) a given specular colour.
_F0_IOR_1_5 = 0.04


def _sg_factor(ld: GltfDocument, i: int, sg: dict, name: str, default: tuple) -> tuple:
    """One of the extension's factors: finite, each component in [0, 1] (its schema)."""
    what = f"material {i}: {name}"
    value = floats(get(sg, name), len(default), default, what, ld.path)
    if not all(0.0 <= x <= 1.0 for x in value):
        shown = list(value) if len(value) > 1 else value[0]
        raise SceneError(ld.path, f"{what} {shown!r} outside 0..1")
    return value


def _specular_glossiness(ld: GltfDocument, i: int, sg: dict, n_images: int) -> dict:
    """Material `i`'s KHR_materials_pbrSpecularGlossiness (archived by Khronos) as Material
    fields, replacing the metallic-roughness fallback the file may also hold.

    As the glTF Sample Viewer shades it (material_info.glsl getSpecularGlossinessInfo and
    getBaseColor): a dielectric (metallic 0) whose base colour is diffuseFactor x
    diffuseTexture, whose F0 is specularFactor x the specularGlossinessTexture's RGB (sRGB),
    and whose perceptual roughness is 1 - glossinessFactor x its A (linear). F0 goes through
    KHR_materials_specular's colour at ior 1.5 (F0 = 0.04 x specular colour: the colour is
    specular / 0.04, its texture the same RGB); roughness_factor and roughness_texture hold
    the glossiness, which the `glossiness` switch inverts in the shader (shade.glsl): 1 - g x
    texel is no product of a factor and a texel."""
    diffuse = _sg_factor(ld, i, sg, "diffuseFactor", (1.0, 1.0, 1.0, 1.0))
    specular = _sg_factor(ld, i, sg, "specularFactor", (1.0, 1.0, 1.0))
    (glossiness,) = _sg_factor(ld, i, sg, "glossinessFactor", (1.0,))
    sg_texture = get(sg, "specularGlossinessTexture")
    return {
        "base_color_factor": diffuse,
        "base_color_texture": _texture_ref(ld, get(sg, "diffuseTexture"), n_images),
        "metallic_factor": 0.0, "metallic_texture": None,
        "roughness_factor": glossiness,
        "roughness_texture": _texture_ref(ld, sg_texture, n_images, channel=3),
        "ior": 1.5, "specular_factor": 1.0, "specular_texture": None,
        "specular_color_factor": tuple(x / _F0_IOR_1_5 for x in specular),
        "specular_color_texture": _texture_ref(ld, sg_texture, n_images),
        "glossiness": True,
    }


def _find(m: object, path: str) -> object:
    """The value at a material_table path in material `m`: a KHR_* part is the extension
    object (`ext`: {} when absent or not an object), the others plain keys; None if absent."""
    obj = m
    for key in path.split("."):
        obj = ext(obj, key) if key.startswith("KHR_") else get(obj, key)
    return obj


def _parameter(ld: GltfDocument, i: int, m: object, prm: MaterialParam) -> object:
    """Material `i`'s value of one table row: the file's (the schema's default when absent),
    finite and within the row's range, or a one-line SceneError naming the property."""
    what = f"material {i}: {_PROPERTY[prm.name]}"
    raw = _find(m, prm.gltf)
    default = prm.default if isinstance(prm.default, tuple) else (prm.default,)
    # A scalar is read as a list of one (gltf_document.scalar's way): one path for both.
    listed = raw if raw is None or isinstance(prm.default, tuple) else [raw]
    value = floats(listed, prm.size, default, what, ld.path)
    if prm.gltf_zero is not None and value == (0.0,):
        value = (prm.gltf_zero,)
    if prm.gltf_above_lo and raw is not None and min(value) <= prm.lo:
        raise SceneError(ld.path, f"{what} {value[0]!r} must be > {prm.lo:g}")
    if prm.gltf_scale is not None:
        scale = scalar(_find(m, prm.gltf_scale), 1.0, prm.gltf_scale.split(".")[-1], ld.path)
        value = tuple(x * scale for x in value)
    result = value[0] if prm.size == 1 else value
    problem = prm.problem(result)
    if problem is not None:
        raise SceneError(ld.path, f"{what} {problem}")
    return result


def variant_names(ld: GltfDocument) -> list[str]:
    """KHR_materials_variants' variant names, in file order."""
    variants = get(ext(ld.doc, "KHR_materials_variants"), "variants", [])
    if not isinstance(variants, list):
        raise SceneError(ld.path, "KHR_materials_variants.variants is not a list")
    return [str(get(v, "name", f"variant {k}")) if isinstance(v, dict) else f"variant {k}"
            for k, v in enumerate(variants)]


def apply_variant(ld: GltfDocument, variant: str | None) -> list[str]:
    """Select KHR_materials_variants' `variant` (by name): every primitive that maps it gets
    the mapped material, in the parsed document, before the meshes are built. Returns the
    file's variant names. None: the file's default materials. An unknown name is a
    SceneError listing the file's variants."""
    names = variant_names(ld)
    if variant is None:
        return names
    if variant not in names:
        listed = ", ".join(repr(n) for n in names) if names else "none"
        raise SceneError(ld.path, f"no material variant {variant!r} (the file's: {listed})")
    index = names.index(variant)
    n_materials = len(ld.gltf.materials or [])
    for mi, mesh in enumerate(ld.gltf.meshes or []):
        for k, prim in enumerate(get(mesh, "primitives", []) or []):
            mappings = get(get(get(prim, "extensions", {}), "KHR_materials_variants", {}),
                           "mappings", [])
            if not isinstance(mappings, list):
                raise SceneError(ld.path, f"mesh {mi} primitive {k}: variant mappings is not a list")
            for mapping in mappings:
                if not isinstance(get(mapping, "variants", []), list):
                    raise SceneError(ld.path, f"mesh {mi} primitive {k}: mapping variants is not a list")
                if index in get(mapping, "variants", []):
                    material = check_index(ld.path, get(mapping, "material"), n_materials,
                                           f"mesh {mi} primitive {k} variant material")
                    if isinstance(prim, dict):
                        prim["material"] = material
                    else:
                        prim.material = material
                    break
    return names
