"""Where the Python time of one render_batch step of worlds goes (issue 32, speed): the
phases of a warm call, in microseconds per call, with the GPU's waits apart.

    python benchmarks/profile_worlds_step.py [--variant primitives|tabletop|helmet|box]
        [--worlds 4096] [--size 16] [--steps 30] [--torch] [--pipeline auto]
        [--expand auto] [--prepared [--frames view]] [--bare] [--cprofile 20]

A step is what a simulator's loop does: new (W, N, 7) poses (position + quaternion x, y, z,
w; benchmarks/tabletop.py's motion, made before the clock starts), then
`render_batch(cams, size, worlds=poses)` of the same cameras, size and options, one view a
world. NumPy poses into NumPy frames by default; `--torch`: the poses are CUDA tensors and
the frames come back as torch tensors on the GPU (device="cuda"), as on the H200.
`--prepared`: the step made once with `renderer.batch_step(...)` and called with the poses.

Each phase is the time inside one function (wrapped here with time.perf_counter: nested
phases are indented and counted in their parents too). "GPU wait" rows are the host
waiting for the GPU (a fence: the step's own batch, or the last step's before its buffers
are rewritten); "readback" copies the frames out; "Python" is the call less those. The
number to compare is the last row: the calling thread's CPU time per step (time.thread_time,
less the readback's), its median over the steps; wall-clock rows count the time the thread
waited for a core too (on lavapipe the GPU's threads share the CPU). Keep the GPU part small
(--variant box, --size 8) on lavapipe; `--bare` leaves the other phases' timers out (their
own overhead, about 2 us a timed call, is then not in the CPU row). Not a test.
"""

from __future__ import annotations

import argparse
import cProfile
import importlib
import pstats
import statistics
import sys
import threading
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE / "peers"))

import tabletop  # noqa: E402  (NumPy only)

from vkpbr.render.renderer import Renderer  # noqa: E402
from vkpbr.scene.camera_batch import CameraBatch  # noqa: E402
from vkpbr.scene.loader import load_scene  # noqa: E402

