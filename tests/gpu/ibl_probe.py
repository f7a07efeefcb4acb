"""Run shaders/ibl.glsl's ibl_evaluate on the GPU at given points (tests/gpu/test_ibl.py).

The probe shader is compiled at test time (glslc, as scripts/setup.sh installs it) into a
temporary folder: it is a test harness, not a shipped shader.
"""

from __future__ import annotations

import math
import subprocess
from pathlib import Path

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.compute import ComputePipeline, groups
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.render.codegen import SHADER_DIR, glslc

PROBE = Path(__file__).parent / "shaders" / "ibl_probe.comp"


def compile_probe(out_dir: Path) -> Path:
    dst = out_dir / "ibl_probe.comp.spv"
    subprocess.run([glslc(), "--target-env=vulkan1.3", "-I", str(SHADER_DIR), str(PROBE),
                    "-o", str(dst)], check=True, capture_output=True, text=True)
    return dst


def ibl_probe(device, env, spirv: Path, n, v, c, metallic, roughness,  # noqa: ANN001
              intensity: float = 1.0, rotation_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(diffuse, specular), each (N, 3) float32, of ibl_evaluate at N points."""
    n, v, c = (np.atleast_2d(np.asarray(x, np.float32)) for x in (n, v, c))
    count = len(n)
    pts = np.zeros((count, 3, 4), np.float32)
    pts[:, 0, :3], pts[:, 0, 3] = n, metallic
    pts[:, 1, :3], pts[:, 1, 3] = v, roughness
    pts[:, 2, :3] = c
    st = ("compute",)
    layout = DescriptorSetLayout(device, [BindingSpec(0, "uniform", st), BindingSpec(2, "samplerCube", st),
                                          BindingSpec(3, "samplerCube", st), BindingSpec(4, "sampler2D", st),
                                          BindingSpec(5, "storage", st), BindingSpec(6, "storage", st)])
    pipe = ComputePipeline(device, spirv, [layout], 16)
    pool = DescriptorPool(device, [(layout, 1)])
    ubo = Buffer(device, 32, "uniform", host_visible=True)
    inp = Buffer(device, pts.nbytes, "storage", host_visible=True)
    out = Buffer(device, count * 32, "storage", host_visible=True)
    try:
        t = math.radians(rotation_deg)
        ubo.write(np.array([intensity, 0, 0, 0, math.cos(t), math.sin(t), env.max_lod, 0], np.float32))
        inp.write(pts)
        ds = pool.allocate(layout)
        wr = DescriptorWriter(device)
        wr.uniform(ds, 0, ubo, 32)
        wr.sampler(ds, 2, env.specular.view, env.specular.sampler)
        wr.sampler(ds, 3, env.irradiance.view, env.irradiance.sampler)
        wr.sampler(ds, 4, env.brdf_lut.view, env.brdf_lut.sampler)
        wr.storage(ds, 5, inp)
        wr.storage(ds, 6, out)
        wr.update()
        with device.one_time_commands() as raw:
            cmd = Commands(device, raw)
            cmd.bind_pipeline(pipe)
            cmd.bind_set(0, ds)
            cmd.push(np.array([count, 0, 0, 0], np.uint32))
            cmd.dispatch(*groups((count, 1, 1), (64, 1, 1)))
        res = out.array(np.float32, count * 8).reshape(count, 2, 4).copy()
    finally:
        for obj in (out, inp, ubo, pool, pipe, layout):
            obj.destroy()
    return res[:, 0, :3], res[:, 1, :3]
