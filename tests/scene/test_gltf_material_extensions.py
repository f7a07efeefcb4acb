# The KHR_materials_* extensions in the glTF loader (scene/gltf_materials.py), written as small
# files here: each extension's factors land in Material, out-of-range values are one-line
# SceneErrors, KHR_materials_variants selects materials per primitive (load_scene(variant=)),
# and the new Material fields round-trip through the baked format and its validation.

from __future__ import annotations

import dataclasses
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vkpbr.errors import SceneError
from vkpbr.scene.loader import load_scene
from vkpbr.scene.types import Material
from vkpbr.scene.validate import validate_scene

sys.path.insert(0, str(Path(__file__).parent))
from test_gltf import GltfBuilder  # noqa: E402

ALL = {
    "KHR_materials_unlit": {},
    "KHR_materials_ior": {"ior": 1.33},
    "KHR_materials_specular": {"specularFactor": 0.5, "specularColorFactor": [1.5, 0.5, 0.25]},
    "KHR_materials_clearcoat": {"clearcoatFactor": 0.75, "clearcoatRoughnessFactor": 0.2},
    "KHR_materials_sheen": {"sheenColorFactor": [0.9, 0.2, 0.1], "sheenRoughnessFactor": 0.4},
    "KHR_materials_transmission": {"transmissionFactor": 0.6},
    "KHR_materials_volume": {"thicknessFactor": 0.25, "attenuationDistance": 2.0,
                             "attenuationColor": [0.9, 0.5, 0.1]},
    "KHR_materials_emissive_strength": {"emissiveStrength": 3.0},
    "KHR_materials_anisotropy": {"anisotropyStrength": 0.7, "anisotropyRotation": 1.25},
    "KHR_materials_iridescence": {"iridescenceFactor": 0.9, "iridescenceIor": 1.8,
                                  "iridescenceThicknessMinimum": 50.0,
                                  "iridescenceThicknessMaximum": 600.0},
    "KHR_materials_diffuse_transmission": {"diffuseTransmissionFactor": 0.4,
                                           "diffuseTransmissionColorFactor": [0.5, 0.6, 0.7]},
    "KHR_materials_dispersion": {"dispersion": 0.33},
}


def write(tmp_path: Path, materials: list[dict], variants: list[str] | None = None,
          mappings: list[dict] | None = None) -> Path:
    b = GltfBuilder()
    b.node(mesh=b.triangle())
    b.doc["materials"] = materials
    b.doc["meshes"][0]["primitives"][0]["material"] = 0
    if variants is not None:
        b.doc["extensions"] = {"KHR_materials_variants": {"variants": [{"name": n} for n in variants]}}
        b.doc["meshes"][0]["primitives"][0]["extensions"] = {
            "KHR_materials_variants": {"mappings": mappings or []}}
    return b.save(tmp_path / "m.gltf", "datauri")


def test_every_extension_factor_is_read(tmp_path: Path) -> None:
    path = write(tmp_path, [{"emissiveFactor": [1, 0.5, 0], "extensions": ALL}])
    m = load_scene(path).materials[0]
    assert m.unlit is True and m.ior == 1.33
    assert (m.specular_factor, m.specular_color_factor) == (0.5, (1.5, 0.5, 0.25))
    assert (m.clearcoat_factor, m.clearcoat_roughness_factor) == (0.75, 0.2)
    assert (m.sheen_color_factor, m.sheen_roughness_factor) == ((0.9, 0.2, 0.1), 0.4)
    assert m.transmission_factor == 0.6
    assert (m.thickness_factor, m.attenuation_distance, m.attenuation_color) == (
        0.25, 2.0, (0.9, 0.5, 0.1))
    assert m.emissive_factor == (3.0, 1.5, 0.0)  # emissive strength folded into the factor
    assert (m.anisotropy_strength, m.anisotropy_rotation) == (0.7, 1.25)
    assert (m.iridescence_factor, m.iridescence_ior, m.iridescence_thickness_minimum,
            m.iridescence_thickness_maximum) == (0.9, 1.8, 50.0, 600.0)
    assert (m.diffuse_transmission_factor, m.diffuse_transmission_color_factor) == (
        0.4, (0.5, 0.6, 0.7))
    assert m.dispersion == 0.33


