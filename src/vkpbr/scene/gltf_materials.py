# glTF images, samplers, textures and materials -> Image, Sampler, TextureRef, Material:
# the metallic-roughness core, KHR_texture_transform, KHR_materials_emissive_strength, _unlit,
# _ior, _specular, _clearcoat, _sheen, _transmission and _volume (factors and textures), and
# KHR_materials_variants (`apply_variant`: the chosen variant's materials replace the
# primitives' before the meshes are built).
# Images stay encoded (decoding is textures.py's job, in parallel); a missing image file is
# not an error here (load_scene reports all of them in one line). Reference: glTF 2.0 spec
# 3.8 (textures, images, samplers), 3.9 (materials).

from __future__ import annotations

import warnings

from vkpbr.errors import SceneError
from vkpbr.scene.gltf_document import GltfDocument, check_index, ext, floats, get, scalar
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
# The material extensions read here (for the loader's list of supported extensions).
MATERIAL_EXTENSIONS = (
    "KHR_materials_emissive_strength", "KHR_materials_unlit", "KHR_materials_variants",
    "KHR_materials_ior", "KHR_materials_specular", "KHR_materials_clearcoat",
    "KHR_materials_sheen", "KHR_materials_transmission", "KHR_materials_volume",
)
# Each extension's textures: (extension, glTF key, Material slot, channel of a scalar map).
_EXTENSION_TEXTURES = (
    ("KHR_materials_clearcoat", "clearcoatTexture", "clearcoat", 0),
    ("KHR_materials_clearcoat", "clearcoatRoughnessTexture", "clearcoat_roughness", 1),
    ("KHR_materials_clearcoat", "clearcoatNormalTexture", "clearcoat_normal", 0),
    ("KHR_materials_sheen", "sheenColorTexture", "sheen_color", 0),
    ("KHR_materials_sheen", "sheenRoughnessTexture", "sheen_roughness", 3),
    ("KHR_materials_specular", "specularTexture", "specular", 3),
    ("KHR_materials_specular", "specularColorTexture", "specular_color", 0),
    ("KHR_materials_transmission", "transmissionTexture", "transmission", 0),
    ("KHR_materials_volume", "thicknessTexture", "thickness", 1),
)


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
    for i, m in enumerate(ld.gltf.materials or []):
        if m is None:
            raise SceneError(p, f"material {i} is null")
        pbr = get(m, "pbrMetallicRoughness", {})
        emissive = floats(get(m, "emissiveFactor"), 3, (0.0, 0.0, 0.0), "emissiveFactor", p)
        strength = scalar(get(ext(m, "KHR_materials_emissive_strength"),
                               "emissiveStrength"), 1.0, "emissiveStrength", p)  # fmt: skip
        mr = get(pbr, "metallicRoughnessTexture")
        normal, occlusion = get(m, "normalTexture"), get(m, "occlusionTexture")
        alpha_mode = get(m, "alphaMode", "OPAQUE")
        if alpha_mode not in _ALPHA:
            raise SceneError(p, f"material {i}: unknown alphaMode {alpha_mode!r}")
        out.append(
            Material(
                **_extension_factors(ld, i, m),
                name=str(get(m, "name", f"material {i}")),
                base_color_factor=floats(
                    get(pbr, "baseColorFactor"), 4, (1.0,) * 4, "baseColorFactor", p
                ),  # fmt: skip
                metallic_factor=scalar(get(pbr, "metallicFactor"), 1.0, "metallicFactor", p),
                roughness_factor=scalar(get(pbr, "roughnessFactor"), 1.0, "roughnessFactor", p),
                emissive_factor=tuple(e * strength for e in emissive),
                normal_scale=scalar(get(normal, "scale") if normal else None, 1.0, "scale", p),
                occlusion_strength=scalar(
                    get(occlusion, "strength") if occlusion else None, 1.0, "strength", p
                ),  # fmt: skip
                alpha_mode=_ALPHA[alpha_mode],
                alpha_cutoff=scalar(get(m, "alphaCutoff"), 0.5, "alphaCutoff", p),
                double_sided=bool(get(m, "doubleSided", False)),
                base_color_texture=_texture_ref(ld, get(pbr, "baseColorTexture"), n_images),
                # The packed texture: B = metalness, G = roughness (glTF spec 3.9.2).
                metallic_texture=_texture_ref(ld, mr, n_images, channel=2),
                roughness_texture=_texture_ref(ld, mr, n_images, channel=1),
                normal_texture=_texture_ref(ld, normal, n_images),
                occlusion_texture=_texture_ref(ld, occlusion, n_images),
                emissive_texture=_texture_ref(ld, get(m, "emissiveTexture"), n_images),
            )
        )
    return out


