# The material table (scene/material_table.py) against what derives from it: Material's fields,
# the glTF reader, validation, the GPU block and generated.glsl. The round trip writes glTF
# files with random valid values and checks the GPU block's values against the defaults and
# ranges that the glTF specifications state, written out here from those documents (not read
# from the table), so a wrong row fails here rather than agreeing with itself.

from __future__ import annotations

import dataclasses
import json
import math
import re
import typing
from pathlib import Path

import numpy as np
import pytest
from gltf_files import GltfFile
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from vkpbr.errors import SceneError
from vkpbr.render import codegen
from vkpbr.render import layouts as L
from vkpbr.render.gpu_scene import material_block
from vkpbr.scene.loader import load_scene
from vkpbr.scene.material_table import PARAMS, TEXTURES, MaterialParam
from vkpbr.scene.types import TEXTURE_SLOTS, Material, Node, Scene
from vkpbr.scene.validate import validate_scene

# Each property's default and valid values as the specifications give them (glTF 2.0 schema:
# material, material.pbrMetallicRoughness, material.normalTextureInfo,
# material.occlusionTextureInfo; the KHR_materials_* extensions' READMEs and schemas).
# Values: (default, strategy of valid values). Unbounded schema ranges are drawn from a span.
_UNIT = st.floats(0.0, 1.0)


def _rgb(lo: float = 0.0, hi: float = 1.0) -> st.SearchStrategy:
    return st.lists(st.floats(lo, hi), min_size=3, max_size=3)


SPEC: dict[str, tuple[object, st.SearchStrategy]] = {
    "pbrMetallicRoughness.baseColorFactor": ([1.0, 1.0, 1.0, 1.0],
                                             st.lists(_UNIT, min_size=4, max_size=4)),
    "pbrMetallicRoughness.metallicFactor": (1.0, _UNIT),
    "pbrMetallicRoughness.roughnessFactor": (1.0, _UNIT),
    "emissiveFactor": ([0.0, 0.0, 0.0], _rgb()),
    "normalTexture.scale": (1.0, st.floats(-10.0, 10.0)),  # no bound in the schema
    "occlusionTexture.strength": (1.0, _UNIT),
    "alphaCutoff": (0.5, st.floats(0.0, 10.0)),  # minimum 0
    "KHR_materials_emissive_strength.emissiveStrength": (1.0, st.floats(0.0, 100.0)),
    # ior: minimum 1, or the special value 0 (a dielectric of maximal reflectance).
    "KHR_materials_ior.ior": (1.5, st.just(0.0) | st.floats(1.0, 10.0)),
    "KHR_materials_specular.specularFactor": (1.0, _UNIT),
    "KHR_materials_specular.specularColorFactor": ([1.0, 1.0, 1.0], _rgb(0.0, 10.0)),  # min 0
    "KHR_materials_clearcoat.clearcoatFactor": (0.0, _UNIT),
    "KHR_materials_clearcoat.clearcoatRoughnessFactor": (0.0, _UNIT),
    "KHR_materials_clearcoat.clearcoatNormalTexture.scale": (1.0, st.floats(-10.0, 10.0)),
    "KHR_materials_sheen.sheenColorFactor": ([0.0, 0.0, 0.0], _rgb()),
    "KHR_materials_sheen.sheenRoughnessFactor": (0.0, _UNIT),
    "KHR_materials_transmission.transmissionFactor": (0.0, _UNIT),
    "KHR_materials_volume.thicknessFactor": (0.0, st.floats(0.0, 100.0)),  # minimum 0
    # exclusiveMinimum 0; absent: +infinity.
    "KHR_materials_volume.attenuationDistance": (math.inf, st.floats(1e-3, 1e3)),
    "KHR_materials_volume.attenuationColor": ([1.0, 1.0, 1.0], _rgb()),
    "KHR_materials_anisotropy.anisotropyStrength": (0.0, _UNIT),
    # Radians; the schema sets no range.
    "KHR_materials_anisotropy.anisotropyRotation": (0.0, st.floats(-10.0, 10.0)),
    "KHR_materials_iridescence.iridescenceFactor": (0.0, _UNIT),
    "KHR_materials_iridescence.iridescenceIor": (1.3, st.floats(1.0, 3.0)),  # minimum 1
    "KHR_materials_iridescence.iridescenceThicknessMinimum": (100.0, st.floats(0.0, 1000.0)),
    "KHR_materials_iridescence.iridescenceThicknessMaximum": (400.0, st.floats(0.0, 1000.0)),
    "KHR_materials_diffuse_transmission.diffuseTransmissionFactor": (0.0, _UNIT),
    "KHR_materials_diffuse_transmission.diffuseTransmissionColorFactor": ([1.0, 1.0, 1.0],
                                                                          _rgb()),
    "KHR_materials_dispersion.dispersion": (0.0, st.floats(0.0, 100.0)),  # minimum 0
}
# vkpbr's encodings of two spec values that a float32 uniform cannot hold as such.
IOR_ZERO = 1e6  # ior 0: F0 -> 1 (((1e6 - 1) / (1e6 + 1))^2)
INFINITE_DISTANCE = 0.0  # attenuationDistance +infinity (as Light.range: 0 = infinite)
EMISSIVE_STRENGTH = "KHR_materials_emissive_strength.emissiveStrength"


