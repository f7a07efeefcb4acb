"""`vkpbr render FILE --animate`: a scene's glTF animation as frames or a clip.

`--time T [--animation NAME]` poses a single render; `--animate` renders `--duration` seconds
(default: the chosen animations' length) at `--fps` into `--out`: a folder of numbered PNGs
(with a transforms.json whose frames carry their times), or a clip: `.gif` through Pillow (a
dependency already, no codec to install), `.mp4` through imageio's ffmpeg plugin (the `video`
extra: imageio-ffmpeg ships its own ffmpeg binary, so no system package is needed). Frames
stream through render_many (frames in flight on the GPU) behind a progress bar; a clip is
written to a temporary file and renamed, so a failed run leaves no half-written clip.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path
from typing import Any

from vkpbr.app.common import camera_from_args, lights_from_args, load_scene_arg
from vkpbr.app.log import is_quiet, say
from vkpbr.errors import UsageError

__all__ = ["add_arguments", "run_animation", "animation_times", "animation_choice", "pose_times",
           "CLIP_SUFFIXES"]

CLIP_SUFFIXES = (".gif", ".mp4")
MAX_FRAMES = 100_000  # a typo in --fps or --duration should not fill a disk


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The render command's animation flags."""
    g = p.add_argument_group("animation options")
    g.add_argument("--time", type=float, metavar="SECONDS",
                   help="pose the scene at this time of its glTF animations")
    g.add_argument("--animation", metavar="NAME|INDEX",
                   help="which animation --time and --animate play (default: all of them)")
    g.add_argument("--animate", action="store_true",
                   help="render the animation into --out: a folder of frames, or a .gif/.mp4 clip")
    g.add_argument("--fps", type=float, default=30.0, help="frames per second of --animate (30)")
    g.add_argument("--duration", type=float, metavar="SECONDS",
                   help="seconds of --animate (default: the animation's length)")


def animation_choice(scene: Any, text: str | None) -> int | str | None:
    """--animation as the API takes it: an index when it is a number."""
    if text is None:
        return None
    return int(text) if text.strip().lstrip("-").isdigit() else text


def animation_times(scene: Any, animation: int | str | None, fps: float,
                    duration: float | None) -> Any:
    """The frame times of --animate ((N,) float64): 0, 1/fps, ... up to `duration` (default:
    the longest chosen animation's), at least one frame."""
    import numpy as np

    from vkpbr.scene.animation import animation_indices

    if not (np.isfinite(fps) and fps > 0):
        raise UsageError(f"--fps {fps}: give a positive number of frames per second")
    chosen = animation_indices(scene, animation)
    if not chosen:
        raise UsageError(f"{scene.source or scene.name}: the scene has no animation to play")
    if duration is None:
        duration = max(scene.animations[i].duration for i in chosen)
    if not (np.isfinite(duration) and duration >= 0):
        raise UsageError(f"--duration {duration}: give a number of seconds >= 0")
    count = int(np.floor(duration * fps + 1e-9)) + 1
    if count > MAX_FRAMES:
        raise UsageError(f"--animate would render {count} frames (at most {MAX_FRAMES}): "
                         "lower --fps or --duration")
    return np.arange(count) / fps


def pose_times(poses: list[Any], where: str, time_arg: float | None) -> list[float] | None:
    """The animation time of each view of a poses file: its "time", else --time; None when
    neither gives one. Some views with a time and others without is an error."""
    given = [p.time for p in poses]
    if all(t is None for t in given):
        return None if time_arg is None else [time_arg] * len(poses)
    if any(t is None for t in given) and time_arg is None:
        missing = next(i for i, t in enumerate(given) if t is None)
        raise UsageError(f'{where}: entry {missing} has no "time" while others do (give every '
                         "view a time, or --time for those without)")
    return [time_arg if t is None else t for t in given]


