"""The built-in default scene (no files): a PBR chart of spheres over a metalness x roughness
grid, a textured and normal-mapped floor, an alpha-masked card, one point light and a camera.

Every texture is generated here with NumPy, so `vkpbr render` works on a fresh install and
the golden-image test has no asset dependency.
"""

from __future__ import annotations

import numpy as np

from vkpbr.scene.types import Camera, Image, Light, Material, Mesh, Node, Sampler, Scene, TextureRef

__all__ = ["default_scene", "uv_sphere", "plane", "GRID"]

GRID = 5  # spheres per row and per column
SPACING = 1.1
RADIUS = 0.45


def uv_sphere(radius: float = 1.0, rings: int = 24, segments: int = 48) -> Mesh:
    """A UV sphere: u around the equator (+X towards -Z), v from the north pole down."""
    theta = np.linspace(0.0, np.pi, rings + 1)  # polar angle
    phi = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    n = np.stack([np.sin(t) * np.cos(p), np.cos(t), -np.sin(t) * np.sin(p)], axis=-1)
    tangent = np.stack([-np.sin(p), np.zeros_like(p), -np.cos(p)], axis=-1)
    uv = np.stack([p / (2 * np.pi), t / np.pi], axis=-1)
    tangents = np.concatenate([tangent, np.ones(t.shape + (1,))], axis=-1)
    r0 = np.arange(rings)[:, None] * (segments + 1)
    s0 = np.arange(segments)[None, :]
    a, b = r0 + s0, r0 + s0 + segments + 1  # this ring, next ring
    quads = np.stack([a, b, a + 1, a + 1, b, b + 1], axis=-1).reshape(-1)
    return Mesh(
        name="sphere",
        positions=(n * radius).reshape(-1, 3).astype(np.float32),
        normals=n.reshape(-1, 3).astype(np.float32),
        texcoords=uv.reshape(-1, 2).astype(np.float32),
        tangents=tangents.reshape(-1, 4).astype(np.float32),
        indices=quads.astype(np.uint32),
    )


def plane(width: float, depth: float, uv_repeat: float = 1.0, y: float = 0.0) -> Mesh:
    """A horizontal quad facing +Y; u grows with +X and v with +Z (so the image's top is at -Z)."""
    x, z = width / 2, depth / 2
    pos = np.array([[-x, y, -z], [x, y, -z], [x, y, z], [-x, y, z]], np.float32)
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32) * uv_repeat
    return Mesh(
        name="plane",
        positions=pos,
        normals=np.tile(np.array([0, 1, 0], np.float32), (4, 1)),
        texcoords=uv,
        tangents=np.tile(np.array([1, 0, 0, 1], np.float32), (4, 1)),
        indices=np.array([0, 2, 1, 0, 3, 2], np.uint32),
    )


def _card(width: float, height: float) -> Mesh:
    """A vertical quad in the XY plane facing +Z."""
    x, y = width / 2, height
    pos = np.array([[-x, 0, 0], [x, 0, 0], [x, y, 0], [-x, y, 0]], np.float32)
    uv = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32)
    return Mesh(
        name="card",
        positions=pos,
        normals=np.tile(np.array([0, 0, 1], np.float32), (4, 1)),
        texcoords=uv,
        tangents=np.tile(np.array([1, 0, 0, 1], np.float32), (4, 1)),
        indices=np.array([0, 1, 2, 0, 2, 3], np.uint32),
    )


def _rgba(rgb: np.ndarray, alpha: np.ndarray | None = None) -> np.ndarray:
    a = np.ones(rgb.shape[:2]) if alpha is None else alpha
    out = np.concatenate([rgb, a[..., None]], axis=-1)
    return np.clip(np.round(out * 255.0), 0, 255).astype(np.uint8)


