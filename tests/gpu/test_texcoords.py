"""TEXCOORD_1 and per-texture KHR_texture_transform on the GPU.

A quad fills the screen exactly (camera at distance 1 / tan(fov / 2) from a 2 x 2 quad), so the
pixel at row i, column j of a W x H image sees TEXCOORD_0 = ((j + 0.5) / W, (i + 0.5) / H), and
TEXCOORD_1 is laid out differently: (1 - v0, u0), a quarter turn. Every material texture reads
its own UV set through its own transform; the expected pixels come from the glTF equations
written out here (T, R, S as 3x3 matrices), independently of the renderer's packing.

Tolerance: 1/255 per channel, the rounding of an 8-bit target (data views) or of an sRGB
decode + encode round trip (colour views). Nearest-filtered 4x4 textures make each pixel's
expected value one texel; pixels whose coordinate lies within 0.05 texel of a texel edge are
left out (the GPU's float rounding may pick either neighbour there).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from vkpbr.bake.bake import bake_scene
from vkpbr.render import layouts as L
from vkpbr.render.gpu_scene import uv_transform_rows
from vkpbr.scene.baked_file import load_baked_scene, write_baked
from vkpbr.scene.types import Camera, Image, Material, Mesh, Node, Sampler, Scene, TextureRef

SIZE = 64  # pixels per side
TEXELS = 4  # texels per side of the test texture
FOV = 60.0
MARGIN = 0.05  # texels: leave out pixels this close to a texel edge
NEAREST = Sampler(mag_filter="nearest", min_filter="nearest", mipmaps=False)

# Each texture: its own UV set and transform, all different from one another (and from the
# base colour's), so a renderer that shares one set or one transform gets them wrong.
REFS = {
    "base_color": TextureRef(0, NEAREST, texcoord=1, offset=(0.1, 0.2), rotation=0.3, scale=(1.5, 0.75)),
    "metallic": TextureRef(0, NEAREST, texcoord=0, offset=(0.5, 0.0), scale=(2.0, 2.0)),
    "roughness": TextureRef(0, NEAREST, texcoord=1),
    "normal": TextureRef(0, NEAREST, texcoord=0, offset=(0.25, -0.1), rotation=-0.5, scale=(1.0, 1.25)),
    "occlusion": TextureRef(0, NEAREST, texcoord=0, offset=(0.3, 0.6), rotation=math.pi / 2),
    "emissive": TextureRef(0, NEAREST, texcoord=1, offset=(0.0, 0.5), rotation=1.0, scale=(0.5, 2.0)),
}
VIEWS = {"base_color": "base_color", "metallic": "metallic", "roughness": "roughness",
         "normal": "mapped_normal", "occlusion": "occlusion", "emissive": "emissive"}


# --- the scene ------------------------------------------------------------------------------
def texture_pixels() -> np.ndarray:
    """(4, 4, 4) uint8: texel k = 4 row + col has R = 20 + 15 k (>= the roughness clamp),
    G = 245 - 15 k and B = 230 (so that it is also a valid tangent-space normal)."""
    k = np.arange(TEXELS * TEXELS).reshape(TEXELS, TEXELS)
    rgba = np.stack([20 + 15 * k, 245 - 15 * k, np.full_like(k, 230), np.full_like(k, 255)], -1)
    return rgba.astype(np.uint8)


def uv1_from_uv0(uv0: np.ndarray) -> np.ndarray:
    return np.stack([1.0 - uv0[..., 1], uv0[..., 0]], axis=-1).astype(np.float32)


def quad(x0: float = -1.0, x1: float = 1.0, uv1: bool = True, tangents: bool = True) -> Mesh:
    """A quad facing +Z over x in [x0, x1], y in [-1, 1]; TEXCOORD_0 spans [0, 1] over it."""
    pos = np.array([[x0, -1, 0], [x1, -1, 0], [x1, 1, 0], [x0, 1, 0]], np.float32)
    uv0 = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32)
    return Mesh("quad", pos, np.array([0, 1, 2, 0, 2, 3], np.uint32),
                normals=np.tile(np.float32([0, 0, 1]), (4, 1)), texcoords=uv0,
                texcoords1=uv1_from_uv0(uv0) if uv1 else None,
                tangents=np.tile(np.float32([1, 0, 0, 1]), (4, 1)) if tangents else None, material=0)


def scene(meshes: list[Mesh], refs: dict[str, TextureRef]) -> Scene:
    mat = Material(metallic_factor=1.0, roughness_factor=1.0, emissive_factor=(1.0, 1.0, 1.0),
                   **{f"{slot}_texture": ref for slot, ref in refs.items()})
    d = 1.0 / math.tan(math.radians(FOV / 2))
    return Scene("texcoords", meshes=meshes, materials=[mat],
                 images=[Image("grid", pixels=texture_pixels())],
                 nodes=[Node(i) for i in range(len(meshes))],
                 cameras=[Camera(eye=(0.0, 0.0, d), target=(0.0, 0.0, 0.0), yfov_deg=FOV)])


# --- what the equations predict -------------------------------------------------------------
def pixel_uv0(x0: float = -1.0, x1: float = 1.0) -> np.ndarray:
    """(SIZE, SIZE, 2) TEXCOORD_0 at each pixel centre for quad(x0, x1) (outside: unused)."""
    c = (np.arange(SIZE) + 0.5) / SIZE
    x = -1.0 + 2.0 * c
    u = np.broadcast_to(((x - x0) / (x1 - x0))[None, :], (SIZE, SIZE))
    v = np.broadcast_to(c[:, None], (SIZE, SIZE))
    return np.stack([u, v], axis=-1)


def gltf_transform(ref: TextureRef, uv: np.ndarray) -> np.ndarray:
    """KHR_texture_transform as its spec writes it: uv' = T R S (u, v, 1)."""
    (ox, oy), (sx, sy), r = ref.offset, ref.scale, ref.rotation
    t = np.array([[1, 0, ox], [0, 1, oy], [0, 0, 1]], np.float64)
    rot = np.array([[math.cos(r), math.sin(r), 0], [-math.sin(r), math.cos(r), 0], [0, 0, 1]])
    s = np.diag([sx, sy, 1.0])
    h = np.concatenate([uv, np.ones(uv.shape[:-1] + (1,))], axis=-1)
    return (h @ (t @ rot @ s).T)[..., :2]