# (depth, label, module, owner (a class name or "" for a module function), attribute). A
# missing one is left out of the table (the code moved): the script keeps working as the
# renderer changes.
PHASES: tuple[tuple[int, str, str, str, str], ...] = (
    (0, "render_batch (the whole call)", "vkpbr.render.renderer", "Renderer", "render_batch"),
    (1, "cached arguments (BatchCache.prepared)", "vkpbr.render.batch_cache", "BatchCache", "prepared"),
    (1, "cameras (as_camera_batch)", "vkpbr.render.batch_call", "", "as_camera_batch"),
    (1, "options", "vkpbr.render.batch_call", "", "_options"),
    (1, "route and checks (batch_route)", "vkpbr.render.batch_call", "", "batch_route"),
    (1, "worlds: checks and plan (_worlds_of)", "vkpbr.render.batch_call", "", "_worlds_of"),
    (2, "CUDA poses: checks (_cuda_call)", "vkpbr.render.batch_call", "", "_cuda_call"),
    (2, "NumPy poses: checks (WorldPoses.of)", "vkpbr.scene.worlds", "WorldPoses", "of"),
    (2, "NumPy poses: records (world_records)", "vkpbr.render.batch_call", "", "world_records"),
    (1, "batch path (BatchPath.run)", "vkpbr.render.batch_path", "BatchPath", "run"),
    (2, "last CUDA-ordered step's fence", "vkpbr.render.batch_path", "BatchPath", "_finish_pending"),
    (2, "replay key (replay_key)", "vkpbr.render.batch_path", "", "replay_key"),
    (2, "replayed step (batch_replay.replay; the plan unchanged)", "vkpbr.render.batch_path", "", "replay"),
    (2, "atlas / target lookup", "vkpbr.render.batch_path", "BatchPath", "_atlas"),
    (2, "post steps (batch_post)", "vkpbr.render.batch_path", "", "batch_post"),
    (2, "view buffers (_views)", "vkpbr.render.batch_path", "BatchPath", "_views"),
    (2, "frame setup (_begin)", "vkpbr.render.batch_path", "BatchPath", "_begin"),
    (3, "lights (frame_lights)", "vkpbr.render.lighting", "Lighting", "frame_lights"),
    (3, "environment (bind_for)", "vkpbr.render.environments", "Environments", "bind_for"),
    (3, "slot's fence (ring.begin: waits)", "vkpbr.gpu.frames", "FrameRing", "begin"),
    (3, "scene state copy (gpu_state.write)", "vkpbr.render.scene_state", "GpuSceneState", "write"),
    (3, "shadow plan (prepare)", "vkpbr.render.shadow_frames", "ShadowFrames", "prepare"),
    (3, "shadow blocks (write_scene)", "vkpbr.render.shadow_frames", "ShadowFrames", "write_scene"),
    (3, "frame blocks (write_frame_blocks)", "vkpbr.render.batch_path", "", "write_frame_blocks"),
    (3, "worlds' buffers (_write_worlds)", "vkpbr.render.batch_path", "BatchPath", "_write_worlds"),
    (4, "worlds kernel inputs (prepare)", "vkpbr.render.worlds", "WorldKernel", "prepare"),
    (5, "NumPy poses into inputs", "vkpbr.render.worlds", "WorldKernel", "write_numpy"),
    (5, "CUDA poses into inputs", "vkpbr.render.worlds", "WorldKernel", "write_cuda"),
    (4, "state + worlds' records (write)", "vkpbr.render.worlds", "WorldBuffers", "write"),
    (3, "view records (_view_records)", "vkpbr.render.batch_path", "BatchPath", "_view_records"),
    (2, "blended groups (write_blend_groups)", "vkpbr.render.batch", "BatchViews", "write_blend_groups"),
    (2, "record, submit, wait (_run)", "vkpbr.render.batch_path", "BatchPath", "_run"),
    (3, "shadow maps' staleness (stale)", "vkpbr.render.shadow_frames", "ShadowFrames", "stale"),
    (3, "commands (recorder.command_buffer)", "vkpbr.render.recorder", "FrameRecorder", "command_buffer"),
    (3, "submit (Frame.submit)", "vkpbr.gpu.frames", "Frame", "submit"),
    (3, "GPU wait: a fence (Frame.wait, all)", "vkpbr.gpu.frames", "Frame", "wait"),
    (3, "GPU timestamps (read_timings, when asked for)", "vkpbr.render.batch_replay", "", "read_timings"),
    (2, "readback: atlas tiles (read_tiles)", "vkpbr.gpu.target", "OffscreenTarget", "read_tiles"),
    (2, "readback: layers (read_color)", "vkpbr.gpu.batch_target", "BatchTarget", "read_color"),
    (2, "frames into torch (_cuda_tensor)", "vkpbr.render.batch_path", "BatchPath", "_cuda_tensor"),
    (2, "validation check", "vkpbr.gpu.device", "Device", "check_validation"),
    (1, "result (batch_result)", "vkpbr.render.batch_call", "", "batch_result"),
)
# Frame.wait is every fence wait (ring.begin's and the last CUDA-ordered step's too)
WAITS = ("GPU wait: a fence (Frame.wait, all)",)
READBACK = ("readback: atlas tiles (read_tiles)", "readback: layers (read_color)")
# The driver's own work in the calling thread (lavapipe's submit does work that NVIDIA's
# driver does not): the last row leaves it out too, the Python alone
DRIVER = ("submit (Frame.submit)", *WAITS)


# The sample models' variants: the first mesh node turns in each world (tabletop.Spin)
MODELS = {"helmet": "DamagedHelmet/glTF/DamagedHelmet.gltf",
          "box": "BoxAnimated/glTF/BoxAnimated.gltf"}


