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
from shadow_scenes import BLOCK, CAMERA, CARD, GROUND, LIGHTS, rect_scene, reference

from vkpbr import Renderer
from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.graph import Rendering, Step, record_steps
from vkpbr.gpu.pipeline import Pipeline, PipelineLayout, PipelineSpec, VertexStream
from vkpbr.gpu.target import COPY_COLOR
from vkpbr.render import layouts as L
from vkpbr.render.codegen import SHADER_DIR, SPV_DIR
from vkpbr.render.frames import write_frame_uniforms
from vkpbr.render.options import RenderOptions
from vkpbr.render.passes import classify
from vkpbr.render.shadows import ShadowMaps, plan_shadows
from vkpbr.scene.types import Light

pytestmark = pytest.mark.skipif(shutil.which("glslc") is None, reason="glslc not installed")

SIZE = (128, 96)
RES = 256

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
    float view_depth = dot(v_world_pos - eye.xyz, views[0].forward_far.xyz);
    out_color = vec4(shadow_factor(test_light, v_world_pos, ng, l, view_depth), dot(ng, l), 0, 1);
}
"""


def _compile(tmp: Path) -> Path:
    src = tmp / "shadow_factor_test.frag"
    src.write_text(FRAG)
    out = tmp / "shadow_factor_test.frag.spv"
    subprocess.run(["glslc", "--target-env=vulkan1.3", "-I", str(SHADER_DIR), str(src), "-o",
                    str(out)], check=True, capture_output=True)
    shutil.copy(SPV_DIR / "pbr_vectors.vert.spv", tmp)
    return tmp


def _render(rects, light: Light, tmp: Path) -> tuple[np.ndarray, ShadowMaps]:
    scene = rect_scene(rects)
    with Renderer(scene, validation=True) as r:
        dev = r.device
        sm = ShadowMaps(dev, r.set_layouts[1], r.ring.count, resolution=RES,
                        frame_layout=r.set_layouts[0])
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
        lo, hi = scene.bounds()
        rec = sm.write(frame.index, plan, [light], CAMERA, SIZE, slot.znear, slot.zfar, lo, hi)
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
                  gs.index_buffer, gs.has_colors, set0=r.slots[frame.index].set0)

        def draw(cmd: Commands) -> None:
            record_draws(cmd, pipe, slot, s2, sm.sets[frame.index], gs, names)

        steps = [Step("draw", draw, rendering=Rendering("color", "depth", target.clear_color, 0.0)),
                 *target.finish_steps(0, frame.index, (COPY_COLOR,))]
        record_steps(cmd, steps, target.resources(0, frame.index), target.extent)
        cmd.end()
        frame.submit(cmd)
        frame.wait()
        cmd.free()
        image = target.read_color(frame.index)
        r.check_validation()
        sm.destroy()
        return image, rec[0]


@pytest.fixture(scope="module")
def shaders(tmp_path_factory):
    return _compile(tmp_path_factory.mktemp("shadow_factor"))


@pytest.mark.parametrize("kind", ["directional", "spot", "point"])
def test_shadow_factor_matches_a_ray_cast(kind, shaders) -> None:
    rects = (GROUND, BLOCK, CARD)
    light = LIGHTS[kind]
    image, record = _render(rects, light, shaders)
    ref = reference(rects, light, SIZE, RES, float(record[3]))
    rid, lit, band = ref["rid"], ref["lit"], ref["band"]
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
    rid = reference((GROUND,), light, SIZE, RES, 0.0)["rid"]
    ground = (rid == 0) & (image[..., 1] > 0.05)
    assert ground.mean() > 0.4
    assert np.all(image[..., 0][ground] > 0.999), (kind, np.min(image[..., 0][ground]))


def record_draws(cmd, pipe, slot, set2, set3, gs, names) -> None:  # noqa: ANN001
    """The test pipeline's draws of every draw of `gs` with the frame's sets bound."""
    cmd.bind_pipeline(pipe)
    cmd.bind_set(0, slot.set0)
    cmd.bind_set(2, set2)
    cmd.bind_set(3, set3)
    cmd.bind_vertex_buffers([gs.streams[n] for n in names])
    cmd.bind_index_buffer(gs.index_buffer)
    for i, d in enumerate(gs.draws):  # pbr.vert reads record i's matrices (gl_InstanceIndex)
        cmd.push(L.draw_push(i))
        cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset, first_instance=i)
