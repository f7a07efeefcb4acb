"""What a living scene costs (issue 31's speed table): Python per pose call, the frame with
moving nodes against the still frame, skinning on the GPU. Prints one Markdown table.

    python3 benchmarks/bench_living.py --assets DIR [--frames 300] [--json out.json]

Rows:
  set_poses 10k         Python ms per Renderer.set_poses call of 10,000 nodes ((N,7) and
                        (N,4,4); and of 100 of them), and the frame's share (frame_copy_ms):
                        the state's update (world matrices, the changed draws' records,
                        boxes), the slot copy of the changed records and the bounds, median.
  instances 10k         add_instances of 10,000 instances of one mesh (the table's one growth:
                        the draw-dependent parts made again), then move_instances of all of
                        them per call: Python ms and the frame's share.
  sponza still/moving   Sponza 1920x1080 (and 640x480), the compute path as `vkpbr bench`
                        draws it, the sun's shadow maps, frames/s through render_many (three
                        in flight, no readback): still, and 100 of its nodes moved every frame
                        (every moved node a caster: the maps redraw each frame).
  2CylinderEngine       every node moved before each 256-view render_batch at 128x128:
                        views/s (the fps column) and Python ms per set_poses.
  crowdinst N           (not in the default set) the crowd through the API: N instances
                        of CesiumMan's skinned mesh (add_instances with time_offsets),
                        render_many(times=): the crowd rows' GPU and frame columns.
  crowdpy N             (not in the default set) the crowd rows' Python alone, no frame drawn:
                        python_ms as below, frame_copy_ms the state work of the frame;
                        the least of --frames calls.
  crowd N               N CesiumMan instances on a grid, each at its own animation time
                        (one vectorised sample a frame), 1920x1080 compute path: GPU ms per
                        frame, the deform step's ms (the kernel alone) and ms per million
                        skinned vertices, deform_wait_ms (the frame's start: its first step
                        waits for the previous frame, which drew from the same vertices),
                        Python ms per frame to pose them (python_ms: the vectorised sample and
                        setting the locals) and the frame's own Python (frame_python_ms:
                        the state's update, joint matrices, culling spheres, the copy).
"""

from __future__ import annotations

import argparse
import copy
import json
import statistics
import time
from pathlib import Path

import numpy as np

from vkpbr.render.renderer import Renderer
from vkpbr.scene.animation import sample
from vkpbr.scene.camera_batch import CameraBatch
from vkpbr.scene.loader import load_scene
from vkpbr.scene.synthetic import sphere_field
from vkpbr.scene.tree import NodeTree
from vkpbr.scene.types import Camera, Skin


def _median(xs: list[float]) -> float:
    return statistics.median(xs) if xs else float("nan")


def set_poses_rows(reps: int = 50) -> list[dict]:
    scene = sphere_field(10_000, rings=4, segments=8)
    rows = []
    with Renderer(scene) as r:
        n = len(r.state)
        idx = np.arange(n)
        rng = np.random.default_rng(0)
        pos7 = np.zeros((n, 7))
        pos7[:, :3], pos7[:, 6] = rng.random((n, 3)), 1.0
        mats = np.tile(np.eye(4), (n, 1, 1))
        mats[:, :3, 3] = rng.random((n, 3))
        some = idx[::100]  # 100 of the 10,000: the frame copies their rows only
        for label, nodes, poses in (("(N,7)", idx, pos7), ("(N,4,4)", idx, mats),
                                    ("(N,7), 100 of them", some, pos7[some])):
            ts, up = [], []
            for _ in range(reps):
                t0 = time.perf_counter()
                r.set_poses(nodes, poses)
                t1 = time.perf_counter()
                r.parts.gpu_state.write(0)  # the frame's share: its slot's copy, the bounds
                _ = r.parts.bounds.radius
                up.append(time.perf_counter() - t1)
                ts.append(t1 - t0)
            rows.append({"row": f"set_poses 10k {label}", "python_ms": 1e3 * _median(ts),
                         "frame_copy_ms": 1e3 * _median(up), "nodes": n})
    return rows