def test_defaults_are_the_core_material(tmp_path: Path) -> None:
    m = load_scene(write(tmp_path, [{}])).materials[0]
    core = Material()
    for f in ("unlit", "ior", "specular_factor", "specular_color_factor", "clearcoat_factor",
              "sheen_color_factor", "transmission_factor", "thickness_factor",
              "attenuation_distance", "attenuation_color"):
        assert getattr(m, f) == getattr(core, f), f


def test_ior_zero_is_the_schema_special_value(tmp_path: Path) -> None:
    m = load_scene(write(tmp_path, [{"extensions": {"KHR_materials_ior": {"ior": 0}}}])).materials[0]
    assert m.ior >= 1e5  # F0 -> 1


@pytest.mark.parametrize(("name", "body", "words"), [
    ("KHR_materials_ior", {"ior": 0.5}, "material 0: ior 0.5 outside 1..1e+06"),
    ("KHR_materials_clearcoat", {"clearcoatFactor": 1.5}, "clearcoatFactor 1.5 outside 0..1"),
    ("KHR_materials_sheen", {"sheenColorFactor": [2, 0, 0]}, "sheenColorFactor"),
    ("KHR_materials_transmission", {"transmissionFactor": -0.1}, "transmissionFactor"),
    ("KHR_materials_volume", {"attenuationDistance": 0}, "attenuationDistance 0.0 must be > 0"),
    ("KHR_materials_specular", {"specularFactor": "x"}, "specularFactor"),
    ("KHR_materials_anisotropy", {"anisotropyStrength": 1.5}, "anisotropyStrength 1.5 outside 0..1"),
    ("KHR_materials_iridescence", {"iridescenceIor": 0.5}, "iridescenceIor 0.5 outside 1..1e+06"),
    ("KHR_materials_dispersion", {"dispersion": -1}, "dispersion -1.0 outside 0..1e+06"),
])
def test_bad_factor_is_one_line_error(tmp_path: Path, name: str, body: dict, words: str) -> None:
    with pytest.raises(SceneError) as info:
        load_scene(write(tmp_path, [{"extensions": {name: body}}]))
    assert words in str(info.value) and "m.gltf" in str(info.value)
    assert "\n" not in str(info.value)


def test_extension_textures_are_read(tmp_path: Path) -> None:
    """Each extension texture lands in its Material slot with the channel the extension reads
    (scalar maps), its UV set and KHR_texture_transform; the coat normal keeps its scale."""
    info = lambda k, **kw: {"index": k, **kw}  # noqa: E731
    mat = {"extensions": {
        "KHR_materials_clearcoat": {"clearcoatFactor": 1, "clearcoatTexture": info(0),
                                    "clearcoatRoughnessTexture": info(1, texCoord=1),
                                    "clearcoatNormalTexture": info(2, scale=0.5)},
        "KHR_materials_sheen": {"sheenColorFactor": [1, 1, 1], "sheenColorTexture": info(1),
                                "sheenRoughnessTexture": info(1)},
        "KHR_materials_specular": {"specularTexture": info(0), "specularColorTexture": info(2)},
        "KHR_materials_transmission": {"transmissionTexture": info(0, extensions={
            "KHR_texture_transform": {"scale": [2, 3]}})},
        "KHR_materials_volume": {"thicknessTexture": info(0)},
        "KHR_materials_anisotropy": {"anisotropyTexture": info(2, texCoord=1)},
        "KHR_materials_iridescence": {"iridescenceTexture": info(1),
                                      "iridescenceThicknessTexture": info(0)},
        "KHR_materials_diffuse_transmission": {"diffuseTransmissionTexture": info(0),
                                               "diffuseTransmissionColorTexture": info(1)},
    }}
    b = GltfBuilder()
    b.node(mesh=b.triangle())
    b.doc["meshes"][0]["primitives"][0]["material"] = 0
    b.doc["materials"] = [mat]
    b.doc["images"] = [{"uri": f"data:image/png;base64,{k}AAA="} for k in "ABC"]
    b.doc["textures"] = [{"source": k} for k in range(3)]
    m = load_scene(b.save(tmp_path / "t.gltf", "datauri")).materials[0]
    got = {slot: (ref.image, ref.channel, ref.texcoord) for slot in (
        "clearcoat", "clearcoat_roughness", "clearcoat_normal", "sheen_color", "sheen_roughness",
        "specular", "specular_color", "transmission", "thickness", "anisotropy", "iridescence",
        "iridescence_thickness", "diffuse_transmission", "diffuse_transmission_color")
        for ref in (getattr(m, f"{slot}_texture"),)}
    assert got == {"clearcoat": (0, 0, 0), "clearcoat_roughness": (1, 1, 1),
                   "clearcoat_normal": (2, 0, 0), "sheen_color": (1, 0, 0),
                   "sheen_roughness": (1, 3, 0), "specular": (0, 3, 0),
                   "specular_color": (2, 0, 0), "transmission": (0, 0, 0),
                   "thickness": (0, 1, 0), "anisotropy": (2, 0, 1), "iridescence": (1, 0, 0),
                   "iridescence_thickness": (0, 1, 0), "diffuse_transmission": (0, 3, 0),
                   "diffuse_transmission_color": (1, 0, 0)}
    assert m.clearcoat_normal_scale == 0.5 and m.transmission_texture.scale == (2, 3)
    out = tmp_path / "t.vkpbr"  # and through the baked format
    from vkpbr.bake.bake import bake_scene
    from vkpbr.scene.baked_file import write_baked

    write_baked(out, bake_scene(load_scene(tmp_path / "t.gltf"), progress=False))
    assert dataclasses.asdict(load_scene(out).materials[0]) == dataclasses.asdict(m)


