"""The material parameters: one row each, one name from the glTF file to the shader.

A row says where the parameter is in a glTF material (the extension and the property), its
`Material` field (scene/types.py), its default (the glTF schema's: the value of an absent
property), the range vkpbr accepts, the texture slot whose texel multiplies it (the slot row
gives the channel), and so its member of the GPU material block (render/layouts.py MATERIAL:
the field's name, a float or vec3/vec4 by the default's length). Derived from the rows:
Material's defaults, the glTF reader (scene/gltf_materials.py), validation
(scene/validate.py), the GPU block's members and packing (render/layouts.py,
render/gpu_scene.py) and generated.glsl's MATERIAL_DEFAULT_* (render/codegen.py). The BRDF
that reads the block (shaders/brdf.glsl, shade.glsl `material_layers`) and its NumPy mirror
(reference/brdf.py) stay hand-written.

Not rows: the switches, which pick pipelines and flag bits rather than values (alpha_mode,
double_sided, unlit, casts_shadows: types.py and gpu_scene.py), and each texture's sampler
and KHR_texture_transform (TextureRef).

References: glTF 2.0 specification 3.9 (materials) and its JSON schema (material.schema.json,
material.pbrMetallicRoughness, material.normalTextureInfo, material.occlusionTextureInfo);
the KHR_materials_ior, _specular, _clearcoat, _sheen, _transmission, _volume and
_emissive_strength specifications (Khronos glTF repository, extensions/2.0/Khronos).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Literal

__all__ = ["DEFAULTS", "EXTENSIONS", "LAYER_PARAMS", "PARAMS", "TEXTURES", "MaterialParam",
           "TextureSlot"]

Value = float | tuple[float, ...]  # a scalar, or a vector's components

# Wide bounds where the schema sets none (or where files in the wild exceed its [0, 1]): what
# float32 uniforms and the shading hold. vkpbr accepted these before the table; kept so.
_WIDE = 1e6


def _extension(path: str | None) -> str | None:
    """The extension a dotted glTF path starts in, None for the core material's."""
    head = (path or "").split(".", 1)[0]
    return head if head.startswith("KHR_") else None


@dataclass(frozen=True)
class TextureSlot:
    """One material texture: the Material field f"{name}_texture", GLSL's f"{name}_map".

    gltf: its textureInfo's place in a glTF material (a `MaterialParam.gltf` path); None for
        a slot no glTF property fills (the OBJ formats' separate alpha mask).
    channel: where a scalar map's value is (0 R .. 3 A), as the glTF specification puts it;
        the GPU view swizzles it into R (render/gpu_scene.py).
    kind: "color" (sRGB-encoded: decoded by the GPU's sRGB formats), "scalar" (linear, one
        channel), "normal" (linear, tangent-space xyz * 2 - 1) or "vector" (linear, RGB as
        stored: KHR_materials_anisotropy's direction in RG, strength in B).
    bound: has a binding in the material's descriptor set (binding order = table order); the
        alpha mask is merged into the base colour's A on upload instead.
    """

    name: str
    gltf: str | None
    channel: int = 0
    kind: Literal["color", "scalar", "normal", "vector"] = "scalar"
    bound: bool = True

    @property
    def srgb(self) -> bool:
        return self.kind == "color"