def instance_rows(reps: int = 50) -> list[dict]:
    """10,000 instances of one loaded mesh (add_instances: the one growth, python_ms), then
    moved every call (move_instances of (N,7) rows: Python per call, the frame's share)."""
    from vkpbr.scene.default import default_scene

    rows = []
    with Renderer(default_scene()) as r:
        rng = np.random.default_rng(0)
        pos7 = np.zeros((10_000, 7))
        pos7[:, :3], pos7[:, 6] = rng.random((10_000, 3)) * 4.0, 1.0
        t0 = time.perf_counter()
        ids = r.add_instances(0, pos7)
        r.parts.gpu_state.write(0)
        rows.append({"row": "add_instances 10k (the table grows once)",
                     "python_ms": 1e3 * (time.perf_counter() - t0)})
        ts, up = [], []
        for _ in range(reps):
            pos7[:, 1] += 0.01
            t0 = time.perf_counter()
            r.move_instances(ids, pos7)
            t1 = time.perf_counter()
            r.parts.gpu_state.write(0)
            _ = r.parts.bounds.radius
            up.append(time.perf_counter() - t1)
            ts.append(t1 - t0)
        rows.append({"row": "move_instances 10k (N,7)", "python_ms": 1e3 * _median(ts),
                     "frame_copy_ms": 1e3 * _median(up)})
    return rows


def moving_views(r: Renderer, cams: list, moving: np.ndarray, rest: np.ndarray):  # noqa: ANN201
    """`cams`, each after moving the `moving` nodes (a small bob each frame)."""
    for step, cam in enumerate(cams):
        m = rest.copy()
        m[:, 1, 3] += 0.01 * np.sin(step * 0.1 + np.arange(len(m)))
        r.set_poses(moving, m)
        yield cam


def crowd_views(r: Renderer, man, cam: Camera, offsets: np.ndarray, k: int, count: int,  # noqa: ANN001, ANN201
                frames: int, py: list, repeat: int = 1):
    """`cam` each frame, after posing every copy at its own time (one vectorised sample);
    with `repeat` N, each pose's frame followed by N - 1 frames of the same pose."""
    for f in range(frames):
        if f % repeat:
            yield cam
            continue
        t0 = time.perf_counter()
        pose = sample(man, offsets + f / 30.0)  # (count, k, 4, 4): one call
        roots = r.state.local[::k].copy()
        r.state.local[:] = pose.local.reshape(-1, 4, 4)
        r.state.local[::k] = roots  # each copy keeps its place on the grid
        r.state._changed(np.arange(0, count * k, k))
        py.append(time.perf_counter() - t0)
        yield cam


def walk_rows(assets: Path, frames: int) -> list[dict]:
    scene = load_scene(assets / "Sponza" / "glTF" / "Sponza.gltf")
    # The file has one node holding all 103 primitives: a node each, so that 100 can move.
    scene.tree = None
    for node in scene.nodes:
        node.tree = -1
    rows = []
    with Renderer(scene) as r:
        moving = np.arange(min(100, len(r.state)))
        rest = r.state.local[moving].copy()
        for size in ((1920, 1080), (640, 480)):
            for label in ("still", "100 moving"):
                cams = [r.default_camera()] * (frames + 30)
                views = moving_views(r, cams, moving, rest) if label != "still" else iter(cams)
                t0, gpu, py = 0.0, [], []
                for i, _ in enumerate(r.render_many(views, size=size, readback=False,
                                                    pipeline="compute", raster="compute")):
                    if i == 30:
                        t0 = time.perf_counter()
                    if i >= 30:
                        gpu.append(r.last_stats.gpu_ms)
                        py.append(r.last_stats.cpu_ms)
                fps = frames / (time.perf_counter() - t0)
                rows.append({"row": f"sponza {size[0]}x{size[1]} {label}", "fps": fps,
                             "gpu_ms": _median(gpu), "python_ms": _median(py),
                             "shadows_ms": r.last_stats.pass_ms.get("shadows", 0.0)})
                r.reset_pose()
    return rows


