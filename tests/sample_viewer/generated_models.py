"""Generated glTF models for the Sample Viewer comparison: the Khronos sample models for the
material extensions vkpbr adds are not in the assets (and are not fetched), so each extension
gets a grid of spheres with its parameters, written here as one self-contained document
(buffers as data URIs) that both renderers load.

Each function returns the glTF document (a dict). The spheres have radius 1, 2.4 apart, in
rows of three, centred on the origin: `Scenario(..., eye=(0, 0, 10.5))` frames two rows at
256 x 256 and 45 degrees.
"""

from __future__ import annotations

import base64
import io
import math

import numpy as np

from vkpbr.scene.default import uv_sphere

_SG = "KHR_materials_pbrSpecularGlossiness"


def png_uri(rgba: tuple[int, int, int, int]) -> str:
    """A 4 x 4 PNG of one texel value as a data URI: a texture filtering cannot change."""
    from PIL import Image

    out = io.BytesIO()
    Image.fromarray(np.broadcast_to(np.asarray(rgba, np.uint8), (4, 4, 4)).copy()).save(out, "PNG")
    return "data:image/png;base64," + base64.b64encode(out.getvalue()).decode()


def sphere_grid(materials: list[dict], name: str, images: tuple[str, ...] = ()) -> dict:
    """One sphere per material, row-major in rows of three, with normals, TEXCOORD_0 and
    TANGENT (both renderers then take the same tangent frame); `images`: data URIs, texture
    k of image k. extensionsUsed from the materials (none required: a viewer without an
    extension still loads the file)."""
    sphere = uv_sphere(1.0, 32, 64)
    pos = np.ascontiguousarray(sphere.positions, np.float32)
    nrm = np.ascontiguousarray(sphere.normals, np.float32)
    uv = np.ascontiguousarray(sphere.texcoords, np.float32)
    tan = np.ascontiguousarray(sphere.tangents, np.float32)
    idx = np.ascontiguousarray(sphere.indices, np.uint32)
    parts = (pos, nrm, uv, tan, idx)
    offsets = np.cumsum([0, *(p.nbytes for p in parts)])
    blob = b"".join(p.tobytes() for p in parts)
    views = [{"buffer": 0, "byteOffset": int(o), "byteLength": p.nbytes}
             for o, p in zip(offsets, parts, strict=False)]
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": len(pos), "type": "VEC3",
         "min": pos.min(0).tolist(), "max": pos.max(0).tolist()},
        {"bufferView": 1, "componentType": 5126, "count": len(nrm), "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": len(uv), "type": "VEC2"},
        {"bufferView": 3, "componentType": 5126, "count": len(tan), "type": "VEC4"},
        {"bufferView": 4, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
    ]
    rows = (len(materials) + 2) // 3
    meshes, nodes = [], []
    for k, material in enumerate(materials):
        meshes.append({"name": material.get("name", f"sphere {k}"), "primitives": [
            {"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2, "TANGENT": 3},
             "indices": 4, "material": k}]})
        row, col = divmod(k, 3)
        nodes.append({"mesh": k, "translation": [(col - 1) * 2.4, (rows - 1) * 1.2 - 2.4 * row, 0.0]})
    used = sorted({e for m in materials for e in m.get("extensions", {})})
    textures = {"images": [{"uri": u} for u in images],
                "textures": [{"source": k} for k in range(len(images))]} if images else {}
    return {
        **textures,
        "asset": {"version": "2.0", "generator": f"vkpbr tests/sample_viewer ({name})"},
        "extensionsUsed": used,
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(blob).decode()}],
        "bufferViews": views, "accessors": accessors, "materials": materials,
        "meshes": meshes, "nodes": nodes, "scenes": [{"nodes": list(range(len(nodes)))}],
        "scene": 0,
    }


