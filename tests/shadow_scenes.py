"""Shadow test scenes and their NumPy ray cast (tests/gpu/test_shadow_factor.py, test_shadows.py):
axis-aligned horizontal rectangles (a ground, a block, an alpha-masked card with a square
hole) lit by one light of each type, and per pixel: which rectangle the camera ray hits,
whether the segment from there to the light hits another (holes let it through), and a
penumbra band where that segment passes within a few shadow-map texels of an occluder's or
a hole's border (where PCF blurs and the biases shift the edge)."""

from __future__ import annotations

import numpy as np
from pinhole import pixel_rays

from vkpbr.scene.default import plane
from vkpbr.scene.types import Camera, Image, Light, Material, Node, Scene, TextureRef

# (y, x0, x1, z0, z1, hole): the hole is (lo, hi) of the texture's unit square, or None.
GROUND = (0.0, -4.0, 4.0, -4.0, 4.0, None)
BLOCK = (1.0, -1.0, 0.8, -1.0, 0.9, None)
CARD = (0.8, 1.2, 2.4, -0.6, 0.6, (0.3, 0.7))
CAMERA = Camera(eye=(0.0, 5.0, 6.0), target=(0.3, 0.0, 0.0), yfov_deg=55.0)


def unit(*v: float) -> tuple[float, ...]:
    a = np.asarray(v, float)
    return tuple(a / np.linalg.norm(a))


LIGHTS = {
    "directional": Light(kind="directional", direction=unit(0.35, -1.0, 0.25)),
    "spot": Light(kind="spot", position=(0.3, 3.5, 0.2), direction=unit(0.05, -1.0, 0.0),
                  outer_cone=0.8),
    "point": Light(kind="point", position=(0.2, 2.6, 0.1)),
}


def _rect_mesh(r):  # noqa: ANN001, ANN202
    y, x0, x1, z0, z1, _ = r
    m = plane(x1 - x0, z1 - z0, y=y)
    m.positions = m.positions + np.array([(x0 + x1) / 2, 0, (z0 + z1) / 2], np.float32)
    return m


def rect_scene(rects) -> Scene:  # noqa: ANN001
    """The rectangles as a Scene: the ones with a hole alpha-masked and double-sided."""
    alpha = np.full((32, 32), 255, np.uint8)
    holes = [r[5] for r in rects if r[5]]  # the holed rects share one texture
    if holes:
        lo, hi = int(32 * holes[0][0]), int(32 * holes[0][1])
        alpha[lo:hi, lo:hi] = 0
    meshes = [_rect_mesh(r) for r in rects]
    mats = []
    for i, (m, r) in enumerate(zip(meshes, rects, strict=True)):
        m.material = i
        mats.append(Material(f"m{i}", alpha_mode="mask", double_sided=True,
                             base_color_texture=TextureRef(0)) if r[5] else Material(f"m{i}"))
    return Scene("shadow factor", meshes=meshes, materials=mats,
                 images=[Image("hole", pixels=np.dstack([np.full((32, 32, 3), 200, np.uint8),
                                                          alpha]))],
                 nodes=[Node(i) for i in range(len(rects))])


def hit_rects(o, d, rects):  # noqa: ANN001, ANN201
    """First hit of rays o + t d on rects: (t, id); holes let rays through."""
    n = len(d)
    best_t, best = np.full(n, np.inf), np.full(n, -1)
    for k, (y, x0, x1, z0, z1, hole) in enumerate(rects):
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (y - o[:, 1]) / d[:, 1]
        p = o + t[:, None] * d
        u, v = (p[:, 0] - x0) / (x1 - x0), (p[:, 2] - z0) / (z1 - z0)
        cheb = np.maximum(np.abs(u - 0.5), np.abs(v - 0.5))
        inside = (t > 1e-6) & (cheb <= 0.5)
        if hole:
            inside &= cheb >= (hole[1] - hole[0]) / 2
        take = inside & (t < best_t)
        best_t[take], best[take] = t[take], k
    return best_t, best


