"""The scenario every peer benchmark renders (issue 6), and the timing and reporting they share.

Sponza, camera eye (9, 1.8, -0.4) looking at (-9, 3.5, -0.4) with +Y up and a 45 degree vertical
field of view, one white point light at (0, 4, 0). Per scenario: 20 warm-up frames, then N timed
frames, wall clock per frame, medians:

- ms_readback: render and read the frame back into a NumPy array (what a user gets);
- ms_render_only: the same draw with the GPU waited for, but no readback;
- load_s: from parsing the glTF to the first frame in NumPy (parse, upload, shader compilation).

The batch scenario (issue 14, `--batch`): B views of one scene at one small size (128x128 or
512x512), the same B camera poses for every peer: a seeded orbit generated once by
`batch_poses` and written to a (B, 4, 4) float64 `.npy` of OpenGL world-from-camera poses
(`--poses FILE`: read when it exists, else generated and written), so that every peer renders
identical views. Two scenes: Sponza (an orbit inside the atrium) and DamagedHelmet (one
textured object, an orbit around it). Timed: `--reps` passes over the B poses after one
warm-up pass, views/s = views / wall clock, into NumPy and render only.
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

# The batch scenario's scenes (key -> path in the sample-models folder) and sizes.
BATCH_SCENES = {"sponza": "Sponza/glTF/Sponza.gltf", "helmet": "DamagedHelmet/glTF/DamagedHelmet.gltf"}
BATCH_SIZES = ("128x128", "512x512")
BATCH_VIEWS = 256
BATCH_SEED = 14


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


def batch_scene_path(key: str) -> Path:
    """The glTF of a batch scene key ("sponza", "helmet"), or a path given as is."""
    path = ASSETS / BATCH_SCENES[key] if key in BATCH_SCENES else Path(key)
    if not path.exists():
        raise SystemExit(f"batch scene {key!r} not found: {path}")
    return path


def batch_poses(key: str, count: int = BATCH_VIEWS, seed: int = BATCH_SEED) -> np.ndarray:
    """(count, 4, 4) float64 OpenGL world-from-camera poses: a seeded orbit about the scene.

    Sponza ("sponza"): eyes on an ellipse inside the atrium (semi-axes 8 m along x, 3 m along
    z; 1.5 to 5 m high), each looking at a point near the courtyard's centre. DamagedHelmet
    ("helmet", unit-sized at the origin): eyes 2.5 to 3.5 units away at elevations -30 to 45
    degrees, looking at the origin. The angle steps evenly round the ring; radius, height and
    target are jittered by a NumPy Generator seeded with `seed`, so the poses are the same
    everywhere (NumPy's PCG64 stream is stable across versions).
    """
    rng = np.random.default_rng(seed)
    a = 2 * np.pi * (np.arange(count) + rng.uniform(0, 1, count)) / count
    if key == "sponza":
        eye = np.stack([8.0 * np.cos(a), rng.uniform(1.5, 5.0, count), 3.0 * np.sin(a)], 1)
        target = np.stack([rng.uniform(-1, 1, count), rng.uniform(2.0, 4.0, count),
                           rng.uniform(-0.5, 0.5, count)], 1)
    elif key == "helmet":
        r = rng.uniform(2.5, 3.5, count)
        el = np.radians(rng.uniform(-30, 45, count))
        eye = np.stack([r * np.cos(el) * np.cos(a), r * np.sin(el), r * np.cos(el) * np.sin(a)], 1)
        target = np.zeros((count, 3))
    else:
        raise SystemExit(f"no orbit for batch scene {key!r}: choose from {', '.join(BATCH_SCENES)}")
    return np.stack([look_at(e, t) for e, t in zip(eye, target, strict=True)])


def load_poses(path: str | Path | None, key: str, count: int = BATCH_VIEWS) -> np.ndarray:
    """The poses of `path` (.npy, (B, 4, 4)) when it exists, else `batch_poses(key, count)`,
    written to `path` when one is given (so that the next peer reads the same file)."""
    if path is not None and Path(path).exists():
        poses = np.load(path)
        if poses.ndim != 3 or poses.shape[1:] != (4, 4):
            raise SystemExit(f"{path}: expected (B, 4, 4) poses, got {poses.shape}")
        return poses
    poses = batch_poses(key, count)
    if path is not None:
        np.save(path, poses)
    return poses


def poses_digest(poses: np.ndarray) -> str:
    """SHA-1 of the poses as little-endian float64: rows measured apart (another run, another
    machine) are compared only when they rendered the same views."""
    import hashlib

    return hashlib.sha1(np.ascontiguousarray(poses, dtype="<f8").tobytes()).hexdigest()


def parse_batch_args(peer: str, extra: Callable[[argparse.ArgumentParser], object] | None = None
                     ) -> argparse.Namespace:
    """Arguments of a peer's batch scenario (--batch): scene key, size, poses, passes."""
    ap = argparse.ArgumentParser(description=f"the batch scenario with {peer}: B views/s")
    ap.add_argument("--batch", action="store_true", help="the batch scenario (this parser)")
    ap.add_argument("--scene", default="sponza", help=f"{' or '.join(BATCH_SCENES)} or a glTF path")
    ap.add_argument("--size", default=BATCH_SIZES[0], help="WIDTHxHEIGHT (default 128x128)")
    ap.add_argument("--views", type=int, default=BATCH_VIEWS, help="B when poses are generated")
    ap.add_argument("--poses", default=None, help="(B, 4, 4) .npy: read if it exists, else written")
    ap.add_argument("--reps", type=int, default=2, help="timed passes over the B views")
    ap.add_argument("--json", default=None, help="append the result as one JSON line to this file")
    ap.add_argument("--png", default=None, help="save view 0 (needs Pillow)")
    if extra:
        extra(ap)
    args = ap.parse_args()
    args.width, args.height = (int(v) for v in args.size.lower().split("x"))
    args.scene_key = args.scene if args.scene in BATCH_SCENES else Path(args.scene).stem.lower()
    args.scene_path = batch_scene_path(args.scene)
    args.pose_array = load_poses(args.poses, args.scene, args.views)
    return args


def views_per_s(pass_: Callable[[], object], views: int, reps: int) -> float:
    """Views per second of pass_() (which renders `views` views) over `reps` timed calls,
    after one untimed call (warm-up: pipelines, caches)."""
    pass_()
    t = time.perf_counter()
    for _ in range(reps):
        pass_()
    return views * reps / (time.perf_counter() - t)


def report_batch(args: argparse.Namespace, peer: str, version: str, vps_readback: float,
                 vps_render_only: float, load_s: float, gpu: str | None, settings: str = "",
                 mode: str = "per-view loop", pixel_scale: float = 1.0,
                 image: np.ndarray | None = None) -> dict:
    """One Markdown row and JSON line of the batch scenario; --png saves view 0."""
    row = {"scenario": "batch", "peer": peer, "version": version, "scene": args.scene_key,
           "size": f"{args.width}x{args.height}", "views": len(args.pose_array), "reps": args.reps,
           "poses_sha1": poses_digest(args.pose_array),
           "views_per_s_readback": round(vps_readback, 2),
           "views_per_s_render_only": round(vps_render_only, 2), "mode": mode,
           "pixel_scale": pixel_scale, "load_s": round(load_s, 3), "gpu": gpu, "settings": settings}
    label = peer if pixel_scale == 1 else f"{peer} (pixel_scale {pixel_scale:g})"
    print(f"| {label} {version} | {args.scene_key} | {row['size']} | {row['views']} | {vps_readback:,.0f} "
          f"| {vps_render_only:,.0f} | {mode} | {load_s:.1f} s | {gpu} |", flush=True)
    if args.json:
        with open(args.json, "a") as f:
            f.write(json.dumps(row) + "\n")
    if args.png and image is not None:
        from PIL import Image

        Image.fromarray(np.ascontiguousarray(np.asarray(image)[..., :3])).save(args.png)
    return row


def main() -> None:
    """`python common.py --write-poses FILE --scene KEY [--views B]`: write the batch poses."""
    ap = argparse.ArgumentParser(description="write the batch scenario's poses (.npy)")
    ap.add_argument("--write-poses", required=True, metavar="FILE")
    ap.add_argument("--scene", default="sponza", choices=list(BATCH_SCENES))
    ap.add_argument("--views", type=int, default=BATCH_VIEWS)
    args = ap.parse_args()
    np.save(args.write_poses, batch_poses(args.scene, args.views))
    print(f"{args.write_poses}: {args.views} poses of {args.scene}")


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


if __name__ == "__main__":
    main()