def engine_rows(assets: Path, calls: int) -> list[dict]:
    """2CylinderEngine, every one of its nodes moved before each 256-view render_batch
    (128x128): views/s and Python ms per pose update."""
    path = assets / "2CylinderEngine" / "glTF" / "2CylinderEngine.gltf"
    if not path.is_file():
        return []
    scene = load_scene(path)
    rows = []
    with Renderer(scene) as r:
        n = len(r.state)
        idx = np.arange(n)
        rest = r.state.local.copy()
        base = r.default_camera()
        angles = np.linspace(0, 2 * np.pi, 256, endpoint=False)
        eye = np.asarray(base.eye) - np.asarray(base.target)
        eyes = np.stack([np.asarray(base.target) + np.array(
            [eye[0] * np.cos(a) - eye[2] * np.sin(a), eye[1], eye[0] * np.sin(a) + eye[2] * np.cos(a)])
            for a in angles])
        cams = CameraBatch.from_look_at(eyes, np.tile(base.target, (256, 1)), yfov_deg=base.yfov_deg)
        py, t_all = [], []
        for call in range(calls + 3):
            t0 = time.perf_counter()
            m = rest.copy()
            m[:, :3, 3] += 0.002 * np.sin(call + np.arange(n))[:, None]
            r.set_poses(idx, m)
            t1 = time.perf_counter()
            r.render_batch(cams, size=(128, 128))
            if call >= 3:
                py.append(t1 - t0)
                t_all.append(time.perf_counter() - t0)
        rows.append({"row": f"2CylinderEngine {n} nodes moving, render_batch 256 x 128x128",
                     "python_ms": 1e3 * _median(py), "fps": 256 / _median(t_all)})
    return rows