def _border_distance(p, rects):  # noqa: ANN001, ANN202
    """World distance from points on the rects' planes to the nearest rect / hole border,
    for the occluders only (not the ground), measured in each occluder's plane."""
    out = np.full(len(p), np.inf)
    for _y, x0, x1, z0, z1, hole in rects[1:]:
        u, v = (p[:, 0] - x0) / (x1 - x0), (p[:, 2] - z0) / (z1 - z0)
        cheb = np.maximum(np.abs(u - 0.5), np.abs(v - 0.5))
        size = min(x1 - x0, z1 - z0)
        out = np.minimum(out, np.abs(cheb - 0.5) * size)
        if hole:
            out = np.minimum(out, np.abs(cheb - (hole[1] - hole[0]) / 2) * size)
    return out


def through_hole(p, to_l, dist, rects):  # noqa: ANN001, ANN201
    """Per point: the segment to the light crosses a holed rect inside its hole."""
    out = np.zeros(len(p), bool)
    for y, x0, x1, z0, z1, hole in rects[1:]:
        if not hole:
            continue
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (y - p[:, 1]) / to_l[:, 1]
        q = p + np.where(np.isfinite(s), s, 0)[:, None] * to_l
        u, v = (q[:, 0] - x0) / (x1 - x0), (q[:, 2] - z0) / (z1 - z0)
        cheb = np.maximum(np.abs(u - 0.5), np.abs(v - 0.5))
        out |= (s > 0) & (s < dist) & (cheb < (hole[1] - hole[0]) / 2)
    return out


def reference(rects, light: Light, size: tuple[int, int], res: int, spot_texel: float,
              camera: Camera = CAMERA) -> dict[str, np.ndarray]:
    """Per pixel (H, W): receiver id `rid` (-1: nothing), `lit`, in the penumbra `band`,
    `facing` the light (the receivers are horizontal, seen from above: normal +Y), and lit
    `hole` (through a holed rect). `spot_texel`: a spot map's texel at unit distance."""
    w, h = size
    d = pixel_rays(camera, w, h).reshape(-1, 3)
    o = np.tile(np.asarray(camera.eye, float), (len(d), 1))
    t, rid = hit_rects(o, d, rects)
    p = o + np.where(np.isfinite(t), t, 0)[:, None] * d
    if light.kind == "directional":
        to_l = np.tile(-np.asarray(light.direction), (len(p), 1))
        dist = np.full(len(p), np.inf)
    else:
        to_l = np.asarray(light.position) - p
        dist = np.linalg.norm(to_l, axis=1)
        to_l = to_l / dist[:, None]
    st, sid = hit_rects(p + 1e-4 * to_l, to_l, rects)
    lit = ~((sid >= 0) & (st < dist))
    # The penumbra band: PCF 3x3 a texel apart with 2x2 filtering blurs 2 texels each side;
    # the normal offset and bias shift the edge up to ~1.5 more.
    band = np.zeros(len(p), bool)
    for y, *_ in rects[1:]:
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (y - p[:, 1]) / to_l[:, 1]
        q = p + s[:, None] * to_l
        crosses = (s > 0) & (s < dist)
        if light.kind == "directional":
            texel = 2.0 * 5.0 / res  # bound: the cascades here are < 5 units across
        elif light.kind == "spot":
            texel = spot_texel * np.abs(q - np.asarray(light.position)) @ np.abs(light.direction)
        else:
            texel = 2.0 * np.max(np.abs(q - np.asarray(light.position)), axis=1) / (res // 2)
        band |= crosses & (_border_distance(q, rects) < 4.0 * texel)
    hole = lit & through_hole(p, to_l, dist, rects)
    out = {"rid": rid, "lit": lit, "band": band, "facing": to_l[:, 1] > 0.05, "hole": hole}
    return {k: v.reshape(h, w) for k, v in out.items()}
