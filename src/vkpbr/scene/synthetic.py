"""Synthetic scenes for benchmarks (many draws and many triangles) and for the fidelity checks
of docs/fidelity.md (a white furnace of spheres, a texture plane that shows its mip levels),
made in NumPy."""

from __future__ import annotations

import numpy as np

from vkpbr.scene.default import uv_sphere
from vkpbr.scene.types import Camera, Image, Light, Material, Mesh, Node, Sampler, Scene, TextureRef

__all__ = ["sphere_field", "FURNACE_METALLIC", "FURNACE_ROUGHNESS", "furnace_spheres",
           "furnace_cells", "furnace_size", "MIP_COLORS", "mip_texture", "mip_plane"]


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


# The white furnace (docs/fidelity.md): a row of spheres per metallic value, a column per
# roughness value (issue 34's grid).
FURNACE_METALLIC = (0.0, 0.25, 0.5, 0.75, 1.0)
FURNACE_ROUGHNESS = tuple(round(0.1 * k, 1) for k in range(11))
_FURNACE_SPACING = 1.0
_FURNACE_DISTANCE = 60.0


def furnace_spheres(color: tuple[float, float, float] = (1.0, 1.0, 1.0), rings: int = 16,
                    segments: int = 32) -> Scene:
    """White spheres (radius 0.45, a material each) on a plane grid facing +Z: row i (top
    first) has metallic FURNACE_METALLIC[i], column j roughness FURNACE_ROUGHNESS[j]. The
    camera looks down -Z from far away through a narrow field of view (nearly orthographic),
    framing the grid with half a cell of margin; `furnace_cells` tells each pixel's sphere.
    In a uniform environment of radiance L with no other light, an energy-conserving BRDF
    returns L at every pixel of every sphere."""
    base = uv_sphere(0.45, rings, segments)
    meshes, mats, nodes = [], [], []
    for i, metallic in enumerate(FURNACE_METALLIC):
        for j, rough in enumerate(FURNACE_ROUGHNESS):
            k = len(mats)
            mats.append(Material(name=f"m{metallic}-r{rough}", base_color_factor=(*color, 1.0),
                                 metallic_factor=metallic, roughness_factor=rough))
            meshes.append(Mesh(name=f"sphere{k}", positions=base.positions, indices=base.indices,
                               normals=base.normals, texcoords=base.texcoords,
                               tangents=base.tangents, material=k))
            m = np.eye(4, dtype=np.float32)
            m[:3, 3] = _furnace_centre(i, j)
            nodes.append(Node(mesh=k, matrix=m))
    half_h = 0.5 * len(FURNACE_METALLIC) * _FURNACE_SPACING
    yfov = float(np.degrees(2.0 * np.arctan(half_h / _FURNACE_DISTANCE)))
    cam = Camera(eye=(0.0, 0.0, _FURNACE_DISTANCE), target=(0.0, 0.0, 0.0), yfov_deg=yfov,
                 znear=_FURNACE_DISTANCE - 2.0, zfar=_FURNACE_DISTANCE + 2.0)
    return Scene(name="white furnace", meshes=meshes, materials=mats, nodes=nodes, lights=[],
                 cameras=[cam])


def _furnace_centre(row: int, col: int) -> tuple[float, float, float]:
    rows, cols = len(FURNACE_METALLIC), len(FURNACE_ROUGHNESS)
    return ((col - (cols - 1) / 2) * _FURNACE_SPACING, ((rows - 1) / 2 - row) * _FURNACE_SPACING,
            0.0)


def furnace_size(cell: int) -> tuple[int, int]:
    """The image size (W, H) that gives each sphere's cell `cell` pixels a side."""
    return len(FURNACE_ROUGHNESS) * cell, len(FURNACE_METALLIC) * cell