def test_variants_select_the_mapped_material(tmp_path: Path) -> None:
    mats = [{"name": "default"}, {"name": "red"}, {"name": "blue"}]
    path = write(tmp_path, mats, ["red", "blue", "plain"],
                 [{"material": 1, "variants": [0]}, {"material": 2, "variants": [1]}])
    plain = load_scene(path)
    assert plain.variants == ["red", "blue", "plain"]
    assert plain.meshes[0].material == 0
    assert load_scene(path, variant="red").meshes[0].material == 1
    assert load_scene(path, variant="blue").meshes[0].material == 2
    assert load_scene(path, variant="plain").meshes[0].material == 0  # unmapped: the default
    with pytest.raises(SceneError, match=r"no material variant 'green' \(the file's: 'red', "
                                         r"'blue', 'plain'\)"):
        load_scene(path, variant="green")


def test_variant_on_a_file_without_variants(tmp_path: Path) -> None:
    with pytest.raises(SceneError, match="no material variant 'x' .the file's: none"):
        load_scene(write(tmp_path, [{}]), variant="x")
    obj = tmp_path / "t.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(SceneError, match="only glTF files have variants"):
        load_scene(obj, variant="x")


def test_variant_mapping_to_a_missing_material(tmp_path: Path) -> None:
    path = write(tmp_path, [{}], ["a"], [{"material": 7, "variants": [0]}])
    with pytest.raises(SceneError, match="variant material 7 out of range"):
        load_scene(path, variant="a")


LAYERED = Material(name="layered", unlit=True, ior=1.7, specular_factor=0.3,
                   specular_color_factor=(2.0, 1.0, 0.5), clearcoat_factor=0.4,
                   clearcoat_roughness_factor=0.6, sheen_color_factor=(0.1, 0.2, 0.3),
                   sheen_roughness_factor=0.8, transmission_factor=0.9, thickness_factor=1.5,
                   attenuation_distance=3.0, attenuation_color=(0.5, 0.6, 0.7))


SG = "KHR_materials_pbrSpecularGlossiness"