@dataclass(frozen=True)
class MaterialParam:
    """One material parameter.

    name: the Material field, the GPU block's member and its GLSL name.
    gltf: the property's place in a glTF material object, dotted; a first part named
        KHR_* is the material's extension object ("KHR_materials_sheen.sheenColorFactor"),
        "normalTexture.scale" a property of a textureInfo.
    default: the schema's default (a tuple for vectors: its length is the GLSL vector's).
    lo, hi: the valid range of every component, for the glTF reader and validation alike.
    texture: the TextureSlot whose texel multiplies it (the shader's LAYER_MAP / SAMPLE).
    gltf_zero: the value that a 0 in the file stands for (ior: the schema's special value).
    gltf_above_lo: the file's value must be greater than `lo` (the schema's exclusive
        minimum); the Material may hold `lo` itself (attenuationDistance: 0 there = infinite,
        the absent property's meaning).
    gltf_scale: a glTF property that the file's value is multiplied by (1 when absent):
        KHR_materials_emissive_strength folds into emissive_factor.
    """

    name: str
    gltf: str
    default: Value
    lo: float = -_WIDE
    hi: float = _WIDE
    texture: str | None = None
    gltf_zero: float | None = None
    gltf_above_lo: bool = False
    gltf_scale: str | None = None

    @property
    def size(self) -> int:
        """Components: 1 for a float, else the default's length."""
        return len(self.default) if isinstance(self.default, tuple) else 1

    @property
    def glsl(self) -> str:
        """The GPU block member's GLSL type."""
        return "float" if self.size == 1 else f"vec{self.size}"

    @property
    def extension(self) -> str | None:
        """The glTF extension holding it; None for the core material."""
        return _extension(self.gltf)

    @property
    def gltf_property(self) -> str:
        """The property within its extension (or the material), as messages name it."""
        return self.gltf.split(".", 1)[1] if self.extension else self.gltf

    @property
    def in_texture_info(self) -> bool:
        """A property of a textureInfo (normal scale, occlusion strength): it shapes that
        texture's texels, not a layer's factor."""
        parts = self.gltf.split(".")
        return len(parts) > 1 and parts[-2].endswith("Texture")

    @property
    def layer(self) -> bool:
        """One of the KHR_materials_* layers' factors: the compute path compiles a material
        whose layer factors are all the defaults without the layers (shade.glsl SHADE_LAYERS,
        generated.glsl MATERIAL_DEFAULT_*)."""
        return self.extension is not None and not self.in_texture_info

    def problem(self, value: Value) -> str | None:
        """Why `value` is outside the valid range (a phrase for a message), or None."""
        values = value if isinstance(value, tuple) else (value,)
        if all(self.lo <= x <= self.hi for x in values):
            return None
        shown = list(values) if isinstance(value, tuple) else value
        return f"{shown!r} outside {self.lo:g}..{self.hi:g}"


_PBR = "pbrMetallicRoughness"
_COAT = "KHR_materials_clearcoat"
_SHEEN = "KHR_materials_sheen"
_SPECULAR = "KHR_materials_specular"
_TRANSMISSION = "KHR_materials_transmission"
_VOLUME = "KHR_materials_volume"
_ANISOTROPY = "KHR_materials_anisotropy"
_IRIDESCENCE = "KHR_materials_iridescence"
_DIFFUSE_TRANSMISSION = "KHR_materials_diffuse_transmission"
_DISPERSION = "KHR_materials_dispersion"

# The texture slots, in Material's order; the bound ones' order is set 1's binding order.
TEXTURES: tuple[TextureSlot, ...] = (
    TextureSlot("base_color", f"{_PBR}.baseColorTexture", kind="color"),  # alpha in A
    # glTF's packed texture: B = metalness, G = roughness (spec 3.9.2).
    TextureSlot("metallic", f"{_PBR}.metallicRoughnessTexture", channel=2),
    TextureSlot("roughness", f"{_PBR}.metallicRoughnessTexture", channel=1),
    TextureSlot("normal", "normalTexture", kind="normal"),
    TextureSlot("occlusion", "occlusionTexture"),  # R
    TextureSlot("emissive", "emissiveTexture", kind="color"),
    # A separate alpha mask (OBJ map_d, .comp5822mesh): `channel` of the TextureRef holds
    # coverage. glTF's alpha is the base colour texture's A.
    TextureSlot("alpha", None, bound=False),
    TextureSlot("clearcoat", f"{_COAT}.clearcoatTexture"),  # R
    TextureSlot("clearcoat_roughness", f"{_COAT}.clearcoatRoughnessTexture", channel=1),
    TextureSlot("clearcoat_normal", f"{_COAT}.clearcoatNormalTexture", kind="normal"),
    TextureSlot("sheen_color", f"{_SHEEN}.sheenColorTexture", kind="color"),
    TextureSlot("sheen_roughness", f"{_SHEEN}.sheenRoughnessTexture", channel=3),
    TextureSlot("specular", f"{_SPECULAR}.specularTexture", channel=3),
    TextureSlot("specular_color", f"{_SPECULAR}.specularColorTexture", kind="color"),
    TextureSlot("transmission", f"{_TRANSMISSION}.transmissionTexture"),  # R
    TextureSlot("thickness", f"{_VOLUME}.thicknessTexture", channel=1),
    TextureSlot("anisotropy", f"{_ANISOTROPY}.anisotropyTexture", kind="vector"),  # RG, B
    TextureSlot("iridescence", f"{_IRIDESCENCE}.iridescenceTexture"),  # R
    # G: the thin film's thickness between the minimum and the maximum (mix, not a product).
    TextureSlot("iridescence_thickness", f"{_IRIDESCENCE}.iridescenceThicknessTexture",
                channel=1),
    TextureSlot("diffuse_transmission", f"{_DIFFUSE_TRANSMISSION}.diffuseTransmissionTexture",
                channel=3),
    TextureSlot("diffuse_transmission_color",
                f"{_DIFFUSE_TRANSMISSION}.diffuseTransmissionColorTexture", kind="color"),
)

