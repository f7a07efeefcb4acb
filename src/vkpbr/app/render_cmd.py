"""`vkpbr render [SCENE]`: render headless to an image file, or one image per camera pose
(--cameras) with frames in flight."""

from __future__ import annotations

import argparse
import logging
import os
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from vkpbr.app.animate_cmd import add_arguments as add_animation_arguments
from vkpbr.app.animate_cmd import animation_choice, pose_times, run_animation
from vkpbr.app.common import camera_from_args, lights_from_args, load_scene_ahead, load_scene_arg
from vkpbr.app.log import is_quiet, say
from vkpbr.app.options import add_options, render_options_from_args
from vkpbr.app.parsing import EPILOG_FORMATTER, _as_type, size_arg
from vkpbr.config import BATCH_VIEWS, default_cache_dir
from vkpbr.errors import UsageError
from vkpbr.io import (
    check_id_count,
    check_output_path,
    check_outputs,
    output_kind,
    output_path,
    write_image_atomic,
    write_outputs,
)

__all__ = ["add_parser", "run"]

log = logging.getLogger(__name__)

EPILOG = """\
examples:
  vkpbr render --out chart.png                       the built-in PBR chart
  vkpbr render scene.gltf --size 1920x1080 --camera 9,1.8,-0.4,-9,3.5,-0.4 --light -5,0.6,-0.9
  vkpbr render scene.gltf --view d --brdf blinn-phong --out d.png
  vkpbr render scene.gltf --cameras poses.json --out frames/
  vkpbr render scene.gltf --cameras poses.json --out frames/ --ray    the same, on Ray
"""


def add_parser(sub: Any) -> None:
    p = sub.add_parser("render", help="render a scene (or the built-in default scene) to an image",
                       description="Render SCENE headless to an image file (or, with --cameras, "
                                   "one image per camera pose into a folder).",
                       epilog=EPILOG, formatter_class=EPILOG_FORMATTER)
    p.add_argument("scene", nargs="?",
                   help="glTF/GLB/OBJ/.comp5822mesh/.vkpbr file; default: the built-in PBR chart")
    p.add_argument("--out", "-o", default="render.png",
                   help="output image: 8-bit .png, .jpg, .bmp, .tif, .webp (RGBA where the format "
                        "has alpha; .jpg drops it), float .exr or .npy with --linear; a folder "
                        "with --cameras; default render.png")
    p.add_argument("--size", type=size_arg, metavar="WxH",
                   help="image size (default 1280x720; with --cameras, the size the poses "
                        "file states, else 1280x720)")
    p.add_argument("--camera", metavar="EX,EY,EZ,TX,TY,TZ[,UX,UY,UZ]",
                   help="eye, target and up (default: the scene's camera, else one framing it)")
    p.add_argument("--camera-index", type=int, metavar="N", help="use the scene file's camera N")
    p.add_argument("--cameras", metavar="FILE.json",
                   help="render one image per camera pose in FILE (a JSON list of "
                        '"ex,ey,ez,tx,ty,tz[,ux,uy,uz]" strings or {"eye","target","up","fov"} '
                        "objects, pose matrices, K + pose, a NeRF transforms.json) into the folder "
                        "--out, with the cameras as written as a NeRF transforms.json there")
    p.add_argument("--orbit", type=int, metavar="N",
                   help="render N views of a turntable around the scene into the folder --out "
                        "(CameraBatch.orbit: 20 degrees above the horizon, the bounds framed), "
                        "as --cameras does")
    p.add_argument("--batch", type=int, default=BATCH_VIEWS, metavar="N",
                   help="with --cameras, render N views per GPU submission (Renderer.render_batch; "
                        "directional lights' shadows then use one map over the whole scene); "
                        "0: frame by frame, each with its own shadow cascades (default %(default)s)")
    p.add_argument("--worlds", metavar="FILE.json",
                   help="with --cameras, each view in its own world: a JSON object {nodes, "
                        "poses: .npy of (views, nodes, 7) or (views, nodes, 4, 4), quaternion, "
                        'visible, world_of_view}, as a job entry\'s "worlds" (docs/distributed.md)')
    p.add_argument("--colmap", action="store_true",
                   help="with --cameras, also write the cameras as COLMAP text files "
                        "(cameras.txt, images.txt, points3D.txt) in --out")
    p.add_argument("--outputs", metavar="NAME,...",
                   type=_as_type(_output_names, "--outputs", "output list"),
                   help="dataset outputs of the same frame, written beside --out as "
                        "STEM.NAME.exr (depth, range, normal, normal_camera, normal_geometric, "
                        "ao: "
                        "float) or STEM.NAME.png (instance, semantic: 16-bit ids); see "
                        "docs/outputs.md")
    p.add_argument("--semantics", default="mesh", metavar="mesh|material|extras|FILE.json",
                   help="where the semantic ids of --outputs semantic come from: each mesh "
                        "primitive its own class (default), each material, the glTF nodes' "
                        'extras {"semantic": id or label}, or a JSON {node, mesh or material '
                        "name: id or label} (docs/outputs.md)")
    p.add_argument("--list-views", action="store_true", help="list the debug views and exit")
    from vkpbr.app.batch_cmd import add_ray_arguments

    add_ray_arguments(p)  # --ray [ADDRESS], --actors, --num-gpus: the batch on Ray
    p.add_argument("--msaa", type=int, default=1, choices=[1, 4], help="samples per pixel")
    p.add_argument("--linear", action="store_true", help="linear float32 colour (write a .exr or .npy)")
    p.add_argument("--frames", type=int, default=1, metavar="N",
                   help="render N frames and report the median time per frame")
    add_animation_arguments(p)
    p.defer(add_options)
    p.set_defaults(run=run)