def test_specular_glossiness_replaces_the_fallback(tmp_path: Path) -> None:
    """KHR_materials_pbrSpecularGlossiness (archived) becomes a dielectric: the diffuse colour
    and texture are the base colour, F0 = 0.04 x specular colour = specularFactor (the
    specular-glossiness texture's RGB multiplying it), glossiness in the roughness slot
    (channel A) with the `glossiness` switch; the metallic-roughness fallback is dropped.
    Absent factors take the extension schema's defaults (1, 1, 1)."""
    info = lambda k, **kw: {"index": k, **kw}  # noqa: E731
    mats = [{"pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.1, 0.1, 1], "metallicFactor": 1,
                                      "metallicRoughnessTexture": info(0)},
             "extensions": {SG: {"diffuseFactor": [0.5, 0.25, 1.0, 0.75],
                                 "specularFactor": [0.2, 0.4, 0.8], "glossinessFactor": 0.6,
                                 "diffuseTexture": info(1, texCoord=1),
                                 "specularGlossinessTexture": info(2)}}},
            {"extensions": {SG: {}}}]
    b = GltfBuilder()
    b.node(mesh=b.triangle())
    b.doc["meshes"][0]["primitives"][0]["material"] = 0
    b.doc["materials"] = mats
    b.doc["images"] = [{"uri": f"data:image/png;base64,{k}AAA="} for k in "ABC"]
    b.doc["textures"] = [{"source": k} for k in range(3)]
    b.doc["extensionsRequired"] = [SG]
    b.doc["extensionsUsed"] = [SG]
    m, plain = load_scene(b.save(tmp_path / "sg.gltf", "datauri")).materials
    assert m.glossiness and plain.glossiness
    assert m.base_color_factor == (0.5, 0.25, 1.0, 0.75) and m.roughness_factor == 0.6
    assert (m.metallic_factor, m.metallic_texture) == (0.0, None)
    f0 = 0.04 * np.asarray(m.specular_color_factor)
    np.testing.assert_allclose(f0, (0.2, 0.4, 0.8), rtol=1e-12)
    assert (m.ior, m.specular_factor) == (1.5, 1.0)
    assert (m.base_color_texture.image, m.base_color_texture.texcoord) == (1, 1)
    assert (m.roughness_texture.image, m.roughness_texture.channel) == (2, 3)
    assert (m.specular_color_texture.image, m.specular_color_texture.channel) == (2, 0)
    assert plain.base_color_factor == (1.0, 1.0, 1.0, 1.0) and plain.roughness_factor == 1.0
    np.testing.assert_allclose(0.04 * np.asarray(plain.specular_color_factor), 1.0)
    out = tmp_path / "sg.vkpbr"  # the switch survives the baked format
    from vkpbr.bake.bake import bake_scene
    from vkpbr.scene.baked_file import write_baked

    write_baked(out, bake_scene(load_scene(tmp_path / "sg.gltf"), progress=False))
    assert dataclasses.asdict(load_scene(out).materials[0]) == dataclasses.asdict(m)


@pytest.mark.parametrize(("body", "words"), [
    ({"glossinessFactor": 1.5}, "material 0: glossinessFactor 1.5 outside 0..1"),
    ({"specularFactor": [0.1, 2, 0]}, "specularFactor [0.1, 2.0, 0.0] outside 0..1"),
    ({"diffuseFactor": [1, 1, 1]}, "diffuseFactor: expected 4 finite numbers"),
])
def test_bad_specular_glossiness_is_one_line_error(tmp_path: Path, body: dict, words: str) -> None:
    with pytest.raises(SceneError) as info:
        load_scene(write(tmp_path, [{"extensions": {SG: body}}]))
    assert words in str(info.value) and "m.gltf" in str(info.value)
    assert "\n" not in str(info.value)


def test_layers_round_trip_through_the_baked_format(tmp_path: Path) -> None:
    from vkpbr.bake.bake import bake_scene
    from vkpbr.scene.baked_file import write_baked
    from vkpbr.scene.default import plane
    from vkpbr.scene.types import Node, Scene

    mesh = plane(1.0, 1.0)
    mesh.material = 0
    scene = Scene("s", meshes=[mesh], materials=[LAYERED], nodes=[Node(mesh=0)])
    out = tmp_path / "s.vkpbr"
    write_baked(out, bake_scene(scene, progress=False))
    back = load_scene(out).materials[0]
    assert dataclasses.asdict(back) == dataclasses.asdict(LAYERED)