def _snake(camel: str) -> str:
    return re.sub(r"(?<!^)([A-Z])", r"_\1", camel).lower()


def _set(material: dict, path: str, value: object) -> None:
    """Put `value` at a dotted table path (KHR_* parts under "extensions"); a textureInfo on
    the way refers to texture 0."""
    obj = material
    for key in path.split(".")[:-1]:
        obj = (obj.setdefault("extensions", {}) if key.startswith("KHR_") else obj).setdefault(key, {})
        if key.endswith("Texture"):
            obj.setdefault("index", 0)
    obj[path.split(".")[-1]] = value


def _file(tmp: Path, material: dict) -> Path:
    """A one-triangle glTF using `material`; texture 0 exists for the textureInfo properties
    (its image is never decoded by loading)."""
    f = GltfFile()
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    f.node(mesh=f.mesh({"POSITION": f.accessor(pos, min=[0, 0, 0], max=[1, 1, 0])},
                       material=0))
    f.doc["materials"] = [material]
    f.doc["images"] = [{"uri": "data:image/png;base64,AAAA"}]
    f.doc["textures"] = [{"source": 0}]
    return f.save(tmp / "m.gltf")


def _block(material: Material) -> np.ndarray:
    return material_block(material, dict.fromkeys(L.MATERIAL_TEXTURES, False))


def _row(path: str) -> MaterialParam:
    return next(p for p in PARAMS if p.gltf == path)


# --- the table and its derivations -------------------------------------------------------------
def test_rows_are_the_specifications_properties() -> None:
    """Every row is a property the specs define (and every spec property here has a row or
    is folded into one), with the spec's default, and one name: the property's in snake case
    (a textureInfo's property prefixed with the texture's name)."""
    folded = {p.gltf_scale for p in PARAMS if p.gltf_scale}
    assert {p.gltf for p in PARAMS} | folded == set(SPEC)
    for p in PARAMS:
        want = SPEC[p.gltf][0]
        want = INFINITE_DISTANCE if want == math.inf else want
        assert p.default == (tuple(want) if isinstance(want, list) else want), p.name
        parts = p.gltf_property.split(".")
        assert p.name == "_".join(_snake(x.removesuffix("Texture")) for x in parts[-2:]
                                  if x != "pbrMetallicRoughness"), p.name
        assert p.problem(p.default) is None, p.name


def test_texture_slots_agree_with_the_rows() -> None:
    slots = {s.name: s for s in TEXTURES}
    assert len(slots) == len(TEXTURES) == len(TEXTURE_SLOTS)
    for p in PARAMS:
        assert p.texture is None or p.texture in slots, p.name
        if p.in_texture_info:  # normalTexture.scale: the normal slot is that textureInfo
            assert slots[p.texture].gltf == p.gltf.rsplit(".", 1)[0], p.name
    assert tuple(s.name for s in TEXTURES if s.bound) == L.MATERIAL_TEXTURES
    for s in TEXTURES:  # one name: the textureInfo's key in snake case, less "_texture"
        key = (s.gltf or "").split(".")[-1]
        if key not in ("", "metallicRoughnessTexture"):  # the packed texture serves two slots
            assert s.name == _snake(key.removesuffix("Texture")), s.name


def test_material_fields_take_the_table_defaults() -> None:
    """Each row is a Material field with the row's default and an annotation of its shape;
    every other numeric field of Material would need a row."""
    fields = {f.name: f for f in dataclasses.fields(Material)}
    hints = typing.get_type_hints(Material)
    for p in PARAMS:
        assert fields[p.name].default == p.default, p.name
        want = float if p.size == 1 else tuple[(float,) * p.size]
        assert hints[p.name] == want, p.name
    rows = {p.name for p in PARAMS}
    textures = {f"{s}_texture" for s in TEXTURE_SLOTS}
    switches = {"name", "alpha_mode", "double_sided", "casts_shadows", "unlit", "glossiness"}
    assert set(fields) == rows | textures | switches


def test_reference_default_layers_are_the_table_defaults() -> None:
    """reference/brdf.py's Layers() (the mirror's default layers) is what the table's
    defaults shade as: no second set of defaults to drift apart."""
    from vkpbr.reference import brdf as ref

    assert ref.Layers.of(Material()) == ref.Layers()