def furnace_cells(camera: Camera, size: tuple[int, int]) -> np.ndarray:
    """(H, W) int: the index row * columns + column of the sphere whose projected centre is
    nearest each pixel's centre (the spheres' cells; coverage is the caller's: depth)."""
    K = camera.intrinsics(size)
    cam_from_world = np.linalg.inv(camera.world_from_camera("opencv"))
    centres = np.array([_furnace_centre(i, j) for i in range(len(FURNACE_METALLIC))
                        for j in range(len(FURNACE_ROUGHNESS))])
    p = (cam_from_world[:3, :3] @ centres.T).T + cam_from_world[:3, 3]
    uv = (K @ p.T).T
    uv = uv[:, :2] / uv[:, 2:]
    w, h = size
    y, x = np.mgrid[0:h, 0:w]
    d2 = (x[..., None] - uv[:, 0]) ** 2 + (y[..., None] - uv[:, 1]) ** 2
    return np.argmin(d2, axis=-1)


# The level-of-detail plane (docs/fidelity.md): level 0 a one-texel checkerboard, every level
# below it one flat colour of its own, so that the colour a pixel gets says which levels the
# sampler blended (and a level-of-detail difference between two renderers is a colour
# difference, not a subtle blur).
MIP_COLORS = ((255, 0, 0), (255, 160, 0), (255, 255, 0), (0, 200, 0), (0, 220, 255),
              (0, 60, 255), (160, 0, 255), (255, 0, 160), (110, 70, 30), (0, 0, 0), (255, 255, 255))


def mip_texture(texels: int = 256) -> Image:
    """A `texels`-square image (a power of two) whose level 0 is a black-and-white one-texel
    checkerboard and whose level k >= 1 is MIP_COLORS[k - 1] (sRGB colour)."""
    y, x = np.mgrid[0:texels, 0:texels]
    c = ((x + y) % 2 * 255).astype(np.uint8)
    level0 = np.stack([c, c, c, np.full_like(c, 255)], -1)
    mips, side, k = [], texels // 2, 0
    while side >= 1:
        rgb = np.broadcast_to(np.uint8(MIP_COLORS[k % len(MIP_COLORS)]), (side, side, 3))
        mips.append(np.concatenate([rgb, np.full((side, side, 1), 255, np.uint8)], -1))
        side, k = side // 2, k + 1
    return Image("mip colours", pixels=level0, mips=tuple(mips), mips_srgb=True)


def mip_plane(extent: float = 200.0, repeats: float = 12.0, cells: int = 8) -> Scene:
    """A ground plane `extent` wide (y = 0, a grid of cells x cells quads) textured with
    `mip_texture` repeated `repeats` times across it, and a camera 1 unit above it looking
    along it: the level of detail runs from magnified texels at the bottom of the image to
    the smallest levels at the horizon, at every anisotropy. The camera leaves its near plane
    to the renderer (a small one: the scene's bounds surround the eye, as inside a building)."""
    g = np.linspace(-extent / 2, extent / 2, cells + 1, dtype=np.float32)
    gx, gz = np.meshgrid(g, g, indexing="xy")
    pos = np.stack([gx, np.zeros_like(gx), gz], -1).reshape(-1, 3)
    uv = ((pos[:, [0, 2]] / extent + 0.5) * repeats).astype(np.float32)
    a = (np.arange(cells)[:, None] * (cells + 1) + np.arange(cells)[None, :]).reshape(-1, 1)
    quads = np.concatenate([a, a + cells + 1, a + 1, a + 1, a + cells + 1, a + cells + 2], 1)
    mesh = Mesh("plane", pos, quads.reshape(-1).astype(np.uint32),
                normals=np.tile(np.float32([0, 1, 0]), (len(pos), 1)), texcoords=uv, material=0)
    mat = Material(name="mip colours", base_color_texture=TextureRef(0, Sampler()),
                   double_sided=True)
    return Scene("mip plane", meshes=[mesh], materials=[mat], images=[mip_texture()],
                 nodes=[Node(0)], lights=[],
                 cameras=[Camera(eye=(60.0, 1.0, 70.0), target=(20.0, 0.2, 10.0), yfov_deg=50.0)])