def _floor_textures(size: int = 256) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Checker base colour (sRGB bytes), a bump normal map, a roughness map and an ambient
    occlusion map darkening the grooves between the bumps (all linear)."""
    v, u = (np.mgrid[0:size, 0:size] + 0.5) / size
    tiles = 8
    checker = ((np.floor(u * tiles) + np.floor(v * tiles)) % 2).astype(np.float64)
    base = np.where(checker[..., None] > 0, [0.80, 0.78, 0.72], [0.30, 0.32, 0.36])
    # Height field: a rounded bump in every tile; normal = normalize(-dh/du, +dh/dv, 1)
    # (tangent-space +Y is "up" in the image, i.e. towards smaller v).
    fu, fv = (u * tiles) % 1.0 - 0.5, (v * tiles) % 1.0 - 0.5
    r2 = np.clip(1.0 - (fu**2 + fv**2) / 0.2, 0.0, None)
    strength = 0.6
    dh_du, dh_dv = -2 * fu * (r2 > 0) * strength, -2 * fv * (r2 > 0) * strength
    n = np.stack([-dh_du, dh_dv, np.ones_like(u)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    rough = 0.35 + 0.4 * checker
    occlusion = 0.35 + 0.65 * np.sqrt(r2)
    grey = lambda x: _rgba(np.repeat(x[..., None], 3, axis=-1))  # noqa: E731
    return _rgba(base), _rgba(n * 0.5 + 0.5), grey(rough), grey(occlusion)


def _card_texture(size: int = 128) -> np.ndarray:
    """A leaf-green card with a grid of round holes in its alpha (for the masked pipeline)."""
    v, u = (np.mgrid[0:size, 0:size] + 0.5) / size
    holes = 4
    fu, fv = (u * holes) % 1.0 - 0.5, (v * holes) % 1.0 - 0.5
    alpha = ((fu**2 + fv**2) > 0.09).astype(np.float64)
    rgb = np.stack([0.2 + 0.3 * u, 0.55 + 0.2 * v, 0.15 * np.ones_like(u)], axis=-1)
    return _rgba(rgb, alpha)


def default_scene() -> Scene:
    """The PBR chart: GRID x GRID spheres (metalness grows left to right, roughness bottom
    to top), a normal-mapped floor, a masked card, the light and a framing camera."""
    floor_base, floor_normal, floor_rough, floor_occlusion = _floor_textures()
    images = [
        Image(name="floor-base-color", pixels=floor_base),
        Image(name="floor-normal", pixels=floor_normal),
        Image(name="floor-roughness", pixels=floor_rough),
        Image(name="card-base-color", pixels=_card_texture()),
        Image(name="floor-occlusion", pixels=floor_occlusion),
    ]
    repeat = Sampler()
    materials: list[Material] = []
    nodes: list[Node] = []
    meshes = [
        uv_sphere(RADIUS),
        plane(8.0, 8.0, uv_repeat=2.0),
        _card(1.6, 1.6),
        uv_sphere(0.12, 12, 24),
    ]
    span = (GRID - 1) * SPACING
    for row in range(GRID):  # roughness
        for col in range(GRID):  # metalness
            materials.append(
                Material(
                    name=f"sphere-m{col}-r{row}",
                    base_color_factor=(0.95, 0.45, 0.25, 1.0),
                    metallic_factor=col / (GRID - 1),
                    roughness_factor=0.05 + 0.95 * row / (GRID - 1),
                )
            )
            m = np.eye(4, dtype=np.float32)
            m[:3, 3] = (col * SPACING - span / 2, 0.5 + row * SPACING, 0.0)
            nodes.append(Node(mesh=0, matrix=m, name=materials[-1].name))
    materials.append(
        Material(
            name="floor",
            metallic_factor=0.0,
            base_color_texture=TextureRef(0, repeat),
            normal_texture=TextureRef(1, repeat),
            roughness_texture=TextureRef(2, repeat, channel=0),
            occlusion_texture=TextureRef(4, repeat),
        )
    )
    floor = np.eye(4, dtype=np.float32)
    floor[:3, 3] = (0.0, -0.05, 1.5)
    nodes.append(Node(mesh=1, matrix=floor, name="floor"))
    materials.append(
        Material(
            name="card",
            metallic_factor=0.0,
            roughness_factor=0.6,
            alpha_mode="mask",
            alpha_cutoff=0.5,
            double_sided=True,
            base_color_texture=TextureRef(3, Sampler(wrap_s="clamp", wrap_t="clamp")),
        )
    )
    card = np.eye(4, dtype=np.float32)
    card[:3, 3] = (span / 2 + 1.4, -0.05, 1.2)
    angle = np.radians(-35.0)
    card[:3, :3] = [
        [np.cos(angle), 0, np.sin(angle)],
        [0, 1, 0],
        [-np.sin(angle), 0, np.cos(angle)],
    ]
    nodes.append(Node(mesh=2, matrix=card, name="card"))
    # A Mesh carries its material, so each sphere is a Mesh sharing the same arrays.
    sphere_meshes = []
    for i in range(GRID * GRID):
        mesh = meshes[0]
        sphere_meshes.append(
            Mesh(
                name=f"sphere{i}",
                positions=mesh.positions,
                indices=mesh.indices,
                normals=mesh.normals,
                texcoords=mesh.texcoords,
                tangents=mesh.tangents,
                material=i,
            )
        )
    # A small emissive bulb marks the light (the light sits inside it, so only Le shows).
    light = Light(position=(-2.6, 4.3, 2.5), color=(1.0, 1.0, 1.0), intensity=3.0)
    materials.append(
        Material(
            name="bulb",
            base_color_factor=(0, 0, 0, 1),
            metallic_factor=0.0,
            emissive_factor=(1.0, 0.95, 0.8),
            casts_shadows=False,  # the light inside it would be in its shadow
        )
    )
    bulb = np.eye(4, dtype=np.float32)
    bulb[:3, 3] = light.position
    nodes.append(Node(mesh=3, matrix=bulb, name="bulb"))
    floor_mesh, card_mesh, bulb_mesh = meshes[1], meshes[2], meshes[3]
    floor_mesh.material, card_mesh.material = GRID * GRID, GRID * GRID + 1
    bulb_mesh.material = GRID * GRID + 2
    all_meshes = sphere_meshes + [floor_mesh, card_mesh, bulb_mesh]
    for i, node in enumerate(nodes):
        node.mesh = i
    return Scene(
        name="default",
        meshes=all_meshes,
        materials=materials,
        images=images,
        nodes=nodes,
        lights=[light],
        cameras=[
            Camera(
                eye=(0.6, 3.2, 9.0), target=(0.4, 2.2, 0.0), yfov_deg=45.0, znear=0.1, zfar=100.0
            )
        ],
    )