class Timers:
    """Wraps each phase's function with a timer: total seconds and calls per label, while
    `on`. A function calling itself (or a phase nested in itself) is counted once. `phases`:
    (depth, label, module, owner, attribute) rows (default: a worlds step's); `main_only`:
    calls on other threads are not counted."""

    def __init__(self, phases: tuple[tuple[int, str, str, str, str], ...] = PHASES,
                 main_only: bool = False) -> None:
        self.phases = phases
        self.main = threading.get_ident() if main_only else None
        self.total: dict[str, float] = {}
        self.cpu: dict[str, float] = {}  # the thread's CPU time (time.thread_time) inside
        self.calls: dict[str, int] = {}
        self.on = False
        self.found: list[tuple[int, str]] = []

    def install(self, only: tuple[str, ...] | None = None) -> None:
        """Wrap every phase's function (`only`: just those labels)."""
        for depth, label, module, owner, attr in self.phases:
            if only is not None and label not in only:
                continue
            try:
                mod = importlib.import_module(module)
            except ImportError:
                continue
            holder = getattr(mod, owner, None) if owner else mod
            fn = getattr(holder, attr, None) if holder is not None else None
            if fn is None:
                continue
            raw = holder.__dict__.get(attr) if isinstance(holder, type) else None
            if isinstance(raw, (staticmethod, classmethod)):  # (kept what it is)
                setattr(holder, attr, type(raw)(self._wrap(raw.__func__, label)))
            else:
                setattr(holder, attr, self._wrap(fn, label))
            self.found.append((depth, label))

    def _wrap(self, fn: Callable[..., Any], label: str) -> Callable[..., Any]:
        inside = [0]

        def timed(*args: Any, **kwargs: Any) -> Any:
            if not self.on or inside[0] or (self.main is not None
                                            and threading.get_ident() != self.main):
                return fn(*args, **kwargs)
            inside[0] += 1
            t, c = time.perf_counter(), time.thread_time()
            try:
                return fn(*args, **kwargs)
            finally:
                self.total[label] = self.total.get(label, 0.0) + time.perf_counter() - t
                self.cpu[label] = self.cpu.get(label, 0.0) + time.thread_time() - c
                self.calls[label] = self.calls.get(label, 0) + 1
                inside[0] -= 1

        timed.__wrapped__ = fn  # type: ignore[attr-defined]
        return timed



