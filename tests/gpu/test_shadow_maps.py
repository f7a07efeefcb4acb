"""The shadow-map passes (render/shadows.py) against a NumPy ray cast: for every texel of every
layer (a directional light's cascades, a spot map, a point light's six cube faces drawn in one
multiview pass), the depth the GPU stored is the reversed depth of the first surface the
texel's ray hits; an alpha-masked card's hole lets the ray through to the ground."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from vkpbr import Renderer
from vkpbr.gpu.commands import Commands
from vkpbr.render import shadow_math as SM
from vkpbr.render import shadows as SH
from vkpbr.render.passes import classify
from vkpbr.render.shadows import ShadowMaps, plan_shadows
from vkpbr.scene.default import plane
from vkpbr.scene.types import Camera, Image, Material, Node, Scene, TextureRef

RES = 128
# Horizontal rectangles: (y, x0, x1, z0, z1, hole) with hole = the card's cut-out in uv.
GROUND = (0.0, -3.0, 3.0, -3.0, 3.0, None)
BLOCK = (1.0, -0.5, 0.5, -0.5, 0.5, None)
CARD = (0.6, 0.8, 2.0, -1.6, -0.4, (0.3, 0.7))
RECTS = (GROUND, BLOCK, CARD)


@dataclass
class _Light:  # the fields of scene.types.Light that shadows read
    kind: str
    position: tuple = (0.0, 0.0, 0.0)
    direction: tuple = (0.0, -1.0, 0.0)
    outer_cone: float = 0.785
    range: float = 0.0
    shadows: bool = True


LIGHTS = [
    _Light("directional", direction=tuple(np.array([0.3, -1.0, 0.2]) / np.linalg.norm([0.3, -1.0, 0.2]))),
    _Light("spot", position=(0.4, 3.0, -0.3), direction=(0.0, -1.0, 0.0), outer_cone=0.9),
    _Light("point", position=(0.3, 2.2, -0.2)),
]


def _rect_mesh(r):
    y, x0, x1, z0, z1, _ = r
    m = plane(x1 - x0, z1 - z0, y=y)
    m.positions = m.positions + np.array([(x0 + x1) / 2, 0, (z0 + z1) / 2], np.float32)
    return m


def _scene() -> Scene:
    alpha = np.full((32, 32), 255, np.uint8)
    lo, hi = int(32 * CARD[5][0]), int(32 * CARD[5][1])
    alpha[lo:hi, lo:hi] = 0
    pixels = np.dstack([np.full((32, 32, 3), 200, np.uint8), alpha])
    meshes = [_rect_mesh(r) for r in RECTS]
    for i, m in enumerate(meshes):
        m.material = i
    mats = [Material("ground"), Material("block"),
            Material("card", alpha_mode="mask", double_sided=True,
                     base_color_texture=TextureRef(0))]
    return Scene("shadow test", meshes=meshes, materials=mats,
                 images=[Image("hole", pixels=pixels)], nodes=[Node(i) for i in range(3)])


def _cast(origin: np.ndarray, d: np.ndarray, rects=RECTS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """First hits of rays o + t d (t > 0) on RECTS: (t, id (-1 none), edge), edge the world
    distance from the hit (or a crossing in front of it) to the nearest rect or hole border:
    texels near a border may go either way (rasterisation rules, bilinear alpha)."""
    n = len(d)
    best_t, best_id = np.full(n, np.inf), np.full(n, -1)
    crossings = []
    for k, (y, x0, x1, z0, z1, hole) in enumerate(rects):
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (y - origin[:, 1]) / d[:, 1]
        p = origin + t[:, None] * d
        u, v = (p[:, 0] - x0) / (x1 - x0), (p[:, 2] - z0) / (z1 - z0)
        cheb = np.maximum(np.abs(u - 0.5), np.abs(v - 0.5))  # 0.5 on the border
        size = min(x1 - x0, z1 - z0)
        border = np.abs(cheb - 0.5) * size
        inside = (t > 0) & (cheb <= 0.5)
        if hole is not None:
            half = (hole[1] - hole[0]) / 2
            border = np.minimum(border, np.abs(cheb - half) * size)
            inside &= cheb >= half
        take = inside & (t < best_t)
        best_t[take], best_id[take] = t[take], k
        crossings.append((t, border))
    edge = np.full(n, np.inf)
    for t, border in crossings:
        front = (t > 0) & (t <= best_t * (1 + 1e-9))
        edge[front] = np.minimum(edge[front], border[front])
    return best_t, best_id, edge


def _expected(m: np.ndarray, res: int, rects=RECTS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Expected stored depth (res, res), hit ids and a world-space edge distance per texel."""
    c = (np.arange(res) + 0.5) / res * 2 - 1
    x, y = np.meshgrid(c, c)  # row = y (down), column = x
    inv = np.linalg.inv(m)
    a = np.stack([x.ravel(), y.ravel(), np.ones(res * res), np.ones(res * res)], 1) @ inv.T
    b = np.stack([x.ravel(), y.ravel(), np.full(res * res, 0.5), np.ones(res * res)], 1) @ inv.T
    a, b = a[:, :3] / a[:, 3:], b[:, :3] / b[:, 3:]
    t, ids, edge = _cast(a, b - a, rects)
    hit = a + np.where(np.isfinite(t), t, 0)[:, None] * (b - a)
    clip = SM.project(m, hit)
    depth = np.where(ids >= 0, clip[:, 2] / clip[:, 3], 0.0)
    # Beyond the far side of a cascade's box nothing is drawn (the map keeps its clear value).
    ids = np.where(depth < 0, -1, ids)
    depth = np.maximum(depth, 0.0)
    return depth.reshape(res, res), ids.reshape(res, res), edge.reshape(res, res)