def crowd(man, count: int) -> tuple:  # noqa: ANN001
    """`count` copies of CesiumMan's tree, skin and mesh nodes on a grid: (scene, the copies'
    root indices, nodes per copy)."""
    tree = man.node_tree()
    k = len(tree)
    side = int(np.ceil(np.sqrt(count)))
    parents = np.concatenate([np.where(tree.parents < 0, -1, tree.parents + c * k) for c in range(count)])
    local = np.tile(tree.local, (count, 1, 1))
    roots = np.flatnonzero(parents < 0)
    grid = np.stack([np.arange(count) % side, np.zeros(count), np.arange(count) // side], -1) * 1.5
    local[roots, :3, 3] += grid[np.arange(len(roots)) // max(len(roots) // count, 1)]
    rep = lambda a: np.tile(a, (count, 1))  # noqa: E731
    big = NodeTree([f"{n}#{c}" for c in range(count) for n in tree.names], parents, local,
                   rep(tree.translation), rep(tree.rotation), rep(tree.scale),
                   np.tile(tree.uses_matrix, count), np.arange(count * k))
    big.skin = {node + c * k: s + c * len(man.skins) for c in range(count) for node, s in tree.skin.items()}
    scene = copy.copy(man)
    scene.tree = big
    scene.skins = [Skin(s.name, s.joints + c * k, s.inverse_bind, None)
                   for c in range(count) for s in man.skins]
    scene.nodes = []
    for c in range(count):
        for node in man.nodes:
            n = copy.copy(node)
            n.tree = node.tree + c * k
            scene.nodes.append(n)
    scene.animations = []
    return scene, k


def _steps(passes: list[dict]) -> str:
    """Each timed step's median GPU ms over the frames, as 'name ms' pairs (where time goes)."""
    names = [n for n in (passes[0] if passes else {}) if _median([p.get(n, 0.0) for p in passes]) > 0.005]
    return " ".join(f"{n} {_median([p.get(n, 0.0) for p in passes]):.3f}" for n in names)


def crowd_rows(assets: Path, counts: tuple[int, ...], frames: int,
               size: tuple[int, int] = (1920, 1080), repeat: int = 1) -> list[dict]:
    """The crowd's frames, each after its poses (GPU ms of those frames alone); `repeat` N:
    each posed frame followed by N - 1 of the same pose, so that the GPU stays busy while
    Python poses the next (the H200 lowers its clocks when frames leave it idle: whether the
    GPU ms of a posed frame is that of a busy GPU)."""
    man = load_scene(assets / "CesiumMan" / "glTF" / "CesiumMan.gltf")
    verts = sum(man.meshes[n.mesh].vertex_count for n in man.nodes)
    rows = []
    for count in counts:
        scene, k = crowd(man, count)
        side = int(np.ceil(np.sqrt(count))) * 1.5
        cam = Camera(eye=(side / 2, side * 0.6, side * 1.3), target=(side / 2, 0.5, side / 2),
                     yfov_deg=50.0)
        offsets = np.random.default_rng(1).random(count) * 2.0
        with Renderer(scene) as r:
            py, gpu, deform, wait, frame_py, passes = [], [], [], [], [], []
            views = crowd_views(r, man, cam, offsets, k, count, (frames + 20) * repeat, py, repeat)
            for i, _ in enumerate(r.render_many(views, size=size, readback=False,
                                                pipeline="compute", raster="compute")):
                if i >= 20 * repeat and i % repeat == 0:
                    gpu.append(r.last_stats.gpu_ms)
                    frame_py.append(r.last_stats.cpu_ms)
                    deform.append(r.last_stats.pass_ms.get("deform", float("nan")))
                    wait.append(r.last_stats.pass_ms.get("deform_wait", float("nan")))
                    passes.append(dict(r.last_stats.pass_ms))
        mverts = count * verts / 1e6
        label = f"crowd {count} CesiumMan {size[0]}x{size[1]}" + (f", each pose x{repeat}" if repeat > 1 else "")
        rows.append({"row": label, "gpu_ms": _median(gpu),
                     "deform_ms": _median(deform), "deform_wait_ms": _median(wait),
                     "deform_ms_per_mvert": _median(deform) / mverts,
                     "python_ms": 1e3 * _median(py[20:]), "frame_python_ms": _median(frame_py),
                     "skinned_vertices": count * verts, "steps": _steps(passes)})
    return rows


def crowd_instance_rows(assets: Path, counts: tuple[int, ...], frames: int,
                        size: tuple[int, int] = (1920, 1080)) -> list[dict]:
    """The crowd through the API: N instances of CesiumMan's skinned mesh (add_instances with
    time_offsets: each its own skeleton, skin and posed vertices), played by render_many's
    times= (set_time poses every copy in one vectorised sample a frame)."""
    man = load_scene(assets / "CesiumMan" / "glTF" / "CesiumMan.gltf")
    verts = man.meshes[man.nodes[0].mesh].vertex_count
    rows = []
    for count in counts:
        side = int(np.ceil(np.sqrt(count)))
        place = np.tile(np.eye(4), (count, 1, 1))
        place[:, 0, 3], place[:, 2, 3] = np.arange(count) % side * 1.5, np.arange(count) // side * 1.5
        cam = Camera(eye=(side * 0.75, side * 0.9, side * 1.95), target=(side * 0.75, 0.5, side * 0.75),
                     yfov_deg=50.0)
        with Renderer(man) as r:
            r.set_visible(np.flatnonzero(r.state.tree.parents < 0)[:1], False)  # the file's own
            t0 = time.perf_counter()
            r.add_instances(man.nodes[0].mesh, place,
                            time_offsets=np.random.default_rng(1).random(count) * 2.0)
            add_s = time.perf_counter() - t0
            gpu, deform, wait, frame_py = [], [], [], []
            times = [f / 30.0 for f in range(frames + 20)]
            for i, _ in enumerate(r.render_many([cam] * len(times), size=size, times=times,
                                                readback=False, pipeline="compute", raster="compute")):
                if i >= 20:
                    gpu.append(r.last_stats.gpu_ms)
                    frame_py.append(r.last_stats.cpu_ms)
                    deform.append(r.last_stats.pass_ms.get("deform", float("nan")))
                    wait.append(r.last_stats.pass_ms.get("deform_wait", float("nan")))
        mverts = count * verts / 1e6
        rows.append({"row": f"crowd {count} CesiumMan instances {size[0]}x{size[1]} "
                            f"(add_instances {add_s:.2f} s)", "gpu_ms": _median(gpu),
                     "deform_ms": _median(deform), "deform_wait_ms": _median(wait),
                     "deform_ms_per_mvert": _median(deform) / mverts,
                     "frame_python_ms": _median(frame_py)})
    return rows


def crowd_python_rows(assets: Path, counts: tuple[int, ...], frames: int) -> list[dict]:
    """The crowd's Python alone, no frame drawn: the vectorised sample and setting the locals
    (python_ms), then the frame's state work (frame_copy_ms: world matrices, joint matrices,
    culling spheres, the draws' records, one frame slot's copy and the bounds); the least of
    `frames` calls each, in this thread's CPU time (time.thread_time: what
    other processes on a shared machine take is not counted)."""
    man = load_scene(assets / "CesiumMan" / "glTF" / "CesiumMan.gltf")
    rows = []
    for count in counts:
        scene, k = crowd(man, count)
        offsets = np.random.default_rng(1).random(count) * 2.0
        with Renderer(scene) as r:
            roots = np.arange(0, count * k, k)
            pose_s, frame_s = [], []
            for f in range(frames + 3):
                t0 = time.thread_time()
                pose = sample(man, offsets + f / 30.0)
                keep = r.state.local[roots].copy()
                r.state.local[:] = pose.local.reshape(-1, 4, 4)
                r.state.local[roots] = keep
                r.state._changed(roots)
                t1 = time.thread_time()
                r.parts.gpu_state.write(f % 3)
                _ = r.parts.bounds.radius
                pose_s.append(t1 - t0)
                frame_s.append(time.thread_time() - t1)
        rows.append({"row": f"crowd {count} CesiumMan, Python only (least of {frames})",
                     "python_ms": 1e3 * min(pose_s[3:]), "frame_copy_ms": 1e3 * min(frame_s[3:])})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--assets", type=Path, required=True)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--crowds", default="100,1000")
    ap.add_argument("--only", default="poses,instances,walk,engine,crowd")
    ap.add_argument("--size", default="1920x1080", help="the crowd rows' image size, WxH")
    ap.add_argument("--crowd-repeat", type=int, default=1,
                    help="the crowd row: each pose's frame drawn N times (the GPU kept busy)")
    ap.add_argument("--json")
    ap.add_argument("--shadow-steps", action="store_true",
                    help="time the compute shadow kernels apart (shadow_raster.TIMED_STEPS)")
    args = ap.parse_args()
    if args.shadow_steps:
        from vkpbr.render import shadow_raster

        shadow_raster.TIMED_STEPS = True
    rows: list[dict] = []
    if "poses" in args.only:
        rows += set_poses_rows()
    if "instances" in args.only:
        rows += instance_rows()
    if "walk" in args.only:
        rows += walk_rows(args.assets, args.frames)
    if "engine" in args.only:
        rows += engine_rows(args.assets, 20)
    if "crowd" in args.only.split(","):
        rows += crowd_rows(args.assets, tuple(int(c) for c in args.crowds.split(",")),
                           max(args.frames // 3, 30),
                           tuple(int(v) for v in args.size.split("x")),  # type: ignore[arg-type]
                           max(args.crowd_repeat, 1))
    if "crowdinst" in args.only:
        rows += crowd_instance_rows(args.assets, tuple(int(c) for c in args.crowds.split(",")),
                                    max(args.frames // 3, 30),
                                    tuple(int(v) for v in args.size.split("x")))  # type: ignore[arg-type]
    if "crowdpy" in args.only:
        rows += crowd_python_rows(args.assets, tuple(int(c) for c in args.crowds.split(",")),
                                  args.frames)
    keys = ("python_ms", "frame_copy_ms", "frame_python_ms", "fps", "gpu_ms", "shadows_ms",
            "deform_ms", "deform_ms_per_mvert", "deform_wait_ms")
    print("| row | " + " | ".join(keys) + " |\n|---|" + "---:|" * len(keys))
    for row in rows:
        cells = [f"{row[k]:.3f}" if isinstance(row.get(k), float) else "" for k in keys]
        print(f"| {row['row']} | " + " | ".join(cells) + " |")
    for row in rows:  # where the GPU time goes (the crowd rows)
        if row.get("steps"):
            print(f"| {row['row']} | GPU ms by step: {row['steps']} |")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
