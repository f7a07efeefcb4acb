"""Sponza with pygfx (wgpu-py, Vulkan), as a user would: gfx.load_gltf, a PointLight, a
PerspectiveCamera placed at the pose, and a rendercanvas offscreen canvas whose draw() returns
the frame as an (H, W, 4) uint8 array. Renderer defaults kept (2x2 supersampling, then its
Mitchell filter down to the canvas size) unless --pixel-scale is given (1: equal pixels).

    python benchmarks/peers/pygfx_bench.py --size 1920x1080 --frames 200 --json out.json
    python benchmarks/peers/pygfx_bench.py --batch --scene sponza --size 128x128 --poses p.npy --pixel-scale 1

--batch: the batch scenario of common.py (B poses, a per-view loop: pygfx has no batch API):
into NumPy, canvas.draw() per view; render only, renderer.render() per view and one device
poll at the end of the pass.

Render + readback: canvas.draw(). Render only: renderer.render() into the canvas texture without
presenting it (no copy to a buffer, no map), then wait for the GPU by a device poll (wgpu-py
0.32's queue.on_submitted_work_done_sync() raises a TypeError). Needs pygfx, wgpu, rendercanvas,
pylinalg, uharfbuzz, hsluv, freetype-py, jinja2 and gltflib (+ dataclasses-json, marshmallow<4).
"""

from __future__ import annotations

import sys
import time

import common as c


def wait_gpu(device) -> None:
    try:
        device.queue.on_submitted_work_done_sync()
    except TypeError:
        device._poll_wait()  # wgpuDevicePoll(wait=True): every submitted command done


def pixel_scale_option(ap) -> None:  # noqa: ANN001
    ap.add_argument("--pixel-scale", type=float, default=None,
                    help="WgpuRenderer pixel_scale (default: pygfx's, 2 = 2x2 supersampling; "
                         "1 = as many pixels as the others)")


def batch_main() -> None:
    args = c.parse_batch_args("pygfx", pixel_scale_option)
    t0 = time.perf_counter()
    import numpy as np
    import pygfx as gfx
    import wgpu
    from rendercanvas.offscreen import RenderCanvas

    gltf = gfx.load_gltf(args.scene_path, quiet=True)
    scene = gfx.Scene()
    scene.add(gltf.scene)
    light = gfx.PointLight(color=c.LIGHT_COLOR, intensity=3, decay=0)
    light.local.position = c.LIGHT_POS
    scene.add(light)
    scene.add(gfx.AmbientLight(intensity=0.3))
    aspect = args.width / args.height
    camera = gfx.PerspectiveCamera(fov=c.vfov_to_mean_fov(c.YFOV_DEG, aspect), aspect=aspect,
                                   depth_range=(c.ZNEAR, c.ZFAR))
    canvas = RenderCanvas(size=(args.width, args.height), pixel_ratio=1)
    renderer = gfx.WgpuRenderer(canvas, pixel_scale=args.pixel_scale)
    canvas.request_draw(lambda: renderer.render(scene, camera))
    poses = args.pose_array
    camera.local.matrix = poses[0]  # OpenGL world-from-camera, pygfx's camera axes too
    image = np.asarray(canvas.draw())
    load_s = time.perf_counter() - t0
    assert image.shape == (args.height, args.width, 4), image.shape
    device = renderer.device

    def readback() -> None:
        for pose in poses:
            camera.local.matrix = pose
            np.asarray(canvas.draw())

    def render_only() -> None:
        for pose in poses:
            camera.local.matrix = pose
            renderer.render(scene, camera)
        wait_gpu(device)

    vps_readback = c.views_per_s(readback, len(poses), args.reps)
    vps_render_only = c.views_per_s(render_only, len(poses), args.reps)
    camera.local.matrix = poses[0]
    image = np.asarray(canvas.draw())
    settings = (f"WgpuRenderer: pixel_scale {renderer.pixel_scale}, pixel_filter "
                f"{renderer.pixel_filter}; wgpu {wgpu.__version__}, {device.adapter.info.get('backend_type')}")
    c.report_batch(args, "pygfx", gfx.__version__, vps_readback, vps_render_only, load_s,
                   device.adapter.info.get("device") or None, settings, "per-view loop",
                   float(renderer.pixel_scale), image)


def main() -> None:
    if "--batch" in sys.argv:
        return batch_main()
    args = c.parse_args("pygfx", pixel_scale_option)
    t0 = time.perf_counter()
    import numpy as np
    import pygfx as gfx
    import wgpu
    from rendercanvas.offscreen import RenderCanvas

    gltf = gfx.load_gltf(args.scene, quiet=True)
    scene = gfx.Scene()
    scene.add(gltf.scene)
    # decay=0: no falloff with distance (pygfx's default for a point light).
    light = gfx.PointLight(color=c.LIGHT_COLOR, intensity=3, decay=0)
    light.local.position = c.LIGHT_POS
    scene.add(light)
    aspect = args.width / args.height
    camera = gfx.PerspectiveCamera(fov=c.vfov_to_mean_fov(c.YFOV_DEG, aspect), aspect=aspect,
                                   depth_range=(c.ZNEAR, c.ZFAR))
    camera.local.position = c.EYE
    camera.look_at(c.TARGET)  # up: the camera's reference up, +Y
    canvas = RenderCanvas(size=(args.width, args.height), pixel_ratio=1)
    renderer = gfx.WgpuRenderer(canvas, pixel_scale=args.pixel_scale)
    canvas.request_draw(lambda: renderer.render(scene, camera))
    image = np.asarray(canvas.draw())
    load_s = time.perf_counter() - t0
    assert image.shape == (args.height, args.width, 4), image.shape

    device = renderer.device
    gpu = device.adapter.info.get("device") or None

    ms_readback = c.median_ms(lambda: np.asarray(canvas.draw()), args.frames, args.warmup)
    image = np.asarray(canvas.draw())

    def render_only() -> None:
        renderer.render(scene, camera)
        wait_gpu(device)

    ms_render_only = c.median_ms(render_only, args.frames, args.warmup)
    settings = (f"WgpuRenderer: pixel_scale {renderer.pixel_scale}, pixel_filter "
                f"{renderer.pixel_filter}; wgpu {wgpu.__version__}, {device.adapter.info.get('backend_type')}")
    c.report(args, "pygfx", gfx.__version__, ms_readback, ms_render_only, load_s, gpu, settings, image)


if __name__ == "__main__":
    main()