def _output_names(text: str) -> tuple[str, ...]:
    """`--outputs depth,instance`: the names, each checked (argparse's one-line error)."""
    from vkpbr.io import OUTPUT_KINDS

    names = tuple(n.strip() for n in text.split(",") if n.strip())
    for name in names:
        if name not in OUTPUT_KINDS:
            raise UsageError(f"unknown output {name!r} (known: {', '.join(OUTPUT_KINDS)})")
    return tuple(n for n in names if n != "color")


# The outputs beside a frame: shared with vkpbr.distributed (vkpbr/io.py).
_output_path, _check_outputs, _write_outputs = output_path, check_outputs, write_outputs


def list_views() -> int:
    from vkpbr.render.layouts import VIEW_HELP

    for view, text in VIEW_HELP.items():
        print(f"{view.label:18s} {text}")
    return 0


def _render_batch(args: argparse.Namespace, options: Any) -> int:
    """--cameras: frames in flight on the GPU, PNG encoding on worker threads, into a frames
    folder kept by its manifest (vkpbr.distributed.manifest): a folder of another run is
    refused, one of this run resumed (views whose files are there with their recorded sizes
    are not rendered again), and transforms.json is written once every view is done."""
    from vkpbr.app.batch_cmd import frames_job
    from vkpbr.distributed.manifest import (
        abandon_frames_folder,
        open_frames_folder,
        remove_leftovers,
    )
    from vkpbr.render.renderer import Renderer

    t0 = time.perf_counter()
    scene, poses = None, None
    if args.orbit:  # the orbit frames the scene's bounds: the scene loads first
        from vkpbr.app.batch_cmd import orbit_poses

        scene = load_scene_arg(args)
        poses = orbit_poses(args.orbit, scene)
    job = frames_job(args, options, poses=poses)  # poses, size, fingerprint: before the scene
    manifest = open_frames_folder(job)  # a folder another run made is refused here
    try:
        todo = sorted(set(range(len(job.poses))) - manifest.done_views())
        if todo and scene is None:
            scene = load_scene_arg(args)
        with Renderer(scene, device=args.device, validation=args.validation, msaa=args.msaa,
                      semantics=args.semantics,
                      cache_dir=default_cache_dir()) as renderer:
            base = camera_from_args(args, renderer)
            cameras = [pose.camera(base) for pose in job.poses]
            times = pose_times(list(job.poses), args.cameras or "--orbit", args.time)
            if todo:
                t1 = time.perf_counter()
                log.info("load + set-up %.2f s", t1 - t0)
                _render_views(args, options, job, manifest, renderer, cameras, todo, times)
            t2 = time.perf_counter()
    except BaseException:
        abandon_frames_folder(job, manifest, manifest.created)
        raise
    finally:
        manifest.close()
    remove_leftovers(job)
    # The cameras as rendered, for NeRF / 3D-reconstruction tools (docs/camera-files.md).
    from vkpbr.scene.camera_files import write_colmap, write_transforms

    size, out_dir, n = job.settings.size, Path(job.settings.out), len(job.poses)
    names = [job.transforms_name(i) for i in range(n)]
    write_transforms(out_dir / "transforms.json", cameras, size, names, times=times)
    wrote = ["transforms.json"]
    if args.colmap:
        wrote += [p.name for p in write_colmap(out_dir, cameras, size, names)]
    before = f", {n - len(todo)} done before" if len(todo) < n else ""
    say(f"wrote {len(todo)} images{before} and {', '.join(wrote)} to {out_dir}/ "
        f"({size[0]}x{size[1]}, view {options.view})")
    if todo:
        say(f"load + set-up {t1 - t0:.2f} s, rendering {1e3 * (t2 - t1) / len(todo):.2f} ms "
            f"per frame ({len(todo) / (t2 - t1):.1f} frames/s)")
    return 0


