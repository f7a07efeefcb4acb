"""`vkpbr view [SCENE]`: the command-line face of the interactive viewer (app/viewer.py).

The shading, light and device options are those of `vkpbr render` (one table,
app/options.py), so a view can be opened in the state a headless render was made in, and
`C` in the window prints the render command back.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from vkpbr.app.common import camera_from_args, lights_from_args, load_scene_ahead
from vkpbr.app.log import say
from vkpbr.app.options import add_options, render_options_from_args
from vkpbr.app.parsing import EPILOG_FORMATTER, size_arg
from vkpbr.errors import UsageError
from vkpbr.io import check_writable

__all__ = ["add_parser", "run"]

EPILOG = """\
examples:
  vkpbr view scene.gltf                              fly with W/A/S/D and the mouse; H: key help
  vkpbr view scene.gltf --view mapped-normal --light -5,0.6,-0.9
  vkpbr view scene.gltf --frames 60 --screenshot shot.png --no-vsync
  vkpbr view scene.gltf --offscreen --frames 600 --size 1920x1080   (no display: the loop's fps)

keys, mouse and --script files: docs/viewer.md
"""


def add_parser(sub: Any) -> None:
    p = sub.add_parser("view", help="open SCENE in an interactive window",
                       description="Fly through SCENE (default: the built-in PBR chart) in a "
                                   "window; every mode switches at run time.",
                       epilog=EPILOG, formatter_class=EPILOG_FORMATTER)
    p.add_argument("scene", nargs="?", help="glTF/GLB/OBJ/.comp5822mesh/.vkpbr file")
    p.add_argument("--size", type=size_arg, default="1280x720", metavar="WxH",
                   help="window size (default 1280x720)")
    p.add_argument("--camera", metavar="EX,EY,EZ,TX,TY,TZ[,UX,UY,UZ]",
                   help="start pose (as `render`)")
    p.add_argument("--camera-index", type=int, metavar="N", help="start at the scene file's camera N")
    p.add_argument("--no-vsync", action="store_true",
                   help="present without waiting for vertical sync (mailbox, else immediate)")
    p.add_argument("--offscreen", action="store_true",
                   help="no window: run the frame loop on offscreen images of --size (a GPU "
                        "server without a display); needs --frames or --script; prints fps")
    p.add_argument("--frames", type=int, metavar="N", help="render N frames, then exit")
    p.add_argument("--screenshot", metavar="PATH.png", help="with --frames: write the last frame here")
    p.add_argument("--script", metavar="FILE.json", help="JSON file of timed input events (docs/viewer.md)")
    p.defer(add_options)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    size = args.size
    if args.frames is not None and args.frames < 1:
        raise UsageError("--frames must be at least 1")
    if args.offscreen and args.frames is None and not args.script:
        raise UsageError("--offscreen needs --frames N or --script FILE (nothing could stop it)")
    shot = None
    if args.screenshot:
        if args.frames is None:
            raise UsageError("--screenshot needs --frames N (press P in the window instead)")
        shot = Path(args.screenshot)
        check_writable(shot, "--screenshot")
        if shot.suffix.lower() != ".png":
            raise UsageError(f"--screenshot {shot}: give a .png file name")
    options = render_options_from_args(args)  # bad values fail before the window opens
    script = None
    if args.script:
        from vkpbr.app.script import load_script

        script = load_script(args.script)
    try:  # GLFW is the viewer's window system: a base dependency, but installs can lack it
        import glfw  # noqa: F401
    except ImportError:
        raise UsageError("the viewer needs the glfw package: pip install glfw (or install "
                         "vkpbr with scripts/setup.sh); `vkpbr render` needs no window") from None
    scene = load_scene_ahead(args)  # loaded on a thread while the window and device are made
    from vkpbr.app.viewer import Viewer, ViewerConfig

    config = ViewerConfig(
        size=size, options=options, vsync=not args.no_vsync, frames=args.frames,
        screenshot=shot, script=script, validation=args.validation, device=args.device,
        offscreen=args.offscreen,
        title=f"vkpbr - {Path(args.scene).name if args.scene else 'default scene'}",
        scene_label=args.scene or "",
        pose=lambda r: (camera_from_args(args, r), lights_from_args(args, r, options)))
    with Viewer(scene, config) as viewer:
        status = viewer.run()
        say(viewer.summary())
    return status
