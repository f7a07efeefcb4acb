"""Sponza with pyrender (OpenGL through EGL, headless), as a user would: trimesh loads the glTF,
pyrender.Scene.from_trimesh_scene, an OffscreenRenderer with its defaults (4x MSAA).

    PYOPENGL_PLATFORM=egl python benchmarks/peers/pyrender_bench.py --size 1920x1080 --frames 200 --json out.json
    python benchmarks/peers/pyrender_bench.py --batch --scene helmet --size 128x128 --poses p.npy

--batch: the batch scenario of common.py (B poses, a per-view loop: pyrender has no batch
API): scene.set_pose(camera) then render() per view, into NumPy and render only as below.

Render + readback: OffscreenRenderer.render(), which always returns colour (H, W, 3) uint8 and a
float32 depth image. Render only: the same call with the framebuffer read replaced by glFinish().
Needs pyrender (installed --no-deps), PyOpenGL 3.1.10, trimesh, pyglet 1.5.x, freetype-py, and
libGLU (importing pyrender imports its pyglet viewer).
"""

from __future__ import annotations

import math
import os
import sys
import time

import common as c

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")


def batch_main() -> None:
    args = c.parse_batch_args("pyrender")
    t0 = time.perf_counter()
    import pyrender
    import trimesh
    from OpenGL.GL import GL_RENDERER, glFinish, glGetString

    tm = trimesh.load(args.scene_path, force="scene")
    scene = pyrender.Scene.from_trimesh_scene(tm, bg_color=(0, 0, 0, 1), ambient_light=(0.3, 0.3, 0.3))
    camera = pyrender.PerspectiveCamera(yfov=math.radians(c.YFOV_DEG), znear=c.ZNEAR, zfar=c.ZFAR,
                                        aspectRatio=args.width / args.height)
    poses = args.pose_array
    cam_node = scene.add(camera, pose=poses[0])
    light_pose = c.np.eye(4)
    light_pose[:3, 3] = c.LIGHT_POS
    scene.add(pyrender.PointLight(color=c.LIGHT_COLOR, intensity=c.LIGHT_CANDELA), pose=light_pose)
    r = pyrender.OffscreenRenderer(args.width, args.height)
    color, _depth = r.render(scene)
    load_s = time.perf_counter() - t0
    assert color.shape == (args.height, args.width, 3), color.shape
    r._platform.make_current()
    gpu = glGetString(GL_RENDERER).decode()
    r._platform.make_uncurrent()

    def one_pass() -> None:
        for pose in poses:
            scene.set_pose(cam_node, pose)
            r.render(scene)

    vps_readback = c.views_per_s(one_pass, len(poses), args.reps)
    scene.set_pose(cam_node, poses[0])
    image = r.render(scene)[0]
    r._renderer._read_main_framebuffer = lambda scene, flags: glFinish()
    vps_render_only = c.views_per_s(one_pass, len(poses), args.reps)
    r.delete()
    c.report_batch(args, "pyrender", pyrender.__version__, vps_readback, vps_render_only, load_s,
                   gpu, "OffscreenRenderer defaults: 4x MSAA, colour + depth read back",
                   "per-view loop", 1.0, image)


def main() -> None:
    if "--batch" in sys.argv:
        return batch_main()
    args = c.parse_args("pyrender")
    t0 = time.perf_counter()
    import pyrender
    import trimesh
    from OpenGL.GL import GL_RENDERER, glFinish, glGetString

    tm = trimesh.load(args.scene, force="scene")
    scene = pyrender.Scene.from_trimesh_scene(tm, bg_color=(0, 0, 0, 1), ambient_light=(0, 0, 0))
    camera = pyrender.PerspectiveCamera(yfov=math.radians(c.YFOV_DEG), znear=c.ZNEAR, zfar=c.ZFAR,
                                        aspectRatio=args.width / args.height)
    scene.add(camera, pose=c.look_at())
    # pyrender's point light falls off with the inverse square (intensity in candela); the
    # value only sets the brightness, not the cost.
    light = pyrender.PointLight(color=c.LIGHT_COLOR, intensity=c.LIGHT_CANDELA)
    light_pose = c.np.eye(4)
    light_pose[:3, 3] = c.LIGHT_POS
    scene.add(light, pose=light_pose)
    r = pyrender.OffscreenRenderer(args.width, args.height)
    color, _depth = r.render(scene)
    load_s = time.perf_counter() - t0
    assert color.shape == (args.height, args.width, 3), color.shape

    r._platform.make_current()
    gpu = glGetString(GL_RENDERER).decode()
    r._platform.make_uncurrent()

    ms_readback = c.median_ms(lambda: r.render(scene), args.frames, args.warmup)
    image = r.render(scene)[0]
    # Render only: pyrender has no public call that skips the readback; drop its framebuffer
    # read (MSAA resolve blits + glReadPixels of colour and depth) and wait for the GPU instead.
    r._renderer._read_main_framebuffer = lambda scene, flags: glFinish()
    ms_render_only = c.median_ms(lambda: r.render(scene), args.frames, args.warmup)
    r.delete()
    c.report(args, "pyrender", pyrender.__version__, ms_readback, ms_render_only, load_s, gpu,
             "OffscreenRenderer defaults: 4x MSAA, colour + depth read back", image)


if __name__ == "__main__":
    main()