def _sg(name: str, diffuse: tuple, specular: tuple, glossiness: float) -> dict:
    """A specular-glossiness material over the metallic-roughness fallback that shades the
    same (metallic 0, roughness 1 - glossiness): the Sample Viewer 1.1.0 takes metallic and
    roughness from the fallback even when it renders the extension (never sets its material
    type to "SG"), so the fallback is written to agree with the extension."""
    return {"name": name,
            "pbrMetallicRoughness": {"baseColorFactor": [*diffuse, 1.0], "metallicFactor": 0.0,
                                     "roughnessFactor": 1.0 - glossiness},
            "extensions": {_SG: {"diffuseFactor": [*diffuse, 1.0], "specularFactor": list(specular),
                                 "glossinessFactor": glossiness}}}


def specular_glossiness_spheres() -> dict:
    """KHR_materials_pbrSpecularGlossiness: red plastic, gold as the extension writes metals
    (black diffuse, coloured specular), rough blue, a mirror (glossiness 1), green under a
    yellow specular, rough white."""
    return sphere_grid([
        _sg("plastic", (0.8, 0.1, 0.1), (0.04, 0.04, 0.04), 0.8),
        _sg("gold", (0.0, 0.0, 0.0), (1.0, 0.77, 0.33), 0.7),
        _sg("rough-blue", (0.1, 0.2, 0.7), (0.2, 0.2, 0.2), 0.2),
        _sg("mirror", (0.0, 0.0, 0.0), (0.9, 0.9, 0.9), 1.0),
        _sg("green-yellow", (0.1, 0.5, 0.1), (0.3, 0.3, 0.1), 0.5),
        _sg("white", (1.0, 1.0, 1.0), (0.04, 0.04, 0.04), 0.0),
    ], "SpecGlossSpheres")


_ANISOTROPY = "KHR_materials_anisotropy"


def _anisotropic(name: str, color: tuple, metallic: float, roughness: float, strength: float,
                 rotation: float, texture: bool = False) -> dict:
    extension = {"anisotropyStrength": strength, "anisotropyRotation": rotation}
    if texture:
        extension["anisotropyTexture"] = {"index": 0}
    return {"name": name,
            "pbrMetallicRoughness": {"baseColorFactor": [*color, 1.0], "metallicFactor": metallic,
                                     "roughnessFactor": roughness},
            "extensions": {_ANISOTROPY: extension}}


def anisotropy_spheres() -> dict:
    """KHR_materials_anisotropy: brushed metal at strength 0.3, 0.6 and 0.9 along the
    tangent (the spheres' longitude direction), 0.9 turned a quarter (along the meridians),
    a red dielectric at 0.6 turned 45 degrees, and a texture (direction (0.57, 0) +
    rotation, strength x 0.78)."""
    gold = (1.0, 0.78, 0.34)
    return sphere_grid([
        _anisotropic("s0.3", gold, 1.0, 0.4, 0.3, 0.0),
        _anisotropic("s0.6", gold, 1.0, 0.4, 0.6, 0.0),
        _anisotropic("s0.9", gold, 1.0, 0.4, 0.9, 0.0),
        _anisotropic("s0.9-quarter", gold, 1.0, 0.4, 0.9, math.pi / 2),
        _anisotropic("red-45", (0.7, 0.1, 0.1), 0.0, 0.3, 0.6, math.pi / 4),
        _anisotropic("texture", (0.9, 0.9, 0.9), 1.0, 0.35, 1.0, 0.3, texture=True),
    ], "AnisotropySpheres", images=(png_uri((200, 128, 200, 255)),))


_IRIDESCENCE = "KHR_materials_iridescence"


def _iridescent(name: str, color: tuple, metallic: float, roughness: float, factor: float,
                ior: float, thickness: float, texture: bool = False) -> dict:
    extension = {"iridescenceFactor": factor, "iridescenceIor": ior,
                 "iridescenceThicknessMinimum": 100.0, "iridescenceThicknessMaximum": thickness}
    if texture:
        extension["iridescenceThicknessTexture"] = {"index": 0}
    return {"name": name,
            "pbrMetallicRoughness": {"baseColorFactor": [*color, 1.0], "metallicFactor": metallic,
                                     "roughnessFactor": roughness},
            "extensions": {_IRIDESCENCE: extension}}