def _render_views(args: argparse.Namespace, options: Any, job: Any, manifest: Any,
                  renderer: Any, cameras: list[Any], todo: list[int],
                  times: list[float] | None = None) -> None:
    """Render views `todo` and record them in the manifest as their files land (in order,
    a group at a time: a killed run loses only what it had not recorded)."""
    from concurrent.futures import ThreadPoolExecutor

    from tqdm import tqdm

    from vkpbr.distributed.manifest import camera_record, start_frames_folder

    out_dir, size = Path(job.settings.out), job.settings.size
    names = job.settings.outputs
    lights = lights_from_args(args, renderer, options)
    for name in names:  # the formats were checked before the scene loaded; now the id count
        if output_kind(name) == "ids":
            check_id_count(renderer.max_id, output_path(out_dir / job.files(0)[0], name),
                           "--outputs")
    manifest.created = start_frames_folder(job, manifest)  # made last: all checks are done
    pending: list[tuple[int, list[Any]]] = []

    def record(done_only: bool) -> None:
        group = []
        while pending and (not done_only or all(f.done() for f in pending[0][1])):
            view, futures = pending.pop(0)
            for f in futures:
                f.result()
            group.append(view)
        if group:
            manifest.done(group, [f for v in group for f in job.files(v)],
                          [camera_record(cameras[v]) for v in group])

    with ThreadPoolExecutor(max(2, (os.cpu_count() or 2) - 1)) as pool:
        if job.worlds is not None:  # each view in its world, as the Ray actors render them
            frames = _world_frames(args, job, renderer, cameras, lights, todo)
        else:
            frames = renderer.render_many([cameras[v] for v in todo], lights, size, options,
                                          linear=args.linear,
                                          outputs=("color", *names) if names else None,
                                          batch=args.batch or None,
                                          times=None if times is None else [times[v] for v in todo],
                                          animation=animation_choice(renderer.scene, args.animation))
        bar = tqdm(frames, total=len(todo), unit="frame", disable=True if is_quiet() else None)
        for view, image in zip(todo, bar, strict=True):
            files = [out_dir / f for f in job.files(view)]
            futures = []
            if names:
                futures.append(pool.submit(_write_outputs, files[0], image, names))
                image = image["color"]
            futures.append(pool.submit(write_image_atomic, files[0], image))
            pending.append((view, futures))
            if len(pending) >= 16:
                record(done_only=True)
        record(done_only=False)


def _world_frames(args: argparse.Namespace, job: Any, renderer: Any, cameras: list[Any],
                  lights: Any, todo: list[int]) -> Iterator[Any]:
    """--worlds: views `todo`, each in its world, as a Ray actor renders them
    (vkpbr.distributed.actor.render_views), in render_many's form."""
    from vkpbr.distributed.actor import render_views

    frames = render_views(renderer, [cameras[v] for v in todo], lights, job.settings,
                          job.worlds.item(tuple(todo)), f"--worlds {args.worlds}")
    return (f if job.settings.outputs else f["color"] for f in frames)


