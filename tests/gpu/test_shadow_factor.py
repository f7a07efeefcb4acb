"""shaders/shadow_sampling.glsl's shadow_factor on the GPU against a NumPy ray cast: an occluder over a
plane, lit by each light type (directional cascades, spot map, point cube); each pixel's
factor (> 0.5 lit) agrees with "does the segment to the light hit the occluder" outside a
penumbra band of a few shadow-map texels (<= 0.5% of the rest wrong); a plane with nothing
over it is lit everywhere (no acne); an alpha-masked card casts a shadow with its hole.

The factor is drawn by a small test shader (pbr.vert + shadow_factor, compiled here), so this
checks the shadow code without the rest of the shading (the full renderer
binds set 3 once integrated; then its SHADOW debug view shows the same factor)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from vkpbr import Renderer
from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.pipeline import Pipeline, PipelineLayout, PipelineSpec, VertexStream
from vkpbr.gpu.target import COPY_COLOR
from vkpbr.render import layouts as L
from vkpbr.render.camera import depth_range, forward, look_at, projection_terms
from vkpbr.render.codegen import SHADER_DIR, SPV_DIR
from vkpbr.render.frames import write_frame_uniforms
from vkpbr.render.options import RenderOptions
from vkpbr.render.passes import classify
from vkpbr.render.shadows import ShadowMaps, plan_shadows
from vkpbr.scene.default import plane
from vkpbr.scene.types import Camera, Image, Light, Material, Node, Scene, TextureRef

pytestmark = pytest.mark.skipif(shutil.which("glslc") is None, reason="glslc not installed")

SIZE = (128, 96)
RES = 256
GROUND = (0.0, -4.0, 4.0, -4.0, 4.0, None)
BLOCK = (1.0, -1.0, 0.8, -1.0, 0.9, None)
CARD = (0.8, 1.2, 2.4, -0.6, 0.6, (0.3, 0.7))
CAMERA = Camera(eye=(0.0, 5.0, 6.0), target=(0.3, 0.0, 0.0), yfov_deg=55.0)

FRAG = """#version 450
#extension GL_GOOGLE_include_directive : require
#include "generated.glsl"
layout(set = 2, binding = 7, std140) uniform TestLight { LightRecord test_light; vec4 eye; };
#include "shadow_sampling.glsl"
layout(location = 0) in vec3 v_world_pos;
layout(location = 2) in vec3 v_normal;
layout(location = 0) out vec4 out_color;
void main() {
    vec3 ng = normalize(v_normal);
    if (!gl_FrontFacing) ng = -ng;
    int kind = int(test_light.direction_kind.w + 0.5);
    vec3 l = kind == 2 ? -test_light.direction_kind.xyz
                       : normalize(test_light.position_range.xyz - v_world_pos);
    float view_depth = dot(v_world_pos - eye.xyz, settings.camera_forward.xyz);
    out_color = vec4(shadow_factor(test_light, v_world_pos, ng, l, view_depth), dot(ng, l), 0, 1);
}
"""


_Light = Light


def _d(*v):
    v = np.asarray(v, float)
    return tuple(v / np.linalg.norm(v))


LIGHTS = {
    "directional": _Light(kind="directional", direction=_d(0.35, -1.0, 0.25)),
    "spot": _Light(kind="spot", position=(0.3, 3.5, 0.2), direction=_d(0.05, -1.0, 0.0),
                   outer_cone=0.8),
    "point": _Light(kind="point", position=(0.2, 2.6, 0.1)),
}


def _rect_mesh(r):
    y, x0, x1, z0, z1, _ = r
    m = plane(x1 - x0, z1 - z0, y=y)
    m.positions = m.positions + np.array([(x0 + x1) / 2, 0, (z0 + z1) / 2], np.float32)
    return m


def _scene(rects) -> Scene:
    alpha = np.full((32, 32), 255, np.uint8)
    lo, hi = int(32 * CARD[5][0]), int(32 * CARD[5][1])
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


def _compile(tmp: Path) -> Path:
    src = tmp / "shadow_factor_test.frag"
    src.write_text(FRAG)
    out = tmp / "shadow_factor_test.frag.spv"
    subprocess.run(["glslc", "--target-env=vulkan1.3", "-I", str(SHADER_DIR), str(src), "-o",
                    str(out)], check=True, capture_output=True)
    shutil.copy(SPV_DIR / "pbr_vectors.vert.spv", tmp)
    return tmp


def _render(rects, light: _Light, tmp: Path) -> tuple[np.ndarray, ShadowMaps]:
    scene = _scene(rects)
    with Renderer(scene, validation=True) as r:
        dev = r.device
        sm = ShadowMaps(dev, r.set_layouts[1], r.ring.count, resolution=RES)
        plan = plan_shadows([light])
        sm.ensure(plan)
        test_layout = DescriptorSetLayout(dev, [BindingSpec(7, "uniform", ("fragment",))])
        layout = PipelineLayout(dev, [r.set_layouts[0], r.set_layouts[1], test_layout,
                                      sm.set_layout], L.PUSH.size)
        target = r.offscreen_target(SIZE, linear=True)
        gs = r.gpu_scene
        names = ("positions", "texcoords", "texcoords1", "colors", "normals", "tangents")
        fmts = ("vec3", "vec2", "vec2", "unorm16x4", "vec3", "vec4")
        streams = tuple(VertexStream(i, i, f, 0 if n == "colors" and not gs.has_colors else None)
                        for i, (n, f) in enumerate(zip(names, fmts, strict=True)))
        pipe = Pipeline(dev, PipelineSpec("pbr_vectors.vert.spv", "shadow_factor_test.frag.spv",
                                          streams, target.color_format, target.depth_format,
                                          cull="none"), layout, tmp)
        frame = r.ring.begin()
        slot = r.slots[frame.index]
        write_frame_uniforms(slot, CAMERA, (light,), SIZE, RenderOptions(), True, r.bounds)
        f = forward(CAMERA)
        znear, zfar = depth_range(CAMERA, r.bounds.corners, r.bounds.radius, f)
        lo, hi = scene.bounds()
        rec = sm.write(frame.index, plan, [light], CAMERA, SIZE, znear, zfar, lo, hi)
        kind = {"point": 0, "spot": 1, "directional": 2}[light.kind]
        ubo = Buffer(dev, 96, "uniform", host_visible=True)
        ubo.array(np.float32, 24)[:] = np.r_[light.position, 0, light.direction, kind,
                                             1, 1, 1, 0, 0, 0, 0, 0, rec[0], CAMERA.eye, 1]
        pool = DescriptorPool(dev, [(test_layout, 1)])
        s2 = pool.allocate(test_layout)
        w = DescriptorWriter(dev)
        w.uniform(s2, 7, ubo, 96)
        w.update()
        classes = [classify(d.alpha_mode, d.double_sided, True) for d in gs.draws]
        cmd = Commands(dev).begin()
        sm.record(cmd, frame.index, plan, gs.draws, classes, gs.material_sets, gs.streams,
                  gs.index_buffer, gs.has_colors)
        target.record_begin(cmd, 0)
        cmd.bind_pipeline(pipe)
        cmd.bind_set(0, slot.set0)
        cmd.bind_set(2, s2)
        cmd.bind_set(3, sm.sets[frame.index])
        cmd.bind_vertex_buffers([gs.streams[n] for n in names])
        cmd.bind_index_buffer(gs.index_buffer)
        for d in gs.draws:
            cmd.push(d.push)
            cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset)
        target.record_end(cmd, 0, frame, (COPY_COLOR,))
        cmd.end()
        frame.submit(cmd)
        frame.wait()
        cmd.free()
        image = target.read_color(frame.index)
        r.check_validation()
        sm.destroy()
        return image, rec[0]


def _hit_rects(o, d, rects):
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


def _border_distance(p, rects):
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


def _reference(rects, light: _Light, record: np.ndarray):
    """Per pixel: receiver id, lit (bool) and in-band (bool) by a NumPy ray cast."""
    w, h = SIZE
    sx, sy, ox, oy = projection_terms(CAMERA, SIZE)
    xs = ((np.arange(w) + 0.5) / w) * 2 - 1
    ys = ((np.arange(h) + 0.5) / h) * 2 - 1
    xn, yn = np.meshgrid(xs, ys)
    dv = np.stack([(xn - ox) / sx, (oy - yn) / sy, -np.ones_like(xn)], -1).reshape(-1, 3)
    inv = np.linalg.inv(look_at(CAMERA.eye, CAMERA.target, CAMERA.up))
    d = dv @ inv[:3, :3].T
    o = np.tile(np.asarray(CAMERA.eye, float), (len(d), 1))
    t, rid = _hit_rects(o, d, rects)
    p = o + np.where(np.isfinite(t), t, 0)[:, None] * d
    if light.kind == "directional":
        to_l = np.tile(-np.asarray(light.direction), (len(p), 1))
        dist = np.full(len(p), np.inf)
    else:
        to_l = np.asarray(light.position) - p
        dist = np.linalg.norm(to_l, axis=1)
        to_l = to_l / dist[:, None]
    st, sid = _hit_rects(p + 1e-4 * to_l, to_l, rects)
    lit = ~((sid >= 0) & (st < dist))
    # The penumbra band: where the segment to the light passes within a few shadow-map
    # texels of an occluder's border (PCF 3x3 a texel apart with 2x2 filtering: 2 texels
    # of blur each side; the normal offset and bias shift up to ~1.5 more).
    band = np.zeros(len(p), bool)
    for y, *_ in rects[1:]:
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (y - p[:, 1]) / to_l[:, 1]
        q = p + s[:, None] * to_l
        crosses = (s > 0) & (s < dist)
        if light.kind == "directional":
            texel = 2.0 * 5.0 / RES  # bound: the cascades here are < 5 units across
        elif light.kind == "spot":
            texel = record[3] * np.abs(q - np.asarray(light.position)) @ np.abs(light.direction)
        else:
            texel = 2.0 * np.max(np.abs(q - np.asarray(light.position)), axis=1) / (RES // 2)
        band |= crosses & (_border_distance(q, rects) < 4.0 * texel)
    return rid.reshape(h, w), lit.reshape(h, w), band.reshape(h, w)


@pytest.fixture(scope="module")
def shaders(tmp_path_factory):
    return _compile(tmp_path_factory.mktemp("shadow_factor"))


@pytest.mark.parametrize("kind", ["directional", "spot", "point"])
def test_shadow_factor_matches_a_ray_cast(kind, shaders) -> None:
    rects = (GROUND, BLOCK, CARD)
    light = LIGHTS[kind]
    image, record = _render(rects, light, shaders)
    rid, lit, band = _reference(rects, light, record)
    factor = image[..., 0]
    facing = image[..., 1] > 0.05  # receivers facing the light (others are unlit anyway)
    judged = (rid >= 0) & ~band & facing
    assert judged.mean() > 0.5
    wrong = (factor > 0.5) != lit
    assert wrong[judged].mean() <= 0.005, (kind, wrong[judged].mean())
    # The scene has both: shadow from the block, and light through the card's hole.
    assert (~lit & judged).sum() > 100 and (lit & judged).sum() > 200
    hole_light = lit & judged & (rid == 0)
    assert hole_light.any()


@pytest.mark.parametrize("kind", ["directional", "spot", "point"])
def test_a_lone_plane_has_no_acne(kind, shaders) -> None:
    """Nothing over the ground: every pixel of it facing the light is fully lit."""
    light = LIGHTS[kind]
    image, _ = _render((GROUND,), light, shaders)
    rid, _, _ = _reference((GROUND,), light, np.zeros(4))
    ground = (rid == 0) & (image[..., 1] > 0.05)
    assert ground.mean() > 0.4
    assert np.all(image[..., 0][ground] > 0.999), (kind, np.min(image[..., 0][ground]))