def scene_and_poses(variant: str, worlds: int, steps: int):  # noqa: ANN201
    """(scene, slot names, camera pose (4, 4), yfov, (S, W, N, 7) float32 NumPy poses,
    space) of the variant (benchmarks/bench_worlds.py's worlds)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if variant in MODELS:
            scene = load_scene(tabletop.assets_dir() / MODELS[variant])
            tree = scene.node_tree()
            slots = [n.tree for n in scene.nodes if n.mesh is not None][:1]
            m = tree.local[slots[0]]
            rest = np.array([[*m[:3, 3], *tabletop.matrix_quat(m[:3, :3])]])
            eye = tabletop.look_at((0.0, 0.0, 3.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
            return scene, slots, eye, 45.0, tabletop.Spin(rest, worlds).steps(steps, "xyzw"), "local"
        world = tabletop.make_tabletop(models=tuple(tabletop.MODELS) if variant == "tabletop" else ())
        import tempfile

        folder = Path(tempfile.mkdtemp(prefix="tabletop-"))
        scene = load_scene(tabletop.write_gltf(world, folder))
        poses = tabletop.Motion(world, worlds).steps(steps, "xyzw")
        return scene, list(tabletop.MOVING), tabletop.camera_gltf(world), world.yfov_deg, poses, "local"


def parse() -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--variant", choices=("primitives", "tabletop", *MODELS),
                    help="the tabletop worlds (bench_worlds.py), DamagedHelmet, or BoxAnimated (a "
                    "few triangles: the GPU part smallest, for lavapipe)", default="primitives")
    ap.add_argument("--worlds", type=int, default=4096)
    ap.add_argument("--size", type=int, default=16, help="views of SIZE x SIZE")
    ap.add_argument("--steps", type=int, default=30, help="timed steps (after 3 warm ones)")
    ap.add_argument("--torch", action="store_true",
                    help="poses as CUDA tensors, frames into torch (device='cuda')")
    ap.add_argument("--pipeline", default="auto", help="auto, forward (layered) or compute")
    ap.add_argument("--expand", default="auto", help="world_expand for NumPy poses")
    ap.add_argument("--prepared", action="store_true",
                    help="renderer.batch_step(...) made once, called with each step's poses")
    ap.add_argument("--frames", choices=("copy", "view"), default="copy",
                    help="with --prepared --torch: batch_step(frames=...): 'view' hands the "
                    "frames without a clone (docs/batch.md)")
    ap.add_argument("--shadows", action="store_true", help="keep shadows on (off by default, "
                    "as bench_worlds.py: the worlds share the state's shadow maps)")
    ap.add_argument("--in-place", action="store_true",
                    help="with --torch --prepared: each step's poses written into the renderer's "
                         "input (batch_step.worlds_input), read with no copy")
    ap.add_argument("--bare", action="store_true",
                    help="time only the waits and the readback (the CPU row without the other "
                    "phases' timer overhead: the number to compare)")
    ap.add_argument("--cprofile", type=int, default=0,
                    help="also print cProfile's top N functions (own time) over the steps")
    return ap.parse_args()


def main() -> None:
    args = parse()
    torch = None
    if args.in_place and not (args.torch and args.prepared):
        raise SystemExit("--in-place is for --torch --prepared (batch_step's CUDA input)")
    if args.torch:
        try:
            import torch
        except ImportError:
            raise SystemExit("--torch: torch is not importable") from None
        if not torch.cuda.is_available():
            raise SystemExit("--torch: torch sees no CUDA device (run without --torch here)")
    scene, slots, eye, yfov, poses, space = scene_and_poses(args.variant, args.worlds, args.steps + 3)
    if torch is not None:
        poses = torch.as_tensor(poses, device="cuda")
    size = (args.size, args.size)
    timers = Timers()
    timers.install((*DRIVER, *READBACK) if args.bare else None)
    with Renderer(scene) as r:
        r.world_slots(slots)
        cams = CameraBatch.from_poses(np.repeat(eye[None], args.worlds, 0), yfov)
        kw = dict(pipeline=args.pipeline, shadows=args.shadows)
        if torch is not None:
            kw["device"] = "cuda"
        else:
            kw["world_expand"] = args.expand
        common = dict(quaternion="xyzw", space=space)
        if args.prepared:
            if args.frames == "view":
                kw["frames"] = "view"
            step = r.batch_step(cams, size, **common, **kw)  # type: ignore[attr-defined]
            call = lambda p: step(worlds=p)  # noqa: E731
        else:
            call = lambda p: r.render_batch(cams, size, worlds=p, **common, **kw)  # noqa: E731
        sync = torch.cuda.synchronize if torch is not None else (lambda: None)
        for s in range(3):  # warm: targets, recordings, imports
            call(poses[s])
        sync()
        # --in-place: the simulator writes each step's poses into the renderer's own input
        # (batch_step.worlds_input(); its write is the simulator's work, outside the step's
        # time as the precomputed poses' making is), and the step reads them with no copy
        given = step.worlds_input() if args.in_place else None
        prof = cProfile.Profile() if args.cprofile else None
        walls: list[float] = []
        python: list[float] = []  # each step's Python: its time less waits and readback
        cpu: list[float] = []  # each step's CPU time (the thread's) less the readback's
        own: list[float] = []  # and less the driver's (submit, fence waits)
        stats_cpu: list[float] = []  # last_stats.cpu_ms (bench_world_batches' "Python ms")
        timers.on = True
        for s in range(3, 3 + args.steps):
            before, before_cpu = dict(timers.total), dict(timers.cpu)
            if given is not None:
                given.copy_(poses[s])
            if prof is not None:
                prof.enable()
            t, c = time.perf_counter(), time.thread_time()
            call(poses[s] if given is None else given)
            walls.append(time.perf_counter() - t)
            cpu.append(time.thread_time() - c)
            stats_cpu.append(r.last_stats.cpu_ms / 1e3)
            if prof is not None:
                prof.disable()
            sync()  # (outside the step's time: the loop's next step waits anyway)
            spent = {k: v - before.get(k, 0.0) for k, v in timers.total.items()}
            python.append(walls[-1] - sum(spent.get(k, 0.0) for k in (*WAITS, *READBACK)))
            cpu[-1] -= sum(timers.cpu.get(k, 0.0) - before_cpu.get(k, 0.0) for k in READBACK)
            own.append(cpu[-1] - sum(timers.cpu.get(k, 0.0) - before_cpu.get(k, 0.0)
                                     for k in DRIVER))
        timers.on = False
        report(args, r, timers, walls, python, cpu, own, stats_cpu)
        if args.prepared:
            print(f"| steps by batch_step's short way (BatchStep.lane_steps) | "
                  f"{getattr(step, 'lane_steps', 'n/a')} of {args.steps + 3} | | |")
    if prof is not None:
        print(f"\ncProfile over the {args.steps} timed steps (its overhead inflates the times):")
        pstats.Stats(prof).sort_stats("tottime").print_stats(args.cprofile)


def report(args: argparse.Namespace, r: Renderer, timers: Timers, walls: list[float],
           python: list[float], cpu: list[float], own: list[float], stats_cpu: list[float]
           ) -> None:
    n = len(walls)
    us = {k: 1e6 * v / n for k, v in timers.total.items()}
    mode = "CUDA poses -> torch" if args.torch else f"NumPy poses -> NumPy (world_expand={args.expand})"
    print(f"## {args.variant}, W={args.worlds}, {args.size}x{args.size}, {mode}, "
          f"pipeline={args.pipeline}{', prepared step' if args.prepared else ''}"
          f"{', frames=view' if args.frames == 'view' else ''}"
          f"{', poses in place' if args.in_place else ''}, "
          f"{r.device.info.name}, {n} steps")
    print("| phase | us per call | CPU us per call | calls per step |")
    print("|---|---:|---:|---:|")
    for depth, label in timers.found:
        if label in us:
            print(f"| {'&nbsp;' * 4 * depth}{label} | {us[label]:.1f} | "
                  f"{1e6 * timers.cpu[label] / n:.1f} | {timers.calls[label] / n:g} |")
    call = us.get("render_batch (the whole call)", 1e6 * statistics.fmean(walls))
    waits = sum(us.get(k, 0.0) for k in WAITS)
    read = sum(us.get(k, 0.0) for k in READBACK)
    print(f"| Python (the call less GPU waits and readback), mean | {call - waits - read:.1f} | | |")
    print(f"| Python per step, median (min {1e6 * min(python):.1f}) | "
          f"{1e6 * statistics.median(python):.1f} | | |")
    print(f"| **Python per step: the thread's CPU time less the readback's, median** (min "
          f"{1e6 * min(cpu):.1f}) | | **{1e6 * statistics.median(cpu):.1f}** | |")
    print(f"| **... and less the driver's (Frame.submit, fence waits): Python alone, median** "
          f"(min {1e6 * min(own):.1f}) | | **{1e6 * statistics.median(own):.1f}** | |")
    print(f"| last_stats.cpu_ms: the batch path's Python up to its submission, median | "
          f"{1e6 * statistics.median(stats_cpu):.1f} | | |")
    print(f"| step wall clock, median (the timers' overhead in) | "
          f"{1e6 * statistics.median(walls):.1f} | | |")
    print(f"| GPU time of the last step (last_stats.gpu_ms) | {1e3 * r.last_stats.gpu_ms:.1f} | | |")
    replays = getattr(getattr(r, "batch_path", None), "replays", None)
    if replays is not None:  # (render/batch_replay.py: the warm steps' replays included)
        print(f"| steps replayed (the plan unchanged: render/batch_replay.py) | "
              f"{replays.replayed} of {n + 3} | | |")


if __name__ == "__main__":
    main()