def iridescence_spheres() -> dict:
    """KHR_materials_iridescence: a soap-bubble-like film (ior 1.3, 300 nm) on black, 500 nm on
    a grey dielectric, 800 nm at ior 2.0 on a rough red, a film over metal (gold, 400 nm),
    half the factor on white, and a thickness texture (G 0.5: 100 + 0.5 x 700 nm)."""
    return sphere_grid([
        _iridescent("bubble", (0.02, 0.02, 0.02), 0.0, 0.1, 1.0, 1.3, 300.0),
        _iridescent("grey-500", (0.3, 0.3, 0.3), 0.0, 0.25, 1.0, 1.5, 500.0),
        _iridescent("red-800", (0.6, 0.1, 0.1), 0.0, 0.5, 1.0, 2.0, 800.0),
        _iridescent("gold", (1.0, 0.78, 0.34), 1.0, 0.2, 1.0, 1.4, 400.0),
        _iridescent("white-half", (0.9, 0.9, 0.9), 0.0, 0.3, 0.5, 1.3, 350.0),
        _iridescent("texture", (0.1, 0.1, 0.3), 0.0, 0.2, 1.0, 1.5, 800.0, texture=True),
    ], "IridescenceSpheres", images=(png_uri((0, 128, 0, 255)),))


_DIFFUSE_TRANSMISSION = "KHR_materials_diffuse_transmission"


def _diffuse_transmissive(name: str, color: tuple, roughness: float, factor: float,
                          dt_color: tuple, texture: bool = False) -> dict:
    extension = {"diffuseTransmissionFactor": factor,
                 "diffuseTransmissionColorFactor": list(dt_color)}
    if texture:
        extension["diffuseTransmissionTexture"] = {"index": 0}
    return {"name": name,
            "pbrMetallicRoughness": {"baseColorFactor": [*color, 1.0], "metallicFactor": 0.0,
                                     "roughnessFactor": roughness},
            "extensions": {_DIFFUSE_TRANSMISSION: extension}}


def diffuse_transmission_spheres() -> dict:
    """KHR_materials_diffuse_transmission (thin-walled: no volume): factors 0.25, 0.5 and 1 on
    white, an orange transmission colour on green, a leaf-like green, and a factor texture
    (A 0.6). The colour texture is left out: the viewer 1.1.0 reads it as linear data."""
    return sphere_grid([
        _diffuse_transmissive("white-0.25", (0.9, 0.9, 0.9), 0.6, 0.25, (1.0, 1.0, 1.0)),
        _diffuse_transmissive("white-0.5", (0.9, 0.9, 0.9), 0.6, 0.5, (1.0, 1.0, 1.0)),
        _diffuse_transmissive("white-1", (0.9, 0.9, 0.9), 0.6, 1.0, (1.0, 1.0, 1.0)),
        _diffuse_transmissive("orange-on-green", (0.2, 0.6, 0.2), 0.4, 0.7, (1.0, 0.5, 0.1)),
        _diffuse_transmissive("leaf", (0.1, 0.4, 0.05), 0.5, 0.5, (0.5, 0.9, 0.2)),
        _diffuse_transmissive("texture", (0.8, 0.3, 0.3), 0.5, 1.0, (1.0, 1.0, 1.0),
                              texture=True),
    ], "DiffuseTransmissionSpheres", images=(png_uri((255, 255, 255, 153)),))


def _stripes_png() -> str:
    """A 64 x 8 texture of vertical stripes (red, green, blue, white, black, ...): dispersion
    splits its edges by colour."""
    from PIL import Image

    colors = np.array([(230, 40, 40), (40, 200, 60), (50, 70, 230), (240, 240, 240), (20, 20, 20),
                       (240, 200, 40), (40, 200, 220), (200, 60, 200)], np.uint8)
    row = np.repeat(colors, 8, axis=0)  # 64 texels, 8 a stripe
    pixels = np.broadcast_to(row[None], (8, 64, 3)).copy()
    out = io.BytesIO()
    Image.fromarray(pixels).save(out, "PNG")
    return "data:image/png;base64," + base64.b64encode(out.getvalue()).decode()


