"""glTF COLOR_0 on the GPU: vertex colours multiply the base colour (RGB and alpha).

Two quads fill a 64x64 image side by side (the camera sits 1 / tan(fov / 2) from a 2 x 2 area,
so screen position is linear in the quads' x and y). The left quad has COLOR_0: the same
colour at its bottom vertices and another at its top, so the base colour varies linearly from
bottom to top; the right quad has none and must show the material's base colour alone. The
expected pixels are the glTF product base_color_factor * COLOR_0, sRGB-encoded for the
base_color view, written out here with the reference's sRGB curve.

Tolerance: 1/255 per channel (8-bit output; COLOR_0 is kept as 16-bit UNORM on the GPU).
A scene with no COLOR_0 anywhere reads one white value with stride 0: every other GPU test
covers that path, the right quad here covers a scene where only some meshes have colours.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from vkpbr.bake.bake import bake_scene
from vkpbr.reference.brdf import linear_to_srgb
from vkpbr.scene.baked_file import load_baked_scene, write_baked
from vkpbr.scene.types import Camera, Material, Mesh, Node, Scene

SIZE = 64
FOV = 60.0
FACTOR = np.array([0.8, 0.6, 1.0, 1.0], np.float32)
BOTTOM = np.array([1.0, 0.25, 0.0, 1.0], np.float32)
TOP = np.array([0.0, 0.5, 1.0, 0.5], np.float32)


def _quad(x0: float, x1: float, colors: np.ndarray | None) -> Mesh:
    pos = np.array([[x0, -1, 0], [x1, -1, 0], [x1, 1, 0], [x0, 1, 0]], np.float32)
    return Mesh("quad", pos, np.array([0, 1, 2, 0, 2, 3], np.uint32),
                normals=np.tile(np.float32([0, 0, 1]), (4, 1)),
                texcoords=np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32),
                colors=colors, material=0)


def _scene() -> Scene:
    colors = np.stack([BOTTOM, BOTTOM, TOP, TOP])
    d = 1.0 / math.tan(math.radians(FOV / 2))
    return Scene("vertex-colors", meshes=[_quad(-1.0, 0.0, colors), _quad(0.0, 1.0, None)],
                 materials=[Material(base_color_factor=tuple(FACTOR))],
                 nodes=[Node(0), Node(1)],
                 cameras=[Camera(eye=(0.0, 0.0, d), target=(0.0, 0.0, 0.0), yfov_deg=FOV)])


def _expected_left(rows: np.ndarray) -> np.ndarray:
    """Linear base colour (RGBA) of the left quad at pixel rows `rows` (row 0 at the top)."""
    t = 1.0 - (rows + 0.5) / SIZE  # 0 at the bottom edge, 1 at the top
    color = BOTTOM[None, :] * (1.0 - t[:, None]) + TOP[None, :] * t[:, None]
    return color * FACTOR[None, :]


def _check(render) -> None:  # noqa: ANN001 - (view) -> image
    rows = np.arange(SIZE)
    left, right = SIZE // 4, 3 * SIZE // 4
    base = render("base_color").astype(np.float64) / 255.0
    alpha = render("alpha").astype(np.float64) / 255.0
    want = _expected_left(rows)
    np.testing.assert_allclose(base[:, left, :3], linear_to_srgb(want[:, :3]), atol=1.0 / 255 + 1e-6)
    np.testing.assert_allclose(alpha[:, left, 0], want[:, 3], atol=1.0 / 255 + 1e-6)
    np.testing.assert_allclose(base[:, right, :3], np.broadcast_to(linear_to_srgb(FACTOR[:3]), (SIZE, 3)),
                               atol=1.0 / 255 + 1e-6)
    np.testing.assert_allclose(alpha[:, right, 0], 1.0, atol=1.0 / 255 + 1e-6)


def test_color0_multiplies_base_colour_and_alpha(make_renderer) -> None:
    r = make_renderer(_scene())
    _check(lambda view: r.render(size=(SIZE, SIZE), view=view))


def test_color0_survives_bake(make_renderer, tmp_path: Path) -> None:
    path = tmp_path / "colors.vkpbr"
    write_baked(path, bake_scene(_scene(), progress=False))
    r = make_renderer(load_baked_scene(path))
    _check(lambda view: r.render(size=(SIZE, SIZE), view=view))
