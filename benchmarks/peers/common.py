"""The scenario every peer benchmark renders (issue 6), and the timing and reporting they share.

Sponza, camera eye (9, 1.8, -0.4) looking at (-9, 3.5, -0.4) with +Y up and a 45 degree vertical
field of view, one white point light at (0, 4, 0). Per scenario: 20 warm-up frames, then N timed
frames, wall clock per frame, medians:

- ms_readback: render and read the frame back into a NumPy array (what a user gets);
- ms_render_only: the same draw with the GPU waited for, but no readback;
- load_s: from parsing the glTF to the first frame in NumPy (parse, upload, shader compilation).
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests"))
from assets_path import ASSETS  # noqa: E402  ($VKPBR_ASSETS, .assets/models or ../shared/assets)

SCENES = (ASSETS / "Sponza/glTF/Sponza.gltf",)
EYE = (9.0, 1.8, -0.4)
TARGET = (-9.0, 3.5, -0.4)
UP = (0.0, 1.0, 0.0)
YFOV_DEG = 45.0
ZNEAR, ZFAR = 0.1, 100.0
LIGHT_POS = (0.0, 4.0, 0.0)
LIGHT_COLOR = (1.0, 1.0, 1.0)
LIGHT_CANDELA = 40.0  # for peers whose point light has inverse-square falloff (pyrender)
SIZES = ("1920x1080", "640x480")
WARMUP = 20


def parse_args(peer: str, extra: Callable[[argparse.ArgumentParser], object] | None = None
               ) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=f"Sponza with {peer}: render + readback vs render only")
    ap.add_argument("--scene", default=None, help="glTF path (default: Sponza in the sample-models folder, "
                    "tests/assets_path.py)")
    ap.add_argument("--size", default=SIZES[0], help="WIDTHxHEIGHT (default 1920x1080)")
    ap.add_argument("--frames", type=int, default=200, help="timed frames per measurement")
    ap.add_argument("--warmup", type=int, default=WARMUP)
    ap.add_argument("--json", default=None, help="append the result as one JSON line to this file")
    ap.add_argument("--png", default=None, help="save the last read-back frame (needs Pillow)")
    if extra:
        extra(ap)
    args = ap.parse_args()
    args.width, args.height = (int(v) for v in args.size.lower().split("x"))
    args.scene = scene_path(args.scene)
    return args


def scene_path(arg: str | None) -> Path:
    if arg:
        return Path(arg)
    for p in SCENES:
        if p.exists():
            return p
    raise SystemExit(f"Sponza not found: tried {', '.join(map(str, SCENES))}; pass --scene")


def look_at(eye=EYE, target=TARGET, up=UP) -> np.ndarray:
    """Camera-to-world 4x4 (OpenGL convention: the camera looks down its -Z, +Y is up)."""
    eye, target, up = (np.asarray(v, dtype=np.float64) for v in (eye, target, up))
    z = eye - target
    z /= np.linalg.norm(z)
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, np.cross(z, x), z, eye
    return m


def median_ms(frame: Callable[[], object], frames: int, warmup: int = WARMUP) -> float:
    """Median wall-clock milliseconds of frame() over `frames` calls after `warmup` calls."""
    for _ in range(warmup):
        frame()
    times = []
    for _ in range(frames):
        t = time.perf_counter()
        frame()
        times.append((time.perf_counter() - t) * 1e3)
    return statistics.median(times)


def report(args: argparse.Namespace, peer: str, version: str, ms_readback: float,
           ms_render_only: float, load_s: float, gpu: str | None, settings: str = "",
           image: np.ndarray | None = None) -> dict:
    """Print one Markdown table row, append the JSON line to --json, save --png."""
    row = {"peer": peer, "version": version, "size": f"{args.width}x{args.height}",
           "fps_readback": round(1e3 / ms_readback, 2), "ms_readback": round(ms_readback, 3),
           "ms_render_only": round(ms_render_only, 3), "load_s": round(load_s, 3), "gpu": gpu,
           "frames": args.frames, "settings": settings}
    print(f"| {peer} {version} | {row['size']} | {ms_readback:.1f} ms ({row['fps_readback']:.0f} fps)"
          f" | {ms_render_only:.1f} ms | {load_s:.1f} s | {gpu} |", flush=True)
    if args.json:
        with open(args.json, "a") as f:
            f.write(json.dumps(row) + "\n")
    if args.png and image is not None:
        from PIL import Image

        Image.fromarray(np.ascontiguousarray(image[..., :3])).save(args.png)
    return row


def vfov_to_mean_fov(yfov_deg: float, aspect: float) -> float:
    """pygfx's `fov` spans the mean of the view's width and height, not its height: the fov
    that gives a vertical field of view of yfov_deg at this aspect (width / height)."""
    return math.degrees(2 * math.atan(math.tan(math.radians(yfov_deg) / 2) * (1 + aspect) / 2))