def _add_backdrop(doc: dict, z: float, half: float, material: int) -> dict:
    """A square (2 half wide) at depth z facing +Z, UV 0..1 repeated 4 times across, as a
    second buffer and a node of the first scene."""
    pos = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]],
                   np.float32)
    nrm = np.tile(np.array([0.0, 0.0, 1.0], np.float32), (4, 1))
    uv = np.array([[0, 1], [4, 1], [4, 0], [0, 0]], np.float32)
    idx = np.array([0, 1, 2, 0, 2, 3], np.uint32)
    parts = (pos, nrm, uv, idx)
    offsets = np.cumsum([0, *(p.nbytes for p in parts)])
    blob = b"".join(p.tobytes() for p in parts)
    buffer = len(doc["buffers"])
    doc["buffers"].append({"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                           + base64.b64encode(blob).decode()})
    view0, acc0 = len(doc["bufferViews"]), len(doc["accessors"])
    doc["bufferViews"] += [{"buffer": buffer, "byteOffset": int(o), "byteLength": p.nbytes}
                           for o, p in zip(offsets, parts, strict=False)]
    doc["accessors"] += [
        {"bufferView": view0, "componentType": 5126, "count": 4, "type": "VEC3",
         "min": pos.min(0).tolist(), "max": pos.max(0).tolist()},
        {"bufferView": view0 + 1, "componentType": 5126, "count": 4, "type": "VEC3"},
        {"bufferView": view0 + 2, "componentType": 5126, "count": 4, "type": "VEC2"},
        {"bufferView": view0 + 3, "componentType": 5125, "count": 6, "type": "SCALAR"}]
    doc["meshes"].append({"name": "backdrop", "primitives": [{"attributes": {
        "POSITION": acc0, "NORMAL": acc0 + 1, "TEXCOORD_0": acc0 + 2}, "indices": acc0 + 3,
        "material": material}]})
    doc["nodes"].append({"mesh": len(doc["meshes"]) - 1})
    doc["scenes"][0]["nodes"].append(len(doc["nodes"]) - 1)
    return doc


def _glass(name: str, ior: float, dispersion: float, roughness: float = 0.0,
           attenuation: tuple = (1.0, 1.0, 1.0)) -> dict:
    extensions = {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                  "KHR_materials_volume": {"thicknessFactor": 2.0, "attenuationDistance": 2.0,
                                           "attenuationColor": list(attenuation)},
                  "KHR_materials_ior": {"ior": ior}}
    if dispersion > 0.0:
        extensions["KHR_materials_dispersion"] = {"dispersion": dispersion}
    return {"name": name, "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                                                    "metallicFactor": 0.0,
                                                    "roughnessFactor": roughness},
            "extensions": extensions}


def dispersion_spheres() -> dict:
    """KHR_materials_dispersion: glass spheres (a volume 2 thick, the diameter) in front of a
    striped backdrop that fills the view, so that both renderers' copies of the opaque scene
    hold the backdrop behind them (the viewer draws no environment into its copy when the
    background is off, vkpbr does): dispersion 0, 1 and 5 at ior 1.5, 3 at ior 1.8, a tinted
    one and a rough one."""
    materials = [
        _glass("d0", 1.5, 0.0), _glass("d1", 1.5, 1.0), _glass("d5", 1.5, 5.0),
        _glass("d3-ior1.8", 1.8, 3.0), _glass("tinted", 1.5, 3.0, attenuation=(0.9, 0.7, 0.5)),
        _glass("rough", 1.5, 3.0, roughness=0.3),
        {"name": "stripes", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                      "metallicFactor": 0.0, "roughnessFactor": 1.0}},
    ]
    doc = sphere_grid(materials[:6], "DispersionSpheres", images=(_stripes_png(),))
    doc["materials"] = materials
    return _add_backdrop(doc, -3.0, 12.0, 6)