def run(args: argparse.Namespace) -> int:
    if args.list_views:
        return list_views()
    options = render_options_from_args(args)  # bad values fail here, before any expensive work
    if args.worlds and not (args.cameras or args.orbit):
        raise UsageError("--worlds gives each view of a --cameras batch its world: give --cameras too")
    if args.colmap and not (args.cameras or args.orbit):
        raise UsageError("--colmap writes the cameras of a --cameras batch: give --cameras too")
    if args.batch < 0:
        raise UsageError(f"--batch {args.batch}: give a number of views per submission, or 0")
    if args.orbit is not None:
        if args.cameras:
            raise UsageError("--orbit makes the cameras: not with --cameras")
        if args.orbit < 1:
            raise UsageError(f"--orbit {args.orbit}: give a number of views >= 1")
    if args.ray is not None:
        from vkpbr.app.batch_cmd import render_on_ray

        return render_on_ray(args, options)
    if args.animate:
        return run_animation(args, options)
    if args.cameras or args.orbit:
        return _render_batch(args, options)
    size = args.size or (1280, 720)
    out = Path(args.out)
    check_output_path(out)  # the folder, the image type, OpenEXR for .exr: before any work
    if args.linear and out.suffix.lower() not in (".npy", ".exr"):
        raise UsageError("--linear writes float32 colour: give an --out path ending in .exr or .npy")
    if not args.linear and out.suffix.lower() == ".exr":
        raise UsageError(f"--out {out}: EXR holds linear float colour: add --linear")
    if args.frames < 1:
        raise UsageError("--frames must be at least 1")
    from vkpbr.render.renderer import Renderer

    t0 = time.perf_counter()
    scene = load_scene_ahead(args)  # loaded on a thread while the Renderer makes its device
    t_load = time.perf_counter()
    with Renderer(scene, device=args.device, validation=args.validation, msaa=args.msaa,
                  semantics=args.semantics,
                  cache_dir=default_cache_dir()) as renderer:
        t_setup = time.perf_counter()
        wait = renderer.timings.get("load_wait", 0.0)  # the load the device's making did not hide
        camera = camera_from_args(args, renderer)
        lights = lights_from_args(args, renderer, options)
        log.debug("camera %s, lights %s", camera, lights)
        if args.time is not None:
            renderer.set_time(args.time, animation_choice(renderer.scene, args.animation))
        names = args.outputs or ()
        if names:
            _check_outputs(out, names, renderer.max_id)
            frame = renderer.render(camera, lights, size, options, linear=args.linear,
                                    outputs=("color", *names))
            _write_outputs(out, frame, names)
        image = renderer.render(camera, lights, size, options, linear=args.linear)
        t_first = time.perf_counter()
        per_frame = []
        for _ in range(args.frames - 1):
            t = time.perf_counter()
            image = renderer.render(camera, lights, size, options, linear=args.linear)
            per_frame.append(time.perf_counter() - t)
        stats = renderer.last_stats
        device_name = renderer.device.info.name
        from vkpbr.render.scene_swap import pipeline_timings

        phases = {**renderer.timings, **pipeline_timings(renderer.device)}  # pipelines: so far
        log.info("set-up by phase: %s", ", ".join(  # -v: where the load's time went
            f"{k} {v:.3f} s" if isinstance(v, float) else f"{k} {v}" for k, v in phases.items()))
    t_closed = time.perf_counter()  # (the frames and the Renderer's close are not the write's)
    write_image_atomic(out, image)
    t_write = time.perf_counter()
    extra = "".join(f", {_output_path(out, n).name}" for n in (args.outputs or ()))
    say(f"wrote {out}{extra} ({size[0]}x{size[1]}, view {options.view}, {device_name})")
    timing = (f"load {t_load - t0 + wait:.2f} s (beyond the device's making), "
              f"set-up {t_setup - t_load - wait:.2f} s, "
              f"first frame {1e3 * (t_first - t_setup):.1f} ms")
    if per_frame:
        per_frame.sort()
        timing += f", per frame {1e3 * per_frame[len(per_frame) // 2]:.2f} ms (median of {len(per_frame)})"
    timing += f", GPU {stats.gpu_ms:.2f} ms, write {1e3 * (t_write - t_closed):.0f} ms"
    say(timing)
    return 0