# The parameters, in Material's field order. Ranges: the extensions' schemas; the wide bounds
# where a schema sets none, and for the core factors, which files in the wild exceed.
_P = MaterialParam
PARAMS: tuple[MaterialParam, ...] = (
    # The metallic-roughness core (glTF 2.0 3.9.2-3.9.5).
    _P("base_color_factor", f"{_PBR}.baseColorFactor", (1.0, 1.0, 1.0, 1.0), texture="base_color"),
    _P("metallic_factor", f"{_PBR}.metallicFactor", 1.0, texture="metallic"),
    _P("roughness_factor", f"{_PBR}.roughnessFactor", 1.0, texture="roughness"),
    _P("emissive_factor", "emissiveFactor", (0.0, 0.0, 0.0), lo=0.0, hi=1e9, texture="emissive",
       gltf_scale="KHR_materials_emissive_strength.emissiveStrength"),
    _P("normal_scale", "normalTexture.scale", 1.0, texture="normal"),
    _P("occlusion_strength", "occlusionTexture.strength", 1.0, texture="occlusion"),
    _P("alpha_cutoff", "alphaCutoff", 0.5),
    # KHR_materials_ior: dielectric F0 = ((ior - 1) / (ior + 1))^2; 0 in a file is a
    # dielectric of maximal reflectance (F0 -> 1).
    _P("ior", "KHR_materials_ior.ior", 1.5, lo=1.0, gltf_zero=_WIDE),
    # KHR_materials_specular: the dielectric lobe's weight, and a colour scaling F0 that may
    # exceed 1 (F0 is clamped to 1 where it is used).
    _P("specular_factor", f"{_SPECULAR}.specularFactor", 1.0, lo=0.0, hi=1.0, texture="specular"),
    _P("specular_color_factor", f"{_SPECULAR}.specularColorFactor", (1.0, 1.0, 1.0), lo=0.0,
       texture="specular_color"),
    _P("clearcoat_factor", f"{_COAT}.clearcoatFactor", 0.0, lo=0.0, hi=1.0, texture="clearcoat"),
    _P("clearcoat_roughness_factor", f"{_COAT}.clearcoatRoughnessFactor", 0.0, lo=0.0, hi=1.0,
       texture="clearcoat_roughness"),
    _P("sheen_color_factor", f"{_SHEEN}.sheenColorFactor", (0.0, 0.0, 0.0), lo=0.0, hi=1.0,
       texture="sheen_color"),
    _P("sheen_roughness_factor", f"{_SHEEN}.sheenRoughnessFactor", 0.0, lo=0.0, hi=1.0,
       texture="sheen_roughness"),
    _P("transmission_factor", f"{_TRANSMISSION}.transmissionFactor", 0.0, lo=0.0, hi=1.0,
       texture="transmission"),
    # KHR_materials_volume: thickness 0 = thin-walled (no volume), in the mesh's units; the
    # schema's default attenuation distance, +infinity, is held as 0 (as Light.range).
    _P("thickness_factor", f"{_VOLUME}.thicknessFactor", 0.0, lo=0.0, texture="thickness"),
    _P("attenuation_distance", f"{_VOLUME}.attenuationDistance", 0.0, lo=0.0, hi=1e9,
       gltf_above_lo=True),
    _P("attenuation_color", f"{_VOLUME}.attenuationColor", (1.0, 1.0, 1.0), lo=0.0, hi=1.0),
    _P("clearcoat_normal_scale", f"{_COAT}.clearcoatNormalTexture.scale", 1.0,
       texture="clearcoat_normal"),
    # KHR_materials_anisotropy: the strength (times the texture's B) and the rotation of the
    # direction (the texture's RG * 2 - 1, else +tangent) from the tangent, radians
    # counter-clockwise towards the bitangent.
    _P("anisotropy_strength", f"{_ANISOTROPY}.anisotropyStrength", 0.0, lo=0.0, hi=1.0,
       texture="anisotropy"),
    _P("anisotropy_rotation", f"{_ANISOTROPY}.anisotropyRotation", 0.0),
    # KHR_materials_iridescence: a thin film (ior, thickness in nanometres) over the base;
    # without its texture the thickness is the maximum.
    _P("iridescence_factor", f"{_IRIDESCENCE}.iridescenceFactor", 0.0, lo=0.0, hi=1.0,
       texture="iridescence"),
    _P("iridescence_ior", f"{_IRIDESCENCE}.iridescenceIor", 1.3, lo=1.0),
    _P("iridescence_thickness_minimum", f"{_IRIDESCENCE}.iridescenceThicknessMinimum", 100.0,
       lo=0.0),
    _P("iridescence_thickness_maximum", f"{_IRIDESCENCE}.iridescenceThicknessMaximum", 400.0,
       lo=0.0, texture="iridescence_thickness"),
    # KHR_materials_diffuse_transmission: the share of the diffuse lobe that passes through
    # the surface as a Lambertian lobe on the other side, and the colour it takes.
    _P("diffuse_transmission_factor", f"{_DIFFUSE_TRANSMISSION}.diffuseTransmissionFactor", 0.0,
       lo=0.0, hi=1.0, texture="diffuse_transmission"),
    _P("diffuse_transmission_color_factor",
       f"{_DIFFUSE_TRANSMISSION}.diffuseTransmissionColorFactor", (1.0, 1.0, 1.0), lo=0.0,
       hi=1.0, texture="diffuse_transmission_color"),
    # KHR_materials_dispersion: 20 / Abbe number; spreads a volume's ior over the three
    # channels (the Sample Viewer's (ior - 1) x 0.025 x dispersion either side of green).
    _P("dispersion", f"{_DISPERSION}.dispersion", 0.0, lo=0.0),
)

# Material's field defaults (types.py takes them from here; Any: each field's annotation
# there says float or tuple).
DEFAULTS: Mapping[str, Any] = MappingProxyType({p.name: p.default for p in PARAMS})
# The KHR_materials_* factors that shade.glsl's LAYER_FACTOR reads (render/layouts.py).
LAYER_PARAMS: tuple[MaterialParam, ...] = tuple(p for p in PARAMS if p.layer)
# Every material extension vkpbr reads: the rows', and three without rows (KHR_materials_unlit
# is a switch; KHR_materials_variants chooses among materials; the archived
# KHR_materials_pbrSpecularGlossiness is converted to the rows and the `glossiness` switch
# when the file is read: scene/gltf_materials.py).
EXTENSIONS: tuple[str, ...] = tuple(dict.fromkeys(
    x for x in [*(_extension(p.gltf) for p in PARAMS), *(_extension(p.gltf_scale) for p in PARAMS),
                *(_extension(s.gltf) for s in TEXTURES),
                "KHR_materials_unlit", "KHR_materials_variants",
                "KHR_materials_pbrSpecularGlossiness"] if x))
