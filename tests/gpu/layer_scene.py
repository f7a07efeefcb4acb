"""A generated glTF file of six spheres, one per KHR_materials_* layer (the Khronos sample
models for these extensions cannot be fetched here), for test_material_layers.py's golden:
top row clearcoat over rough red, sheen over dark blue, ior 2.4 with a tinted specular
colour; bottom row a thick transmissive sphere with an orange volume, a thin transmissive one
(thickness 0) and an unlit green one. A variant "blue-coat" swaps the first sphere's material
(KHR_materials_variants)."""

from __future__ import annotations

import base64
import json
from pathlib import Path

import numpy as np

from vkpbr.scene.default import uv_sphere

CAMERA = "0,0.3,8.5,0,0,0"  # eye, target: the whole grid at 160x120, 45 degrees
MATERIALS = [
    {"name": "clearcoat", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.08, 0.05, 1],
                                                    "metallicFactor": 0, "roughnessFactor": 0.8},
     "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0,
                                                "clearcoatRoughnessFactor": 0.05}}},
    {"name": "sheen", "pbrMetallicRoughness": {"baseColorFactor": [0.05, 0.06, 0.25, 1],
                                                "metallicFactor": 0, "roughnessFactor": 0.9},
     "extensions": {"KHR_materials_sheen": {"sheenColorFactor": [1.0, 0.7, 0.8],
                                            "sheenRoughnessFactor": 0.4}}},
    {"name": "ior-specular", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.1, 0.1, 1],
                                                       "metallicFactor": 0, "roughnessFactor": 0.2},
     "extensions": {"KHR_materials_ior": {"ior": 2.4},
                    "KHR_materials_specular": {"specularColorFactor": [1.0, 0.8, 0.3]}}},
    {"name": "volume", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1],
                                                 "metallicFactor": 0, "roughnessFactor": 0.1},
     "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                    "KHR_materials_ior": {"ior": 1.5},
                    "KHR_materials_volume": {"thicknessFactor": 2.0, "attenuationDistance": 1.0,
                                             "attenuationColor": [1.0, 0.5, 0.1]}}},
    {"name": "thin", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 1, 0.9, 1],
                                               "metallicFactor": 0, "roughnessFactor": 0.3},
     "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.9}}},
    {"name": "unlit", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.6, 0.2, 1]},
     "extensions": {"KHR_materials_unlit": {}}},
    {"name": "blue-coat", "pbrMetallicRoughness": {"baseColorFactor": [0.05, 0.1, 0.7, 1],
                                                    "metallicFactor": 0, "roughnessFactor": 0.8},
     "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0}}},
]


def write_layer_spheres(path: Path) -> Path:
    """Write the six-sphere .gltf (one embedded buffer) to `path`; returns it."""
    sphere = uv_sphere(1.0, 24, 48)
    pos = np.ascontiguousarray(sphere.positions, np.float32)
    nrm = np.ascontiguousarray(sphere.normals, np.float32)
    idx = np.ascontiguousarray(sphere.indices, np.uint32)
    blob = pos.tobytes() + nrm.tobytes() + idx.tobytes()
    views = [{"buffer": 0, "byteOffset": 0, "byteLength": pos.nbytes},
             {"buffer": 0, "byteOffset": pos.nbytes, "byteLength": nrm.nbytes},
             {"buffer": 0, "byteOffset": pos.nbytes + nrm.nbytes, "byteLength": idx.nbytes}]
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": len(pos), "type": "VEC3",
         "min": pos.min(0).tolist(), "max": pos.max(0).tolist()},
        {"bufferView": 1, "componentType": 5126, "count": len(nrm), "type": "VEC3"},
        {"bufferView": 2, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
    ]
    meshes, nodes = [], []
    for k in range(6):
        prim = {"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": k}
        if k == 0:
            prim["extensions"] = {"KHR_materials_variants": {"mappings": [
                {"material": 6, "variants": [0]}]}}
        meshes.append({"name": MATERIALS[k]["name"], "primitives": [prim]})
        row, col = divmod(k, 3)
        nodes.append({"mesh": k, "translation": [(col - 1) * 2.4, 1.2 - 2.4 * row, 0.0]})
    used = sorted({e for m in MATERIALS for e in m.get("extensions", {})}
                  | {"KHR_materials_variants"})
    doc = {
        "asset": {"version": "2.0", "generator": "vkpbr tests/gpu/layer_scene.py"},
        "extensionsUsed": used,
        "extensions": {"KHR_materials_variants": {"variants": [{"name": "blue-coat"}]}},
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(blob).decode()}],
        "bufferViews": views, "accessors": accessors, "materials": MATERIALS,
        "meshes": meshes, "nodes": nodes, "scenes": [{"nodes": list(range(6))}], "scene": 0,
    }
    path.write_text(json.dumps(doc))
    return path