@pytest.mark.parametrize(("field", "value"), [
    ("ior", 0.9), ("clearcoat_factor", 1.1), ("sheen_color_factor", (0.0, 1.5, 0.0)),
    ("attenuation_distance", -1.0), ("transmission_factor", float("nan")), ("unlit", "yes"),
    ("specular_color_factor", (1.0, 1.0)), ("thickness_factor", -0.5), ("glossiness", 1),
])
def test_validation_rejects_bad_layers(field: str, value: object) -> None:
    from vkpbr.scene.default import plane
    from vkpbr.scene.types import Node, Scene

    mesh = plane(1.0, 1.0)
    mesh.material = 0
    bad = dataclasses.replace(LAYERED, **{field: value})
    scene = Scene("s", meshes=[mesh], materials=[bad], nodes=[Node(mesh=0)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(SceneError, match=rf"materials\[0\]\.{field}"):
            validate_scene(scene, Path("s.vkpbr"))


@pytest.mark.parametrize("command", ["render", "view"])
def test_variant_option_reaches_the_loader(tmp_path: Path, command: str) -> None:
    """`--variant NAME` (one definition in app/options.py, on render and view) loads that
    variant through load_scene_arg, also through the bake cache (a file per variant)."""
    from vkpbr.app.cli import build_parser
    from vkpbr.app.common import load_scene_arg

    mats = [{"name": "default"}, {"name": "red"}]
    path = write(tmp_path, mats, ["red"], [{"material": 1, "variants": [0]}])
    args = build_parser().parse_args([command, str(path), "--variant", "red"])
    assert args.variant == "red"
    assert load_scene_arg(args).meshes[0].material == 1
    cached = build_parser().parse_args([command, str(path), "--variant", "red", "--cache",
                                        str(tmp_path / "cache")])
    assert load_scene_arg(cached).meshes[0].material == 1
    plain = build_parser().parse_args([command, str(path), "--cache", str(tmp_path / "cache")])
    assert load_scene_arg(plain).meshes[0].material == 0
    assert len(list((tmp_path / "cache").glob("*.vkpbr"))) == 2


_JSON = st.recursive(st.none() | st.booleans() | st.integers(-5, 5)
                     | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=3),
                     lambda inner: st.lists(inner, max_size=4)
                     | st.dictionaries(st.text(max_size=3), inner, max_size=3), max_leaves=8)
_KEYS = {"KHR_materials_ior": ["ior"], "KHR_materials_specular": ["specularFactor",
         "specularColorFactor", "specularTexture"], "KHR_materials_clearcoat": [
         "clearcoatFactor", "clearcoatRoughnessFactor", "clearcoatNormalTexture"],
         "KHR_materials_sheen": ["sheenColorFactor", "sheenRoughnessFactor"],
         "KHR_materials_transmission": ["transmissionFactor", "transmissionTexture"],
         "KHR_materials_volume": ["thicknessFactor", "attenuationDistance", "attenuationColor"],
         "KHR_materials_unlit": ["x"], "KHR_materials_emissive_strength": ["emissiveStrength"],
         "KHR_materials_anisotropy": ["anisotropyStrength", "anisotropyRotation",
                                      "anisotropyTexture"],
         "KHR_materials_iridescence": ["iridescenceFactor", "iridescenceIor",
                                       "iridescenceThicknessMaximum",
                                       "iridescenceThicknessTexture"],
         "KHR_materials_diffuse_transmission": ["diffuseTransmissionFactor",
                                                "diffuseTransmissionColorFactor"],
         "KHR_materials_dispersion": ["dispersion"],
         "KHR_materials_pbrSpecularGlossiness": ["diffuseFactor", "specularFactor",
                                                 "glossinessFactor", "diffuseTexture",
                                                 "specularGlossinessTexture"]}


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.sampled_from(sorted(_KEYS)), st.data(), _JSON, _JSON)
def test_hostile_extension_values_are_scene_errors(tmp_path: Path, name: str, data, value,  # noqa: ANN001
                                                   mapping) -> None:  # noqa: ANN001
    """Any JSON value in an extension's field (or as the variant mappings) loads or is a
    SceneError naming the file: never another exception."""
    key = data.draw(st.sampled_from(_KEYS[name]))
    path = write(tmp_path, [{"extensions": {name: {key: value}}}, {}], ["a"],
                 mapping if isinstance(mapping, list) else [mapping])
    for variant in (None, "a"):
        try:
            load_scene(path, variant=variant)
        except SceneError as exc:
            assert "m.gltf" in str(exc) and "\n" not in str(exc)


def test_bake_command_bakes_the_variant(tmp_path: Path) -> None:
    from vkpbr.app.cli import main

    mats = [{"name": "default"}, {"name": "red"}]
    path = write(tmp_path, mats, ["red"], [{"material": 1, "variants": [0]}])
    out = tmp_path / "red.vkpbr"
    assert main(["bake", str(path), "-o", str(out), "--variant", "red", "--no-progress"]) == 0
    assert load_scene(out).meshes[0].material == 1


def test_material_extensions_are_in_the_supported_list() -> None:
    """A file may require every material extension the loader reads."""
    from vkpbr.scene.gltf_document import SUPPORTED_EXTENSIONS
    from vkpbr.scene.gltf_materials import MATERIAL_EXTENSIONS

    assert set(MATERIAL_EXTENSIONS) <= SUPPORTED_EXTENSIONS
