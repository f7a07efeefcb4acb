"""`vkpbr view [SCENE]`: the command-line face of the interactive viewer (app/viewer.py).

The mode options are those of `vkpbr render`, so a view can be opened in the state a headless
render was made in, and `C` in the window prints the render command back.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from vkpbr.errors import UsageError

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vkpbr.app.cli import add_device_options, add_shading_options

    p = sub.add_parser("view", help="open SCENE in an interactive window",
                       description="Fly through SCENE (default: the built-in PBR chart); "
                                   "keys and scripts: docs/viewer.md.")
    p.add_argument("scene", nargs="?", help="glTF/GLB/OBJ/.comp5822mesh/.vkpbr file")
    p.add_argument("--size", default="1280x720", help="window WIDTHxHEIGHT (default 1280x720)")
    p.add_argument("--camera", help="start pose ex,ey,ez,tx,ty,tz[,ux,uy,uz] (as `render`)")
    p.add_argument("--camera-index", type=int, help="start at the scene file's camera N")
    add_shading_options(p)
    p.add_argument("--no-vsync", action="store_true",
                   help="present without waiting for vertical sync (mailbox, else immediate)")
    p.add_argument("--offscreen", action="store_true",
                   help="no window: run the frame loop on offscreen images of --size (a GPU "
                        "server without a display); needs --frames or --script; prints fps")
    p.add_argument("--frames", type=int, help="render N frames, then exit")
    p.add_argument("--screenshot", help="with --frames: write the last frame to this PNG")
    p.add_argument("--script", help="JSON file of timed input events (docs/viewer.md)")
    add_device_options(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from vkpbr.app.cli import (
        _camera_from_args,
        _light_from_args,
        check_writable,
        load_scene_arg,
        options_from_args,
        parse_size,
    )

    size = parse_size(args.size)
    if args.frames is not None and args.frames < 1:
        raise UsageError("--frames must be at least 1")
    if args.offscreen and args.frames is None and not args.script:
        raise UsageError("--offscreen needs --frames N or --script FILE (nothing could stop it)")
    shot = None
    if args.screenshot:
        if args.frames is None:
            raise UsageError("--screenshot needs --frames N (press P in the window instead)")
        shot = Path(args.screenshot)
        check_writable(shot)
        if shot.suffix.lower() != ".png":
            raise UsageError(f"--screenshot {shot}: give a .png file name")
    options = options_from_args(args)  # unknown names fail before the window opens
    script = None
    if args.script:
        from vkpbr.app.script import load_script

        script = load_script(args.script)
    scene = load_scene_arg(args)
    from vkpbr.app.viewer import Viewer, ViewerConfig

    config = ViewerConfig(
        size=size, options=options, vsync=not args.no_vsync, frames=args.frames,
        screenshot=shot, script=script, validation=args.validation, device=args.device,
        offscreen=args.offscreen,
        title=f"vkpbr - {Path(args.scene).name if args.scene else 'default scene'}",
        scene_label=args.scene or "",
        pose=lambda r: (_camera_from_args(args, r), _light_from_args(args, r)))
    with Viewer(scene, config) as viewer:
        status = viewer.run()
        print(viewer.summary())
    return status