@pytest.fixture(scope="module")
def maps():
    scene = _scene()
    with Renderer(scene, validation=True) as r:
        sm = ShadowMaps(r.device, r.set_layouts[1], r.ring.count, resolution=RES, readable=True,
                        frame_layout=r.set_layouts[0])
        plan = plan_shadows(LIGHTS)
        sm.ensure(plan)
        camera = Camera(eye=(0.0, 1.5, 2.5), target=(0.0, 0.0, 0.0))
        lo, hi = scene.bounds()
        frame = r.ring.begin()
        rec = sm.write(frame.index, plan, LIGHTS, camera, (160, 120), 1.0, 8.0, lo, hi)
        gs = r.gpu_scene
        cmd = Commands(r.device).begin()
        sm.record(cmd, frame.index, plan, gs.draws,
                  [classify(d.alpha_mode, d.double_sided, True) for d in gs.draws],
                  gs.material_sets, gs.streams, gs.index_buffer, gs.has_colors,
                  set0=r.slots[frame.index].set0)  # its Instances: the draws' matrices
        cmd.end()
        frame.submit(cmd)
        frame.wait()
        cmd.free()
        layers, cubes = sm.read_maps()
        mats = sm._views[frame.index][SH.HEADER_BYTES // 4:].reshape(-1, 4, 4)
        mats = mats.transpose(0, 2, 1).astype(np.float64)
        r.check_validation()
        sm.destroy()
        yield plan, rec, layers, cubes, mats


def _check(stored: np.ndarray, m: np.ndarray, res: int, label: str, kind: str):
    want, ids, edge = _expected(m, res)
    # The world size of a texel at the hit, to exclude a band of 1.5 texels around every edge
    # (rasterisation rules and bilinear alpha put those either way).
    texel = np.full((res, res), np.inf)
    inv = np.linalg.inv(m)
    p0 = SM.project(inv, np.array([[0.0, 0.0, 0.5]]))
    p1 = SM.project(inv, np.array([[2.0 / res, 0.0, 0.5]]))
    w0 = p0[0, :3] / p0[0, 3] - p1[0, :3] / p1[0, 3]
    texel[:] = np.linalg.norm(w0)
    if abs(m[3, 3] - 1.0) > 1e-9 or np.any(m[3, :3]):  # perspective: scale with distance
        axial = 1.0 / np.where(want > 0, want, np.inf) * (m[2, 3])
        texel = texel * axial / (m[2, 3] * 2.0)
    keep = edge > 2.5 * texel
    assert keep.mean() > 0.6, f"{label}: the band excludes too much ({keep.mean():.2f})"
    # Stored depth = the surface's, pushed away from the light by the passes' slope-scaled
    # bias: |slope factor| x the depth slope per texel (Vulkan's m), plus float rounding.
    gy, gx = np.gradient(want)
    slope = np.maximum(np.abs(gx), np.abs(gy))
    bias = abs(SH.DEPTH_BIAS[kind][1]) * slope + 1e-6 * np.maximum(want, 1e-3)
    err = (want - stored)[keep]
    wrong = (err < -1e-6) | (err > 1.5 * bias[keep] + 1e-7)
    assert wrong.mean() <= 0.002, (label, wrong.mean(), np.max(np.abs(err)))
    return ids, keep


def test_cascades_match_a_ray_cast(maps) -> None:
    plan, rec, layers, _, mats = maps
    e = plan.entries[0]
    assert e.kind == "directional" and rec[0][0] == e.first and rec[0][1] == SM.CASCADES
    for c in range(SM.CASCADES):
        _check(layers[e.first + c], mats[e.matrix_base + c], RES, f"cascade {c}", e.kind)


def test_spot_map_matches_a_ray_cast(maps) -> None:
    plan, rec, layers, _, mats = maps
    e = plan.entries[1]
    ids, keep = _check(layers[e.first], mats[e.matrix_base], RES, "spot", e.kind)
    assert (ids == 1).sum() > 100 and (ids == 2).sum() > 100  # block and card both in view


def test_point_light_faces_match_a_ray_cast_and_the_hole_shows_the_ground(maps) -> None:
    plan, rec, _, cubes, mats = maps
    e = plan.entries[2]
    res = RES // 2
    assert cubes.shape[1] == res
    for f in range(6):
        _check(cubes[6 * e.first + f], mats[e.matrix_base + f], res, f"cube face {f}", e.kind)
    # The -Y face looks down through the card's hole: there the map holds the ground, where
    # a card without the hole would have been.
    m = mats[e.matrix_base + 3]
    want, ids, edge = _expected(m, res)
    solid, solid_ids, _ = _expected(m, res, (GROUND, BLOCK, CARD[:5] + (None,)))
    hole = (ids == 0) & (solid_ids == 2) & (edge > 0.1)
    assert hole.sum() >= 9
    stored = cubes[6 * e.first + 3][hole]
    assert np.all(np.abs(stored - want[hole]) < 0.25 * np.abs(solid[hole] - want[hole]))


def test_resolution_change_and_growth_remake_the_images() -> None:
    with Renderer(_scene(), validation=True) as r:
        sm = ShadowMaps(r.device, r.set_layouts[1], r.ring.count, resolution=64)
        assert sm.maps.size == 1 and sm.cubes.size == 1  # nothing shadowed yet: 1x1 stand-ins
        plan = plan_shadows(LIGHTS)
        assert sm.ensure(plan) and (sm.maps.size, sm.cubes.size) == (64, 32)
        assert not sm.ensure(plan)  # same plan: nothing to do
        assert not sm.ensure(plan_shadows(LIGHTS[:1]))  # fewer layers fit
        sm.set_resolution(128)
        assert sm.ensure(plan) and (sm.maps.size, sm.cubes.size) == (128, 64)
        assert plan_shadows(LIGHTS, enabled=False).entries == ()
        many = plan_shadows([_Light("directional")] * 5 + [_Light("point")] * 5)
        assert many.layers == 16 and many.cubes == 4 and many.dropped == 2
        with pytest.warns(UserWarning, match="without shadows"):
            sm.ensure(many)
        r.check_validation()
        sm.destroy()
