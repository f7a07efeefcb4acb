"""Sponza with pygfx (wgpu-py, Vulkan), as a user would: gfx.load_gltf, a PointLight, a
PerspectiveCamera placed at the pose, and a rendercanvas offscreen canvas whose draw() returns
the frame as an (H, W, 4) uint8 array. Renderer defaults kept (2x2 supersampling, then its
Mitchell filter down to the canvas size) unless --pixel-scale is given.

    python benchmarks/peers/pygfx_bench.py --size 1920x1080 --frames 200 --json out.json

Render + readback: canvas.draw(). Render only: renderer.render() into the canvas texture without
presenting it (no copy to a buffer, no map), then wait for the GPU by a device poll (wgpu-py
0.32's queue.on_submitted_work_done_sync() raises a TypeError). Needs pygfx, wgpu, rendercanvas,
pylinalg, uharfbuzz, hsluv, freetype-py, jinja2 and gltflib (+ dataclasses-json, marshmallow<4).
"""

from __future__ import annotations

import time

import common as c


def wait_gpu(device) -> None:
    try:
        device.queue.on_submitted_work_done_sync()
    except TypeError:
        device._poll_wait()  # wgpuDevicePoll(wait=True): every submitted command done


def main() -> None:
    args = c.parse_args("pygfx", lambda ap: ap.add_argument(
        "--pixel-scale", type=float, default=None,
        help="WgpuRenderer pixel_scale (default: pygfx's, 2 = 2x2 supersampling)"))
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
