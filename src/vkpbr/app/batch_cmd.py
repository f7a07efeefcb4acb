"""`vkpbr batch JOB.json [--ray ADDRESS]`: render a job of many scenes on Ray, and the
`vkpbr render SCENE --cameras POSES --out DIR --ray [ADDRESS]` path (one scene's job).
Both end with the job's summary; exit status 1 when items failed. See docs/distributed.md."""

from __future__ import annotations

import argparse
import dataclasses
import logging
from pathlib import Path
from typing import Any

from vkpbr.app.log import say
from vkpbr.app.parsing import EPILOG_FORMATTER
from vkpbr.config import BATCH_VIEWS
from vkpbr.errors import UsageError

__all__ = ["add_parser", "run", "add_ray_arguments", "render_on_ray"]

log = logging.getLogger(__name__)

EPILOG = """\
examples:
  vkpbr batch job.json                      a local Ray instance, one actor per CPU or GPU
                                            (without Ray installed: as --processes)
  vkpbr batch job.json --ray head:6379      an existing Ray cluster
  vkpbr batch job.json --ray                a local Ray instance (an error without Ray)
  vkpbr batch job.json --ray auto --num-gpus 0.5   two actors on each GPU
  vkpbr batch job.json --in-process         no Ray: one renderer here, the next scene loading
                                            on a thread while this one renders
  vkpbr batch job.json --processes          no Ray: renderer processes on this machine's GPU
                                            (3 for every 8 cores, 1 to 8; --processes 4: four)
  vkpbr batch job.json --processes 16 --devices 0,1,2,3
                                            sixteen processes over four GPUs, in turn
"""

# `vkpbr render` options a --ray job does not carry (each actor uses the scene's camera and
# lights, as `vkpbr render --cameras` does without them).
_NOT_WITH_RAY = (("camera", "--camera"), ("camera_index", "--camera-index"), ("fov", "--fov"),
                 ("light", "--light"), ("light_color", "--light-color"),
                 ("light_intensity", "--light-intensity"), ("falloff", "--falloff"),
                 ("device", "--device"), ("variant", "--variant"), ("animate", "--animate"))


def add_ray_arguments(p: argparse.ArgumentParser, with_flag: bool = True) -> None:
    """--ray [ADDRESS] (with `with_flag`), --actors, --num-gpus."""
    if with_flag:
        p.add_argument("--ray", nargs="?", const="local", metavar="ADDRESS",
                       help="render on Ray: a cluster's HOST:PORT, ray://HOST:PORT or auto; "
                            "alone: a local Ray instance (needs vkpbr[ray])")
    p.add_argument("--actors", type=int, metavar="N",
                   help="renderer actors (default: one per GPU, else one per CPU)")
    p.add_argument("--num-gpus", type=float, metavar="F",
                   help="GPUs per actor (0.5: two actors share each GPU)")


def add_parser(sub: Any) -> None:
    p = sub.add_parser("batch", help="render a job of many scenes and poses on Ray",
                       description="Render every entry of JOB (a JSON list of {scene, cameras, "
                                   "out, size, outputs}) on Ray: resumable (a manifest in each "
                                   "out folder records finished views) and exactly once.",
                       epilog=EPILOG, formatter_class=EPILOG_FORMATTER)
    p.add_argument("job", metavar="JOB.json", help="the job file (docs/distributed.md)")
    p.add_argument("--ray", nargs="?", const="local", metavar="ADDRESS",
                   help="a Ray cluster's HOST:PORT, ray://HOST:PORT or auto; alone: a local "
                        "Ray instance (the default where Ray is installed; without it, "
                        "--processes)")
    p.add_argument("--in-process", action="store_true",
                   help="render in this process without Ray (one renderer on the default "
                        "device; the same files and manifests, resumable alike)")
    p.add_argument("--processes", nargs="?", const=0, type=_processes, metavar="N",
                   help="render without Ray in N renderer processes of this machine (default "
                        "device; alone: 3 for every 8 cores, 1 to 8; at most one an item): a "
                        "many-scene job's scene changes run side by side")
    p.add_argument("--devices", type=_devices, metavar="LIST",
                   help="with --processes: the GPUs the processes open in turn, as indices or "
                        "name parts (`vkpbr info` lists them), e.g. 0,1,2,3 (default: the "
                        "default device)")
    add_ray_arguments(p, with_flag=False)
    p.set_defaults(run=run)


