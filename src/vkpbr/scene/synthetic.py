"""Synthetic scenes for benchmarks: many draws and many triangles, made in NumPy."""

from __future__ import annotations

import numpy as np

from vkpbr.scene.default import uv_sphere
from vkpbr.scene.types import Camera, Light, Material, Mesh, Node, Scene

__all__ = ["sphere_field"]


def sphere_field(draws: int = 5000, rings: int = 16, segments: int = 32, materials: int = 64,
                 seed: int = 0, instanced: bool = False) -> Scene:
    """`draws` sphere instances (2 * rings * segments triangles each) on a jittered grid,
    sharing `materials` meshes (one per material): draws and triangles scale independently
    of loading cost. 5000 draws of 16 x 32 spheres = 5.12 M triangles; of 32 x 64, 20.5 M.
    `instanced`: one node per mesh holding its spheres as `Node.instances` (as glTF's
    EXT_mesh_gpu_instancing), the same spheres at the same places."""
    rng = np.random.default_rng(seed)
    base = uv_sphere(0.4, rings, segments)
    meshes, mats = [], []
    for i in range(materials):
        mats.append(Material(name=f"m{i}", base_color_factor=(*rng.uniform(0.2, 0.95, 3), 1.0),
                             metallic_factor=float(rng.uniform()), roughness_factor=float(rng.uniform(0.1, 1))))
        meshes.append(Mesh(name=f"sphere{i}", positions=base.positions, indices=base.indices,
                           normals=base.normals, texcoords=base.texcoords, tangents=base.tangents, material=i))
    side = int(np.ceil(np.sqrt(draws)))
    k = np.arange(draws)
    places = np.tile(np.eye(4, dtype=np.float32), (draws, 1, 1))
    places[:, 0, 3] = (k % side) - side / 2
    places[:, 1, 3] = rng.uniform(0, 0.5, draws)  # the same draws as one call a sphere
    places[:, 2, 3] = (k // side) - side / 2
    if instanced:
        nodes = [Node(mesh=i, instances=places[k % materials == i]) for i in range(materials)
                 if np.any(k % materials == i)]
    else:
        nodes = [Node(mesh=int(i % materials), matrix=places[i]) for i in range(draws)]
    half = side / 2
    return Scene(
        name=f"spheres-{draws}",
        meshes=meshes, materials=mats, nodes=nodes,
        lights=[Light(position=(0.0, half, 0.0), intensity=1.0)],
        cameras=[Camera(eye=(0.0, 0.8 * half, 1.3 * half), target=(0.0, 0.0, 0.0), yfov_deg=60.0,
                        znear=0.1, zfar=4 * half + 10)],
    )