def texture_uv(ref: TextureRef, uv0: np.ndarray) -> np.ndarray:
    return gltf_transform(ref, uv1_from_uv0(uv0) if ref.texcoord == 1 else uv0)


def nearest_texels(uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(texel RGBA per pixel, mask of pixels safely inside a texel), repeat wrapping."""
    t = uv * TEXELS
    frac = t - np.floor(t)
    safe = np.all((frac > MARGIN) & (frac < 1.0 - MARGIN), axis=-1)
    col, row = (np.floor(t).astype(int) % TEXELS).transpose(2, 0, 1)
    return texture_pixels()[row, col], safe


def expected_view(slot: str, texel: np.ndarray) -> np.ndarray:
    """The 8-bit RGB the view shows for a texel (factors are 1, occlusion strength 1)."""
    rgb = texel[..., :3].astype(np.float64)
    if slot in ("base_color", "emissive"):  # sRGB texture decoded, the view encodes again
        return rgb
    if slot == "normal":  # tangent frame = world axes here: n = normalize(2 t - 1)
        n = rgb / 255.0 * 2.0 - 1.0
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        return (n * 0.5 + 0.5) * 255.0
    return np.repeat(rgb[..., :1], 3, axis=-1)  # scalar maps read R


def assert_close(got: np.ndarray, want: np.ndarray, mask: np.ndarray, what: str) -> None:
    assert mask.mean() > 0.5, f"{what}: too few pixels away from texel edges"
    diff = np.abs(got[..., :3].astype(np.float64) - want)[mask]
    assert diff.max() <= 1.0 + 1e-6, f"{what}: off by up to {diff.max():.1f}/255"


# --- tests ----------------------------------------------------------------------------------
def test_uv_transform_rows_are_the_gltf_matrix() -> None:
    """The MATERIAL rows hold T R S's top two rows, and the UV set in row 0's w."""
    for ref in REFS.values():
        r0, r1 = uv_transform_rows(ref)
        uv = np.array([[0.3, 0.7], [-1.0, 2.0]])
        h = np.concatenate([uv, np.ones((2, 1))], axis=1)
        packed = np.stack([h @ np.array(r0[:3]), h @ np.array(r1[:3])], axis=-1)
        np.testing.assert_allclose(packed, gltf_transform(ref, uv), atol=1e-12)
        assert (r0[3], r1[3]) == (float(ref.texcoord), 0.0)
    assert uv_transform_rows(None) == ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0))


def test_each_texture_reads_its_own_set_and_transform(make_renderer) -> None:
    """Base colour, metallic, roughness, normal, occlusion and emissive views each show the
    texel that their own UV set and transform select."""
    r = make_renderer(scene([quad()], REFS))
    uv0 = pixel_uv0()
    for slot, view in VIEWS.items():
        texel, safe = nearest_texels(texture_uv(REFS[slot], uv0))
        got = r.render(size=(SIZE, SIZE), view=view, lighting="course")  # the 0.02 ambient
        assert_close(got, expected_view(slot, texel), safe, slot)


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_packed_metallic_roughness_reads_its_two_channels(make_renderer, pipeline: str) -> None:
    """glTF's packed metallic-roughness texture (one image, sampler and transform; roughness
    in G) is sampled once through one view holding metallic in R and roughness in G
    (gpu_scene.py, MATERIAL_SHARED_METALLIC_ROUGHNESS): each view still shows its channel."""
    packed = TextureRef(0, NEAREST, texcoord=0, offset=(0.5, 0.0), scale=(2.0, 2.0))
    refs = {"metallic": packed, "roughness": dataclasses.replace(packed, channel=1)}
    r = make_renderer(scene([quad()], refs))
    assert r.gpu_scene.material_blocks[0]["flags"] & L.MATERIAL_SHARED_METALLIC_ROUGHNESS
    if pipeline == "compute" and not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    texel, safe = nearest_texels(texture_uv(packed, pixel_uv0()))
    for view, channel in (("metallic", 0), ("roughness", 1)):
        got = r.render(size=(SIZE, SIZE), view=view, lighting="course", pipeline=pipeline)
        want = np.repeat(texel[..., channel:channel + 1].astype(np.float64), 3, axis=-1)
        assert_close(got, want, safe, f"{view} ({pipeline})")


def test_texcoords_view_shows_base_colour_coordinates(make_renderer) -> None:
    """The texcoords view is fract(uv') of the base-colour texture: set 1, transformed."""
    r = make_renderer(scene([quad()], {"base_color": REFS["base_color"]}))
    uv = texture_uv(REFS["base_color"], pixel_uv0())
    f = uv - np.floor(uv)
    safe = np.all((f > 0.01) & (f < 0.99), axis=-1)  # fract jumps 1 -> 0 there
    want = np.concatenate([f, np.zeros(f.shape[:-1] + (1,))], axis=-1) * 255.0
    got = r.render(size=(SIZE, SIZE), view="texcoords")
    assert_close(got, want, safe, "texcoords")


def test_texcoord1_stream_only_when_a_mesh_has_one(make_renderer) -> None:
    """No TEXCOORD_1 anywhere: no stream (TEXCOORD_0's buffer is bound instead, no extra bytes)
    and set-1 textures read TEXCOORD_0. Some TEXCOORD_1: one stream, 8 bytes more per vertex,
    and a mesh without TEXCOORD_1 reads its TEXCOORD_0 (the fill) while its neighbour reads
    its own TEXCOORD_1."""
    ref = TextureRef(0, NEAREST, texcoord=1)
    plain = make_renderer(scene([quad(uv1=False)], {"base_color": ref}))
    gs = plain.gpu_scene
    assert gs.streams["texcoords1"] is gs.streams["texcoords"] and "texcoords1" not in gs.stream_bytes
    assert gs.bytes_per_vertex() == {"vectors": 48, "quat": 36, "packed": 24}
    uv0 = pixel_uv0()
    texel, safe = nearest_texels(uv0)
    assert_close(plain.render(size=(SIZE, SIZE), view="base_color"), texel[..., :3], safe, "no TEXCOORD_1")

    mixed = make_renderer(scene([quad(-1.0, 0.0, uv1=True), quad(0.0, 1.0, uv1=False)], {"base_color": ref}))
    gs = mixed.gpu_scene
    assert gs.stream_bytes["texcoords1"] == 8 * 8 and gs.bytes_per_vertex()["packed"] == 32
    left, right = pixel_uv0(-1.0, 0.0), pixel_uv0(0.0, 1.0)
    is_left = np.arange(SIZE)[None, :] < SIZE // 2
    uv = np.where(is_left[..., None], uv1_from_uv0(left), right)
    texel, safe = nearest_texels(uv)
    got = mixed.render(size=(SIZE, SIZE), view="base_color")
    assert_close(got, texel[..., :3], safe, "mixed scene")


@pytest.mark.parametrize("texcoord", [0, 1])
def test_generated_tangents_follow_the_normal_maps_set(make_renderer, tmp_path: Path, texcoord: int) -> None:
    """Without TANGENT, tangents point along +u of the set the normal texture reads (glTF):
    TEXCOORD_0's u grows to +X, TEXCOORD_1's (1 - v0) to +Y. Rendered from the scene and
    from its bake, which generates tangents itself."""
    source = scene([quad(tangents=False)], {"normal": TextureRef(0, NEAREST, texcoord=texcoord)})
    path = tmp_path / "quad.vkpbr"
    write_baked(path, bake_scene(source))
    want = np.array([255.0, 127.5, 127.5]) if texcoord == 0 else np.array([127.5, 255.0, 127.5])
    everywhere = np.ones((SIZE, SIZE), bool)
    for name, s in (("source", source), ("baked", load_baked_scene(path))):
        got = make_renderer(s).render(size=(SIZE, SIZE), view="tangent")
        assert_close(got, np.broadcast_to(want, (SIZE, SIZE, 3)), everywhere, f"{name} tangent")


def test_baked_scene_keeps_each_textures_set_and_transform(make_renderer, tmp_path: Path) -> None:
    """bake -> file -> load: the same material references and the same pixels in every view."""
    source = scene([quad(-1.0, 0.0), quad(0.0, 1.0, uv1=False)], REFS)
    path = tmp_path / "refs.vkpbr"
    write_baked(path, bake_scene(source))
    baked = load_baked_scene(path)
    for slot in REFS:
        a = getattr(baked.materials[0], f"{slot}_texture")
        assert dataclasses.replace(a, image=0) == REFS[slot], slot
    r_src, r_baked = make_renderer(source), make_renderer(baked)
    for view in (*VIEWS.values(), "texcoords"):
        a = r_src.render(size=(SIZE, SIZE), view=view).astype(int)
        b = r_baked.render(size=(SIZE, SIZE), view=view).astype(int)
        assert np.abs(a - b).max() <= 1, view