def _has_ray() -> bool:
    """Whether the ray extra imports (vkpbr batch's default then: a local Ray instance)."""
    try:
        import ray  # noqa: F401
    except ImportError:
        return False
    return True


def _devices(text: str) -> list[str]:
    """--devices 0,1 (or name parts): non-empty items (argparse's one line otherwise)."""
    items = [t.strip() for t in text.split(",")]
    if not items or any(not t for t in items):
        raise argparse.ArgumentTypeError(f"expected device indices or names separated by "
                                         f"commas, got {text!r}")
    return items


def _processes(text: str) -> int:
    """--processes N: a whole number of at least 1 (argparse's one line otherwise)."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number of at least 1, got {text!r}")
    return n


def _report(result: Any) -> int:
    lines = result.summary()
    if result.ok:
        say(lines[0])
        return 0
    for line in lines:
        log.error("%s", line)
    return 1


def _render(job: Any, args: argparse.Namespace) -> int:
    from vkpbr.app.log import is_quiet
    from vkpbr.distributed import render
    from vkpbr.distributed.cluster import RAY_INSTALL
    from vkpbr.distributed.driver import IN_PROCESS, PROCESSES

    processes = getattr(args, "processes", None)
    actors = args.actors
    if getattr(args, "in_process", False) and processes is not None:
        raise UsageError("--in-process and --processes: choose one (one renderer in this "
                         "process, or N renderer processes)")
    if processes is not None and args.ray is not None:
        raise UsageError("--ray and --processes: choose one (a Ray cluster, or renderer "
                         "processes of this machine)")
    if processes is not None:
        address, actors = PROCESSES, processes or actors  # (--processes alone: 0)
    elif getattr(args, "in_process", False):
        address = IN_PROCESS
    elif args.ray is None and not _has_ray():
        address = PROCESSES  # the documented fallback: no Ray, this machine's processes
        log.info("ray is not installed: rendering on renderer processes of this machine "
                 "(--processes; %s for a Ray cluster)", RAY_INSTALL)
    else:
        address = None if args.ray in (None, "local") else args.ray
    devices = getattr(args, "devices", None)
    if devices is not None and address != PROCESSES:
        raise UsageError("--devices goes with --processes (Ray places its actors on GPUs "
                         "itself; --in-process uses one)")
    result = render(job, address, actors=actors, num_gpus=args.num_gpus, devices=devices,
                    progress=False if is_quiet() else None)
    return _report(result)


def run(args: argparse.Namespace) -> int:
    from vkpbr.distributed import load_job

    return _render(load_job(args.job), args)


def _semantics_arg(value: str) -> str:
    """--semantics for the actors: a source name, or the mapping file checked and absolute."""
    from vkpbr.scene.semantics import SEMANTIC_SOURCES, load_semantic_mapping

    if value in SEMANTIC_SOURCES:
        return value
    load_semantic_mapping(value)  # a bad file fails here, before any actor starts
    return str(Path(value).resolve())


# `vkpbr render --cameras` options besides RenderOptions that change the frames (the Ray
# path refuses them): they are part of the folder's fingerprint when given.
_FRAME_ARGS = ("camera", "camera_index", "fov", "light", "light_color", "light_intensity",
               "falloff", "variant", "time", "animation")


def orbit_poses(n: int, scene: Any) -> tuple[Any, ...]:
    """`--orbit N`: N views of a turntable around the scene's bounds (CameraBatch.orbit: 20
    degrees above the horizon, 45 degree field of view, the bounds framed)."""
    from vkpbr.scene.camera import Pose
    from vkpbr.scene.camera_batch import CameraBatch

    if scene is None:  # the built-in chart
        from vkpbr.scene.default import default_scene

        scene = default_scene()
    batch = CameraBatch.orbit(n, bounds=scene.bounds())
    return tuple(Pose(tuple(map(float, batch.eye[i])), tuple(map(float, batch.target[i])),
                      tuple(map(float, batch.up[i])), float(batch.yfov_deg[i]),
                      name=f"orbit {i}", where=f"--orbit view {i}") for i in range(n))


def _given(value: object) -> bool:
    """Whether an option was given: not its default None, False or an empty list (0 is)."""
    return not (value is None or value is False or value == [] or value == ())


def frames_job(args: argparse.Namespace, options: Any, where: str = "--out",
               poses: tuple[Any, ...] | None = None) -> Any:
    """The one-entry job of `vkpbr render SCENE --cameras POSES --out DIR [--ray]`: its
    settings, poses (read and checked) and the folder's fingerprint, the same with and
    without --ray so that either may resume the other's folder. Nothing is created."""
    from vkpbr.distributed.job import RenderSettings, SceneJob
    from vkpbr.io import OUTPUT_SUFFIXES
    from vkpbr.scene.poses import load_poses, poses_size

    out = Path(args.out)
    if out.suffix.lower() in OUTPUT_SUFFIXES:
        raise UsageError(f"--out {out}: with --cameras, --out is a folder")
    if poses is None:  # the whole file is checked before the scene loads
        poses = tuple(load_poses(args.cameras))
    settings = RenderSettings(
        scene=Path(args.scene) if args.scene else None, out=out,
        size=poses_size(list(poses), args.size, "--size"),
        outputs=tuple(args.outputs or ()), linear=args.linear, msaa=args.msaa,
        cache=args.cache is not None, cache_dir=args.cache or None, options=options,
        strict=bool(getattr(args, "strict", False)),
        allow_outside_paths=bool(getattr(args, "allow_outside_paths", False)),
        semantics=_semantics_arg(getattr(args, "semantics", "mesh")),
        batch=int(getattr(args, "batch", BATCH_VIEWS)))
    if settings.scene is not None and not settings.scene.is_file():
        raise UsageError(f"{settings.scene}: no such scene file")
    extra = tuple(sorted((name, repr(getattr(args, name))) for name in _FRAME_ARGS
                         if _given(getattr(args, name, None))))
    worlds = _worlds_arg(args, len(poses), settings.allow_outside_paths)
    return SceneJob(settings, poses, colmap=args.colmap, where=where, extra=extra, worlds=worlds)