def test_gpu_block_holds_every_row_under_its_name() -> None:
    members = dict(L.MATERIAL.fields)
    for p in PARAMS:
        assert members[p.name] == p.glsl, p.name
    assert tuple(p.name for p in PARAMS if p.layer) == L.LAYER_FIELDS
    # No std140 padding: each vec3 shares its 16 bytes with a float; the texture rows start
    # at the first vec4 boundary after the parameters and the flags.
    sizes = [p.size for p in PARAMS]
    used = 16 * (sizes.count(4) + sizes.count(3)) + 4 * (sizes.count(1) - sizes.count(3)) + 4
    assert L.MATERIAL.offsets["base_color_uv_row0"] == -(-used // 16) * 16
    block = _block(Material())
    for p in PARAMS:
        np.testing.assert_array_equal(block[p.name], np.float32(p.default), err_msg=p.name)


def test_generated_glsl_names_the_rows() -> None:
    text = codegen.GENERATED.read_text()
    material = text[text.index("uniform Material {"):text.index("} material;")]
    for p in PARAMS:
        assert f"    {p.glsl} {p.name};" in material, p.name
        if p.layer:
            assert f" MATERIAL_DEFAULT_{p.name} = " in text, p.name


# --- the round trip: a glTF file to the GPU block ----------------------------------------------
@st.composite
def _materials(draw: st.DrawFn) -> tuple[dict, dict[str, object]]:
    """A glTF material with a random subset of the properties set to random valid values,
    and what each property is then (given or the spec's default)."""
    material: dict = {}
    values: dict[str, object] = {}
    for path, (default, valid) in SPEC.items():
        if draw(st.booleans()):
            values[path] = draw(valid)
            _set(material, path, values[path])
        else:
            values[path] = default
            if ".".join(path.split(".")[-2:-1]).endswith("Texture") and draw(st.booleans()):
                _set(material, path.rsplit(".", 1)[0] + ".index", 0)  # textureInfo, no property
    return material, values


def _expected(path: str, values: dict[str, object]) -> object:
    """The value the GPU block should hold for `path`, by the specifications' meanings."""
    value = values[path]
    if path == "KHR_materials_ior.ior" and value == 0.0:
        return IOR_ZERO
    if value == math.inf:
        return INFINITE_DISTANCE
    if path == "emissiveFactor":
        return [e * values[EMISSIVE_STRENGTH] for e in value]  # type: ignore[attr-defined]
    return value


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(_materials())
def test_gltf_values_reach_the_gpu_block(tmp_path: Path, case: tuple[dict, dict]) -> None:
    material, values = case
    loaded = load_scene(_file(tmp_path, json.loads(json.dumps(material)))).materials[0]
    block = _block(loaded)
    for p in PARAMS:
        want = _expected(p.gltf, values)
        got = getattr(loaded, p.name)
        assert got == (tuple(want) if isinstance(want, list) else want), p.name
        np.testing.assert_array_equal(block[p.name], np.float32(want), err_msg=p.name)


# --- out of range: one error naming the parameter -----------------------------------------------
@st.composite
def _out_of_range(draw: st.DrawFn) -> tuple[MaterialParam, float]:
    p = draw(st.sampled_from(PARAMS))
    step = draw(st.floats(1e-3, 1e9))
    x = p.lo - step if draw(st.booleans()) else p.hi + step
    assume(p.gltf_zero is None or x != 0.0)  # ior 0 is the schema's special value
    return p, x


def _bad(p: MaterialParam, x: float) -> float | list[float]:
    """`x` in one component of the parameter (the others the default's)."""
    return x if p.size == 1 else [x, *list(p.default)[1:]]  # type: ignore[arg-type]


@settings(max_examples=80, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(_out_of_range())
@example((_row("KHR_materials_volume.attenuationDistance"), 0.0))  # the exclusive minimum
def test_out_of_range_in_a_file_names_the_property(tmp_path: Path,
                                                   case: tuple[MaterialParam, float]) -> None:
    p, x = case
    material: dict = {}
    _set(material, p.gltf, _bad(p, x))
    with pytest.raises(SceneError) as info:
        load_scene(_file(tmp_path, material))
    message = str(info.value)
    assert f"material 0: {p.gltf_property} " in message and "\n" not in message, message


@settings(max_examples=80, deadline=None)
@given(_out_of_range())
def test_out_of_range_in_a_material_names_the_field(case: tuple[MaterialParam, float]) -> None:
    from vkpbr.scene.default import plane

    p, x = case
    value = x if p.size == 1 else tuple(_bad(p, x))  # type: ignore[arg-type]
    mesh = plane(1.0, 1.0)
    mesh.material = 0
    bad = dataclasses.replace(Material(), **{p.name: value})
    scene = Scene("s", meshes=[mesh], materials=[bad], nodes=[Node(mesh=0)])
    where = re.escape(f"materials[0].{p.name}") + r"(\[0\])?"
    problem = re.escape(f": expected a finite number in [{p.lo:g}, {p.hi:g}]")
    with pytest.raises(SceneError, match=where + problem):
        validate_scene(scene, Path("s.vkpbr"))