def _unit(value: object, default: float, what: str, path: object, lo: float = 0.0,
          hi: float = 1.0) -> float:
    """A scalar factor that the extension's schema bounds to [lo, hi] (a SceneError outside)."""
    x = scalar(value, default, what, path)
    if not lo <= x <= hi:
        raise SceneError(path, f"{what} {x!r} outside {lo:g}..{hi:g}")
    return x


def _color(value: object, default: tuple, what: str, path: object,
           hi: float = 1.0) -> tuple[float, float, float]:
    rgb = floats(value, 3, default, what, path)
    if not all(0.0 <= c <= hi for c in rgb):
        raise SceneError(path, f"{what} {list(rgb)} outside 0..{hi:g}")
    return rgb


def _extension_factors(ld: GltfDocument, i: int, m: object) -> dict[str, object]:
    """The Material fields of material `i`'s KHR_materials_* extensions (defaults when absent)."""
    p = ld.path
    where = f"material {i}"
    n_images = len(ld.gltf.images or [])
    textures = {f"{slot}_texture": _texture_ref(ld, get(ext(m, name), key), n_images, channel)
                for name, key, slot, channel in _EXTENSION_TEXTURES}
    coat_normal = get(ext(m, "KHR_materials_clearcoat"), "clearcoatNormalTexture")
    spec = ext(m, "KHR_materials_specular")
    coat = ext(m, "KHR_materials_clearcoat")
    sheen = ext(m, "KHR_materials_sheen")
    volume = ext(m, "KHR_materials_volume")
    ior = scalar(get(ext(m, "KHR_materials_ior"), "ior"), 1.5, "ior", p)
    if ior == 0.0:
        ior = 1.0e6  # the schema's special value: a dielectric of maximal reflectance (F0 -> 1)
    if not 1.0 <= ior <= 1.0e6:
        raise SceneError(p, f"{where}: ior {ior!r} is below 1")
    distance = scalar(get(volume, "attenuationDistance"), 0.0, "attenuationDistance", p)
    if distance < 0.0 or (get(volume, "attenuationDistance") is not None and distance == 0.0):
        raise SceneError(p, f"{where}: attenuationDistance {distance!r} must be > 0")
    unlit = isinstance(get(get(m, "extensions", {}), "KHR_materials_unlit"), dict)
    return {
        **textures,
        "clearcoat_normal_scale": scalar(get(coat_normal, "scale") if coat_normal else None,
                                         1.0, "clearcoatNormalTexture scale", p),
        "unlit": unlit,
        "ior": ior,
        "specular_factor": _unit(get(spec, "specularFactor"), 1.0, "specularFactor", p),
        # specularColorFactor may exceed 1 (F0 is clamped to 1 where it is used).
        "specular_color_factor": _color(get(spec, "specularColorFactor"), (1.0, 1.0, 1.0),
                                        "specularColorFactor", p, hi=1e6),
        "clearcoat_factor": _unit(get(coat, "clearcoatFactor"), 0.0, "clearcoatFactor", p),
        "clearcoat_roughness_factor": _unit(get(coat, "clearcoatRoughnessFactor"), 0.0,
                                            "clearcoatRoughnessFactor", p),
        "sheen_color_factor": _color(get(sheen, "sheenColorFactor"), (0.0, 0.0, 0.0),
                                     "sheenColorFactor", p),
        "sheen_roughness_factor": _unit(get(sheen, "sheenRoughnessFactor"), 0.0,
                                        "sheenRoughnessFactor", p),
        "transmission_factor": _unit(get(ext(m, "KHR_materials_transmission"),
                                         "transmissionFactor"), 0.0, "transmissionFactor", p),
        "thickness_factor": _unit(get(volume, "thicknessFactor"), 0.0, "thicknessFactor", p,
                                  hi=1e6),
        "attenuation_distance": distance,
        "attenuation_color": _color(get(volume, "attenuationColor"), (1.0, 1.0, 1.0),
                                    "attenuationColor", p),
    }


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