def _worlds_arg(args: argparse.Namespace, views: int, outside: bool) -> Any:
    """`--worlds FILE.json`: a job entry's "worlds" object in a file of its own, its paths
    relative to that file (vkpbr.distributed.worlds); None without the option."""
    path = getattr(args, "worlds", None)
    if not path:
        return None
    from vkpbr.distributed.worlds import job_worlds
    from vkpbr.errors import JsonError
    from vkpbr.json_input import read_json
    from vkpbr.user_paths import check_path, os_reason

    if args.time is not None or getattr(args, "animate", None):
        raise UsageError("--worlds poses nodes per view: not with --time or --animate")
    try:
        doc = read_json(check_path(path, "--worlds"))
    except OSError as exc:
        raise UsageError(f"--worlds {path}: cannot read it: {os_reason(exc)}") from None
    except JsonError as exc:
        raise UsageError(f"--worlds {path}: not valid JSON ({exc.problem})") from None
    return job_worlds(doc, views, f"--worlds {path}", Path(path).parent, outside)


def render_on_ray(args: argparse.Namespace, options: Any) -> int:
    """`vkpbr render SCENE --cameras POSES --out DIR --ray [ADDRESS]`: the same files as
    without --ray, rendered by the actors of a one-entry job."""
    from vkpbr.distributed import Job
    from vkpbr.distributed.job import view_times

    if not args.cameras and not getattr(args, "orbit", None):
        raise UsageError("--ray renders a --cameras batch (or --orbit N): give --cameras too")
    for dest, flag in _NOT_WITH_RAY:
        if _given(getattr(args, dest, None)):
            raise UsageError(f"{flag} is not available with --ray (the actors render with the "
                             "scene's camera and lights); drop it or render without --ray")
    if args.frames != 1:
        raise UsageError("--frames is a timing option: not available with --ray")
    poses = None
    if getattr(args, "orbit", None):  # the bounds need the scene, here as well as on the actors
        from vkpbr.app.common import load_scene_arg

        poses = orbit_poses(args.orbit, load_scene_arg(args))
    scene = frames_job(args, options, poses=poses)
    time, animation = getattr(args, "time", None), getattr(args, "animation", None)
    if time is not None or animation is not None:  # the poses' "time"s, else --time
        from vkpbr.app.animate_cmd import animation_choice

        scene = dataclasses.replace(scene, settings=dataclasses.replace(
            scene.settings, time=time, animation=animation_choice(None, animation)))
    if scene.worlds is not None and view_times(scene.poses, scene.settings) is not None:
        raise UsageError('--worlds with animation times ("time" in the poses, --time) is not '
                         "rendered yet: give one or the other")
    view_times(scene.poses, scene.settings, str(args.cameras or "--orbit"))
    return _render(Job((scene,), source="--cameras"), args)