def check_animation_args(args: argparse.Namespace) -> None:
    """Before any work: the output kind --animate writes."""
    out = Path(args.out)
    if out.suffix.lower() == ".mp4":
        try:
            import imageio.v3  # noqa: F401
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise UsageError("--out .mp4 needs imageio with ffmpeg: pip install 'vkpbr[video]' "
                             "(or write a .gif, or a folder of frames)") from None
    elif out.suffix and out.suffix.lower() not in CLIP_SUFFIXES:
        raise UsageError(f"--out {out}: with --animate, give a folder, a .gif or a .mp4")
    if args.outputs and out.suffix.lower() in CLIP_SUFFIXES:
        raise UsageError("--outputs writes files beside each frame: with --animate, give a "
                         "folder as --out")
    if args.cameras:
        raise UsageError("--animate plays one camera: use --camera, --camera-index or none "
                         "(a poses file can give each camera its own \"time\" instead)")


def run_animation(args: argparse.Namespace, options: Any) -> int:
    """`render --animate`: the frames, then the clip or the folder's files."""
    from tqdm import tqdm

    from vkpbr.app.output import write_image_atomic
    from vkpbr.io import check_outputs, write_outputs
    from vkpbr.render.renderer import Renderer
    from vkpbr.scene.camera_files import write_transforms

    check_animation_args(args)
    out = Path(args.out)
    t0 = time.perf_counter()
    scene = load_scene_arg(args)
    if scene is None:
        raise UsageError("--animate needs a scene file with animations")
    animation = animation_choice(scene, args.animation)
    times = animation_times(scene, animation, args.fps, args.duration)
    with Renderer(scene, device=args.device, validation=args.validation, msaa=args.msaa,
                  semantics=args.semantics) as renderer:
        camera = camera_from_args(args, renderer)
        lights = lights_from_args(args, renderer, options)
        names = tuple(args.outputs or ())
        if names:  # the folder is made last, after the frames: check its parent's here
            check_outputs(out.parent / "frame_00000.png", names, renderer.max_id)
        t1 = time.perf_counter()
        frames = renderer.render_many([camera] * len(times), lights, args.size, options,
                                      times=times, animation=animation,
                                      outputs=("color", *names) if names else None)
        bar = tqdm(frames, total=len(times), unit="frame", disable=True if is_quiet() else None)
        images = list(bar)
        t2 = time.perf_counter()
    extras = images if names else None  # the outputs (motion: from each frame's previous)
    images = [f["color"] for f in images] if names else images
    if out.suffix.lower() in CLIP_SUFFIXES:
        _write_clip(out, images, args.fps)
        wrote = str(out)
    else:
        out.mkdir(parents=True, exist_ok=True)
        names_ = [f"frame_{i:05d}.png" for i in range(len(images))]
        for i, (name, image) in enumerate(zip(names_, images, strict=True)):
            write_image_atomic(out / name, image)
            if extras is not None:
                write_outputs(out / name, extras[i], names)
        write_transforms(out / "transforms.json", [camera] * len(images), args.size, names_,
                         times=list(map(float, times)))
        wrote = f"{len(images)} frames and transforms.json to {out}/"
    say(f"wrote {wrote} ({args.size[0]}x{args.size[1]}, {len(times)} frames at {args.fps:g} fps, "
        f"{times[-1]:.2f} s of animation)")
    say(f"load + set-up {t1 - t0:.2f} s, rendering {1e3 * (t2 - t1) / len(times):.2f} ms per "
        f"frame, written after {time.perf_counter() - t1:.2f} s")
    return 0


def _write_clip(out: Path, images: list[Any], fps: float) -> None:
    """A .gif (Pillow) or .mp4 (imageio-ffmpeg, H.264) of RGBA frames, written beside `out`
    and renamed onto it."""
    import numpy as np

    tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp{out.suffix}")
    try:
        if out.suffix.lower() == ".gif":
            from PIL import Image

            pics = [Image.fromarray(np.ascontiguousarray(im[..., :3])) for im in images]
            pics[0].save(tmp, save_all=True, append_images=pics[1:], loop=0,
                         duration=max(int(round(1000 / fps)), 20), optimize=False)
        else:
            import imageio.v3 as iio

            rgb = np.stack([im[..., :3] for im in images])
            even = rgb[:, : rgb.shape[1] // 2 * 2, : rgb.shape[2] // 2 * 2]  # yuv420p: even sizes
            iio.imwrite(tmp, even, plugin="FFMPEG", fps=fps, codec="libx264", macro_block_size=1)
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
