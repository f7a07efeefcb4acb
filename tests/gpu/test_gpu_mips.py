"""Mip chains made once: a chain that comes with an image (a baked file's) is what the GPU
samples, uploaded level by level without blits; an image without one gets the GPU's blits; and
the NumPy chain (vkpbr.scene.mips) renders like the blits did.

A 2 x 2 quad fills an 8 x 8 pixel image (the camera at 1 / tan(fov / 2)) and carries a 64 x 64
texture, so each pixel spans 8 texels and samples mip level 3 at a texel centre. A chain whose
level 0 is red and every level below green therefore shows green when the file's levels are
used, and red when the GPU rebuilt the chain from level 0.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from goldens import GOLDENS, load, mismatch, render

from vkpbr.bake.bake import bake_scene
from vkpbr.scene.baked_file import load_baked_scene, write_baked
from vkpbr.scene.mips import mip_chain
from vkpbr.scene.textures import decode_images
from vkpbr.scene.types import Camera, Image, Material, Mesh, Node, Scene, TextureRef

SIZE = 8  # pixels per side: 64 texels / 8 pixels = level 3
TEXELS = 64
FOV = 60.0
RED, GREEN = (255, 0, 0, 255), (0, 255, 0, 255)


def marked_chain() -> list[np.ndarray]:
    """A valid chain's shapes, level 0 red and all others green (no filter makes this)."""
    shapes = [max(TEXELS >> k, 1) for k in range(TEXELS.bit_length())]
    return [np.full((s, s, 4), RED if k == 0 else GREEN, np.uint8) for k, s in enumerate(shapes)]


def quad_scene(image: Image, slot: str = "base_color") -> Scene:
    pos = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    mesh = Mesh("quad", pos, np.array([0, 1, 2, 0, 2, 3], np.uint32),
                normals=np.tile(np.float32([0, 0, 1]), (4, 1)),
                texcoords=np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32), material=0)
    d = 1.0 / math.tan(math.radians(FOV / 2))
    return Scene("mips", meshes=[mesh], materials=[Material(**{f"{slot}_texture": TextureRef(0)})],
                 images=[image], nodes=[Node(0)],
                 cameras=[Camera(eye=(0.0, 0.0, d), target=(0.0, 0.0, 0.0), yfov_deg=FOV)])


def test_baked_levels_are_uploaded_as_they_are(make_renderer, tmp_path: Path) -> None:
    levels = marked_chain()
    source = quad_scene(Image("marked", pixels=levels[0]))
    baked = bake_scene(source)
    baked.images[0].levels, baked.images[0].srgb = levels, True
    path = tmp_path / "marked.vkpbr"
    write_baked(path, baked)
    loaded = load_baked_scene(path)
    assert len(loaded.images[0].mips) == len(levels) - 1 and loaded.images[0].mips_srgb
    got = make_renderer(loaded).render(size=(SIZE, SIZE), view="base_color")
    assert (got[..., :3] == GREEN[:3]).all(), np.unique(got[..., :3].reshape(-1, 3), axis=0)
    # The same pixels without a chain: the GPU blits one from level 0 (red all the way down).
    got = make_renderer(source).render(size=(SIZE, SIZE), view="base_color")
    assert (got[..., :3] == RED[:3]).all(), np.unique(got[..., :3].reshape(-1, 3), axis=0)


def test_a_chain_for_the_other_colour_space_is_not_used(make_renderer) -> None:
    """An sRGB-filtered chain on an image used as a linear (metallic) map: rebuilt by blits.
    The metallic view shows R: 255 from the red level 0, where the green levels give 0."""
    levels = marked_chain()
    image = Image("marked", pixels=levels[0], mips=tuple(levels[1:]), mips_srgb=True)
    got = make_renderer(quad_scene(image, "metallic")).render(size=(SIZE, SIZE), view="metallic")
    assert (got[..., 0] == 255).all()
    image.mips_srgb = False  # now it is the right colour space: used
    got = make_renderer(quad_scene(image, "metallic")).render(size=(SIZE, SIZE), view="metallic")
    assert (got[..., 0] == 0).all()


def test_numpy_chain_renders_like_the_gpu_blits(make_renderer) -> None:
    """A smooth random texture seen at level 3: NumPy's chain against the GPU's blits, for an
    sRGB (base colour) and a linear (metallic) use. Within 2/255: lavapipe's UNORM blits round
    up by about 0.45 of a step per level on average (measured: mean +0.43 at level 1, +1.42 at
    level 3), the NumPy chain rounds to nearest; sRGB agrees to a mean of 0.2."""
    rng = np.random.default_rng(3)
    coarse = rng.integers(0, 256, (8, 8, 4), dtype=np.uint8)
    from PIL import Image as PILImage  # bilinear upscale: structure at every level

    rgba = np.asarray(PILImage.fromarray(coarse, "RGBA").resize((TEXELS, TEXELS), PILImage.BILINEAR))
    rgba = rgba.copy()
    rgba[..., 3] = 255
    for slot, srgb in (("base_color", True), ("metallic", False)):
        chain = mip_chain(rgba, srgb)
        blit = make_renderer(quad_scene(Image("t", pixels=rgba), slot))
        mine = make_renderer(quad_scene(Image("t", pixels=rgba, mips=tuple(chain[1:]),
                                              mips_srgb=srgb), slot))
        a = blit.render(size=(SIZE, SIZE), view=slot)[..., :3].astype(int)
        b = mine.render(size=(SIZE, SIZE), view=slot)[..., :3].astype(int)
        assert np.abs(a - b).max() <= 2, (slot, np.abs(a - b).max())
        assert len(np.unique(b)) > 10  # a textured view, not a constant


# Goldens of models with textures (the others have no mip chains to compare).
_UNTEXTURED = ("MetalRoughSpheresNoTextures", "OrientationTest")


@pytest.mark.parametrize("key", [k for k, g in GOLDENS.items()  # mips: one lighting mode will do
                                 if g.scene and g.lighting == "course"
                                 and not any(u in str(g.scene) for u in _UNTEXTURED)])
def test_goldens_hold_with_numpy_mip_chains(make_renderer, assets: Path, key: str) -> None:
    """Every textured golden (made with GPU blits) rendered from NumPy mip chains instead, as a
    baked file's would be: still within the golden's tolerance (measured on lavapipe: Sponza
    mean 0.90 of its 1.0, the sample models at most 0.16 of 0.5)."""
    golden = GOLDENS[key]
    scene = load(golden, assets)
    assert scene.images, f"{golden.scene} has no textures: list it in _UNTEXTURED"
    pixels = decode_images(scene)
    srgb = {t.image for m in scene.materials for t in (m.base_color_texture, m.emissive_texture) if t}
    scene.images = [img if px is None else dataclasses.replace(
        img, pixels=px, data=None, path=None, mips=tuple(mip_chain(px, i in srgb)[1:]), mips_srgb=i in srgb)
        for i, (img, px) in enumerate(zip(scene.images, pixels, strict=True))]
    r = make_renderer(scene)
    uploaded = [im for im in r.gpu_scene.images.values() if im.mip_levels > 1]
    assert uploaded  # textured
    why = mismatch(render(r, golden), golden, r.device.info.name)
    assert why is None, why
