"""Load time and many-scene jobs (issue 32, must-have 7): where a scene's file-to-first-frame
time goes, cold and with each cache warm, and a job of many different scenes against one
scene rendered in-process.

    python benchmarks/bench_load.py [--scene SPONZA.gltf] [--size 1280x720]
                                    [--models DIR] [--scenes 100] [--views 16] [--job-size 256x256]
                                    [--no-job] [--no-load] [--ray] [--profile DIR] [--serial]
                                    [--json OUT.json]

Part 1, one scene (default: the sample models' Sponza), each row a fresh process with its own
cache folder ($VKPBR_CACHE_DIR) in this order:
  cold                  nothing cached: the glTF parsed, pipelines compiled, the BRDF table
                        made; auto takes the rule (it measures only after 10 s of frames)
  warm pipelines        the same folder again: the pipeline cache and frame-path record read
  bake (first)          through the bake cache (`--cache`), which bakes now
  warm bake + pipelines through the bake cache again: everything warm
  warm bake only        the pipeline cache and frame-path record removed first
The scene is loaded on a thread while the Renderer makes its device (vkpbr.bake.ahead: the
bake cache's look-up, the parse or the baked file's read, the images' decode), or with
`--serial` first (as before). Columns: the scene's load (parse or bake-cache read; loaded
ahead: only the wait for it after the device was made), the Renderer's set-up split into the
device, the scene's upload (geometry, textures: decode + upload + mips) and the rest of its
GPU objects, auto's path choice (a measurement when nothing is recorded), the first frame's
render call (of which the environment's pre-filter, made first here), the pipelines built in the process (the driver's reported cache hits) and their
seconds, and file-to-first-frame (load + set-up + choice + first frame; Python's import of
vkpbr is the separate "import" column), and file to first frame again in the same process on
the same Renderer (`set_scene`: the device and its pipelines kept, as a job's next scene).

Part 2, a job (docs/batch.md, "Many scenes"): `--scenes` entries cycling over the sample
models under `--models` (every */glTF/*.gltf; consecutive entries are different scenes, so
every item changes scene), `--views` orbit views each at `--job-size`, PNG files written:
  one scene in-process  each model's views rendered by a warm actor (no loads): the job's
                        views over the sum of its entries' times at their model's rate
  in-process job        `vkpbr batch --in-process`: one renderer, set_scene per change, the next
                        scene loaded on a thread (cold bake cache, then warm)
  no load ahead         the same actor without hints (every scene loaded when needed)
  Ray, 1 actor          `vkpbr batch` (with --ray): the render span, Ray's start excluded
Prints Markdown tables. Not a test: asserts nothing but that the jobs succeed.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))
sys.path.insert(0, str(REPO / "benchmarks"))
from assets_path import ASSETS  # noqa: E402

ROWS = (("cold", False, ()), ("warm pipelines", False, ()), ("bake (first)", True, ()),
        ("warm bake + pipelines", True, ()),
        ("warm bake only", True, ("pipelines-*.bin", "frame-paths.json")))


# --- part 1: one scene, a child process per row ---------------------------------------------
def child(scene: str, size: tuple[int, int], cached: bool, serial: bool = False) -> dict:
    """Runs in the child: load, set up, choose the path, first frame; the phases' seconds.
    The scene loads on a thread while the device is made (vkpbr.bake.ahead), unless `serial`
    (load, then device): "load" is then the part of the load the device did not hide."""
    t0 = time.perf_counter()
    from vkpbr.config import default_cache_dir
    from vkpbr.render.options import RenderOptions
    from vkpbr.render.renderer import Renderer
    from vkpbr.render.scene_swap import pipeline_timings
    from vkpbr.scene.loader import load_scene

    t_import = time.perf_counter()
    cache = default_cache_dir() if cached else None
    if serial:
        path, root = Path(scene), None
        if cached:
            from vkpbr.bake.bake import cached_bake

            root, path = path.parent, cached_bake(path, cache)
        loaded = load_scene(path, root=root)
    else:
        from vkpbr.bake.ahead import load_ahead

        loaded = load_ahead(scene, cache)
    t_load = time.perf_counter()
    renderer = Renderer(loaded, cache_dir=default_cache_dir())
    t_setup = time.perf_counter()
    renderer.choose_paths(renderer.offscreen_target(size, False), RenderOptions())
    t_choice = time.perf_counter()
    renderer.environments.get(RenderOptions())  # the sky's pre-filter: the first frame's own
    t_env = time.perf_counter()
    renderer.render(size=size)
    t_first = time.perf_counter()
    timings = dict(renderer.timings)
    wait = timings.pop("load_wait", 0.0)
    out = {"import": t_import - t0, "load": t_load - t_import + wait, **timings,
           "choice": t_choice - t_setup, "first_frame": t_first - t_choice,
           "environment": t_env - t_choice,
           **pipeline_timings(renderer.device), "total": t_first - t_import,
           "decode_wait": getattr(renderer.gpu_scene, "decode_wait", float("nan")),
           "bytecode": _bytecode(),
           "path": renderer.paths.choice.label if renderer.paths.choice else "rule",
           "device_name": renderer.device.info.name,
           "device_parts": getattr(renderer.device, "timings", {}),
           "upload_parts": getattr(renderer.gpu_scene, "upload_stats", {}),
           "builds": _builds(renderer.device, t0),
           "marks": {"load": t_load - t0, "set-up": t_setup - t0, "choice": t_choice - t0,
                     "environment": t_env - t0, "first frame": t_first - t0},
           "again": _again(renderer, scene, size, cache, serial)}
    renderer.close()
    return out


def _builds(device: object, t0: float) -> list[tuple[str, float, float, bool]]:
    """The device's pipeline builds so far: (shaders, start from `t0`, seconds, cache hit)."""
    cache = getattr(device, "pipeline_cache", None)
    return [(n, t - t0, s, h) for n, t, s, h, _ in (cache.stats.builds if cache else [])]


def print_builds(rows: list[dict]) -> None:
    """Each row's pipeline builds, in order, with the phase each began in."""
    for r in rows:
        marks = sorted(r["marks"].items(), key=lambda kv: kv[1])
        print(f"\n#### {r['row']}: {len(r['builds'])} pipeline builds, "
              + ", ".join(f"{k} done at {v:.3f} s" for k, v in marks) + "\n")
        print("| shaders | began, s | ms | hit | phase |")
        print("|---|---:|---:|---|---|")
        for name, start, sec, hit in r["builds"]:
            phase = next((k for k, v in marks if start < v), "after")
            print(f"| {name} | {start:.3f} | {1000 * sec:.1f} | {'yes' if hit else ''} | {phase} |")


def _again(renderer: object, scene: str, size: tuple[int, int], cache: Path | None,
           serial: bool) -> float:
    """File to first frame once more on the same Renderer (`set_scene`: the device, its
    pipelines and the driver kept), as a job's next scene pays it: the scene read again (the
    bake cache's file when `cache`), uploaded, its first frame rendered."""
    from vkpbr.bake.ahead import load_ahead
    from vkpbr.scene.loader import load_scene

    t = time.perf_counter()
    if serial:
        path, root = Path(scene), None
        if cache is not None:
            from vkpbr.bake.bake import cached_bake

            root, path = path.parent, cached_bake(path, cache)
        renderer.set_scene(load_scene(path, root=root))
    else:
        renderer.set_scene(load_ahead(scene, cache))
    renderer.render(size=size)
    return time.perf_counter() - t


def _bytecode() -> str:
    """Whether this process's modules came from cached bytecode (vkpbr's and the vulkan
    binding's 1 MB of source compiled on every start cost 0.2-0.5 s: import and device)."""
    import vulkan

    mods = (vulkan._vulkan, sys.modules["vkpbr.render.renderer"])
    cached = [bool(m.__cached__) and Path(m.__cached__).is_file() for m in mods]
    return ("not written (PYTHONDONTWRITEBYTECODE)" if sys.dont_write_bytecode and not all(cached)
            else "cached" if cached and all(cached) else "compiled")


def load_table(scene: Path, size: tuple[int, int], profile: Path | None,
               serial: bool = False, rows_wanted: list[str] | None = None,
               fresh_driver_cache: bool = False) -> list[dict]:
    """The rows of ROWS (those named in `rows_wanted`, in ROWS' order, each as often as
    named), each a child process; `fresh_driver_cache`: each child with an empty NVIDIA
    shader disk cache of its own (a cold row as on a fresh machine, every time)."""
    cache = Path(tempfile.mkdtemp(prefix="vkpbr-bench-load-"))
    rows = []
    plan = [r for r in ROWS for _ in range(rows_wanted.count(r[0]) if rows_wanted else 1)]
    try:
        for name, cached, remove in plan:
            if name == "cold":
                shutil.rmtree(cache, ignore_errors=True)
                cache.mkdir()
            for pattern in remove:
                for f in cache.glob(pattern):
                    f.unlink()
            env = {**os.environ, "VKPBR_CACHE_DIR": str(cache)}
            if fresh_driver_cache:  # (the driver's own cache of compiled shaders, NVIDIA's)
                env["__GL_SHADER_DISK_CACHE_PATH"] = tempfile.mkdtemp(dir=cache)
            cmd = [sys.executable, __file__, "--child", str(scene), "--size", f"{size[0]}x{size[1]}"]
            if profile is not None:
                profile.mkdir(parents=True, exist_ok=True)
                cmd += ["--profile", str(profile / f"load-{name.replace(' ', '-')}.txt")]
            cmd += ["--serial"] if serial else []
            got = subprocess.run(cmd + (["--cached"] if cached else []), env=env, check=True,
                                 capture_output=True, text=True)
            rows.append({"row": name, **json.loads(got.stdout.strip().splitlines()[-1])})
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    return rows


def print_load_table(scene: Path, size: tuple[int, int], rows: list[dict], serial: bool) -> None:
    how = "load, then device" if serial else "loaded on a thread while the device is made"
    print(f"\n### {scene.name} file to first frame at {size[0]}x{size[1]} on {rows[0]['device_name']}"
          f" ({how}; auto: {rows[-1]['path']}; bytecode {rows[-1]['bytecode']})\n")
    print("| row | import | load | device | geometry | textures (decode wait) | other set-up "
          "| path choice | first frame (environment) | pipelines (hits) | pipeline s | **file to first frame** "
          "| again, device kept |")
    print("|---|" + "---:|" * 12)
    for r in rows:
        print(f"| {r['row']} | {r['import']:.2f} | {r['load']:.2f} | {r['device']:.2f} | "
              f"{r['geometry']:.2f} | {r['textures']:.2f} ({r['decode_wait']:.2f}) | "
              f"{r['parts']:.2f} | {r['choice']:.2f} | "
              f"{r['first_frame']:.2f} ({r['environment']:.2f}) | {r['pipelines_built']} ({r['pipeline_hits']}) | "
              f"{r['pipelines_s']:.2f} | **{r['total']:.2f}** | {r['again']:.2f} |")
    print("\nWhere the device's and the upload's seconds went (device: the loader's instance, the"
          " physical device's choice, the logical device, the pipeline cache's file; upload:"
          " images' and buffers' creation, the copy into staging memory, recording and submitting,"
          " the wait at the end):\n")
    print("| row | " + " | ".join(f"device: {k}" for k in _DEVICE_PARTS) + " | "
          + " | ".join(f"upload: {k}" for k in _UPLOAD_PARTS) + " |")
    print("|---|" + "---:|" * (len(_DEVICE_PARTS) + len(_UPLOAD_PARTS)))
    for r in rows:
        cells = [r.get("device_parts", {}).get(k) for k in _DEVICE_PARTS] + [
            r.get("upload_parts", {}).get(k) for k in _UPLOAD_PARTS]
        print(f"| {r['row']} | " + " | ".join("-" if v is None else f"{v:.3f}" for v in cells) + " |")


_DEVICE_PARTS = ("binding", "instance", "choice", "device", "pipeline_cache")
_UPLOAD_PARTS = ("create", "copy", "record", "wait")


# --- part 2: many scenes --------------------------------------------------------------------
def job_doc(models: list[Path], scenes: int, views: int, size: str, out: Path) -> dict:
    """`scenes` entries cycling over `models`, each a scene of its own: its model's folder
    under its own name (a symlink), so no two entries share a scene (a renderer keeps the
    scene it has, and the driver gives an actor the items of its scene first: entries of one
    path would be rendered without a load between them)."""
    from bench_ray import orbit

    poses = {m: [{"eye": list(map(float, p.eye)), "target": list(map(float, p.target))}
                 for p in orbit(m, views)] for m in models}
    entries = []
    for i in range(scenes):
        model = models[i % len(models)]
        folder = out.parent / "scenes" / f"{i:03d}-{model.parents[1].name}"
        folder.parent.mkdir(parents=True, exist_ok=True)
        if not folder.exists():
            folder.symlink_to(model.parents[1], target_is_directory=True)
        scene = folder / model.relative_to(model.parents[1])
        entries.append({"scene": str(scene), "cameras": poses[model],
                        "out": str(out / f"{i:03d}-{model.stem}"), "size": size})
    return {"scenes": entries, "views_per_item": views}


def _model_of(entry: dict) -> str:
    """The model an entry's scene is (its symlinked folder resolved)."""
    return str(Path(entry["scene"]).resolve())


def one_scene_rates(doc: dict, work: Path) -> dict[str, float]:
    """Views/s of each model's items rendered by a warm actor (its scene loaded once)."""
    from vkpbr.distributed import job_from_doc
    from vkpbr.distributed.actor import RendererActor

    rates = {}
    firsts = {}
    for entry in doc["scenes"]:
        firsts.setdefault(_model_of(entry), entry)
    actor = RendererActor()
    try:
        for scene, entry in firsts.items():
            job = job_from_doc([{**entry, "out": str(work / Path(scene).name)}])
            item = job.items()[0]
            (work / Path(scene).name).mkdir(parents=True, exist_ok=True)
            if not actor.render(item)["ok"]:  # the load and first renders: not timed
                continue  # (the job's rows count its views as failed)
            t = time.perf_counter()
            for _ in range(3):
                res = actor.render(item)
                assert res["ok"], res
            rates[scene] = 3 * len(item.frames) / (time.perf_counter() - t)
    finally:
        actor.close()
    return rates


def run_job(doc: dict, how: str, processes: int = 1) -> dict:
    from vkpbr.distributed import job_from_doc, render
    from vkpbr.distributed.driver import IN_PROCESS, PROCESSES

    for entry in doc["scenes"]:
        shutil.rmtree(entry["out"], ignore_errors=True)
    if "cold" in how:  # (the bake cache and the pipeline cache both)
        shutil.rmtree(os.environ["VKPBR_CACHE_DIR"], ignore_errors=True)
    job = job_from_doc(doc)
    if how == "no load ahead":
        return sequential(job)
    address = (PROCESSES if "processes" in how else IN_PROCESS if how.startswith("in-process")
               else None)
    if PROFILE_WORKERS is not None and address == PROCESSES:
        _profile_workers(PROFILE_WORKERS / "".join(c if c.isalnum() else "-" for c in how))
    timed_calls = None
    if TIME_VK_CALLS is not None and address == PROCESSES:
        timed_calls = _time_vk_calls(TIME_VK_CALLS / "".join(c if c.isalnum() else "-" for c in how))
    t0, firsts, cpu0 = time.perf_counter(), [], _cpu_seconds()
    phases: collections.Counter = collections.Counter()

    def on_result(item: object, res: dict) -> None:
        firsts.append(time.perf_counter() - t0)
        phases.update(res.get("phases", {}))

    result = render(job, address, actors=processes, progress=False, on_result=on_result)
    wall, cpu1 = time.perf_counter() - t0, _cpu_seconds()
    cores = ((cpu1[0] - cpu0[0]) / wall, (cpu1[1] - cpu0[1]) / wall)
    for line in result.summary()[1:4]:  # the first failures, if any (a model that needs a codec)
        print(f"  {how}: {line}", file=sys.stderr)
    if timed_calls is not None:
        import vk_call_timer

        print(f"\n{how}: " + "\n".join(vk_call_timer.summary(timed_calls, max(1, len(firsts)))))
    return {"views": result.rendered, "seconds": result.render_seconds,
            "failed": result.failed_views, "first": min(firsts, default=0.0), "cores": cores,
            "phases": {k: 1000 * v / max(1, len(firsts)) for k, v in phases.items()}}


PROFILE_WORKERS: Path | None = None  # --profile-workers
TIME_VK_CALLS: Path | None = None  # --time-vk-calls


def _time_vk_calls(folder: Path) -> Path:
    """Each renderer process's Vulkan calls timed by name from now on (vk_call_timer.py),
    a file a process in `folder`, written when it ends; the folder."""
    from vkpbr.distributed import processes

    shutil.rmtree(folder, ignore_errors=True)
    here = str(Path(__file__).resolve().parent)
    processes.WORKER = (f"import sys; sys.path.insert(0, {here!r}); import vk_call_timer; "
                        f"vk_call_timer.install({str(folder)!r}); "
                        "from vkpbr.app.render_worker import serve; serve()")
    return folder


def _profile_workers(folder: Path) -> None:
    """Each renderer process's main thread (the one that renders) under cProfile from now
    on, a file a process in `folder`, written when the job ends its workers (not killed)."""
    from vkpbr.distributed import processes

    folder.mkdir(parents=True, exist_ok=True)
    processes.WORKER = ("import cProfile, os; from vkpbr.app.render_worker import serve; "
                        f"cProfile.run('serve()', {str(folder)!r} + f'/{{os.getpid()}}.prof')")


def _cpu_seconds() -> tuple[float, float]:
    """CPU time of this process and its ended children (renderer processes): (user + system,
    system)."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    system = own.ru_stime + kids.ru_stime
    return own.ru_utime + kids.ru_utime + system, system


def sequential(job: object) -> dict:
    from vkpbr.distributed import check_job
    from vkpbr.distributed.actor import RendererActor
    from vkpbr.distributed.manifest import start_frames_folder

    for scene, manifest in zip(job.scenes, check_job(job), strict=True):
        start_frames_folder(scene, manifest)
        manifest.close()
    actor = RendererActor()
    t = time.perf_counter()
    views = failed = 0
    try:
        for item in job.items():
            res = actor.render(item)
            failed += 0 if res["ok"] else len(item.frames)
            views += len(item.frames) if res["ok"] else 0
    finally:
        actor.close()
    return {"views": views, "seconds": time.perf_counter() - t, "failed": failed}


def job_table(args: argparse.Namespace) -> list[dict]:
    models = sorted(p.resolve() for p in args.models.glob("*/glTF/*.gltf"))
    if not models:
        raise SystemExit(f"no */glTF/*.gltf under {args.models}")
    work = Path(tempfile.mkdtemp(prefix="vkpbr-bench-job-"))
    # (a fresh cache folder unless --cache-dir names one: "warm" alone is then warm only
    # where a run before filled it; a "cold" row empties it)
    os.environ["VKPBR_CACHE_DIR"] = str(args.cache_dir or work / "cache")
    rows = []
    try:
        doc = job_doc(models, args.scenes, args.views, args.job_size, work / "out")
        named = {"cold": "in-process job (cold bake cache)", "warm": "in-process job (warm)",
                 "sequential": "no load ahead"}
        runs = [] if args.no_in_process else [(named[r], 1) for r in args.job_runs.split(",") if r]
        for n in args.processes:
            runs += [(f"{n} processes job ({r})", n) for r in ("cold", "warm")
                     if r in args.job_runs.split(",")]
        for how, n in runs + ([("Ray, 1 actor", 1)] if args.ray else []):
            try:
                rows.append({"run": how, **run_job(doc, how, n)})
            except Exception as exc:  # noqa: BLE001 - Ray missing or failing: the other rows stand
                print(f"{how}: not measured ({type(exc).__name__}: {exc})", file=sys.stderr)
        rates = one_scene_rates(doc, work / "one")  # after: the bake cache is warm by now
        known = [_model_of(e) for e in doc["scenes"] if _model_of(e) in rates]
        ideal, good = sum(args.views / rates[m] for m in known), len(known)
        rows.insert(0, {"run": "one scene in-process", "views": args.views * good, "failed": 0,
                        "seconds": ideal, "rates": {Path(k).stem: v for k, v in rates.items()}})
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"\n### {args.scenes} scenes ({len(models)} models: {', '.join(m.stem for m in models)})"
          f" x {args.views} views at {args.job_size}, PNG written\n")
    print("| run | views | failed | s | views/s | of one scene in-process | first item done, s "
          "| cores busy (in the kernel) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    base = rows[0]["views"] / rows[0]["seconds"]
    for r in rows:
        rate = r["views"] / r["seconds"]
        first = f"{r['first']:.2f}" if "first" in r else ""
        cores = f"{r['cores'][0]:.1f} ({r['cores'][1]:.1f})" if "cores" in r else ""
        print(f"| {r['run']} | {r['views']} | {r['failed']} | {r['seconds']:.2f} | {rate:.1f} | "
              f"{rate / base:.0%} | {first} | {cores} |")
    named = [r for r in rows if r.get("phases")]
    if named:
        keys = list(named[0]["phases"])
        print("\nan item's ms (mean; wall clock of the thread that renders it, and its CPU):\n")
        print("| run | " + " | ".join(keys) + " |")
        print("|---|" + "---:|" * len(keys))
        for r in named:
            print(f"| {r['run']} | " + " | ".join(f"{r['phases'].get(k, 0):.1f}" for k in keys)
                  + " |")
    print("\none scene in-process, views/s per model: "
          + ", ".join(f"{k} {v:.0f}" for k, v in rows[0]["rates"].items()))
    return rows


def _positive(kind: type) -> object:
    """An argparse type: a number of `kind` above 0 (else argparse's one-line usage error)."""
    def parse(text: str) -> object:
        value = kind(text)
        if not value > 0:
            raise argparse.ArgumentTypeError(f"{text}: expected a number above 0")
        return value

    parse.__name__ = kind.__name__
    return parse


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", type=Path, default=ASSETS / "Sponza" / "glTF" / "Sponza.gltf")
    p.add_argument("--size", default="1280x720", help="the first frame's (vkpbr render's default)")
    p.add_argument("--models", type=Path, default=ASSETS)
    p.add_argument("--scenes", type=int, default=100)
    p.add_argument("--views", type=int, default=16)
    p.add_argument("--job-size", default="256x256")
    p.add_argument("--no-job", action="store_true")
    p.add_argument("--no-load", action="store_true")
    p.add_argument("--ray", action="store_true", help="also the job on Ray with one actor")
    p.add_argument("--json", type=Path)
    p.add_argument("--profile", type=Path, metavar="DIR",
                   help="also write each row's cProfile (top 60 by cumulative time) into DIR")
    p.add_argument("--builds", action="store_true",
                   help="also print every row's pipeline builds (shaders, when, how long)")
    p.add_argument("--rows", help="only these rows of part 1, comma-separated, each as often "
                   "as named (cold,cold: twice)")
    p.add_argument("--fresh-driver-cache", action="store_true",
                   help="each row with an empty shader disk cache of the driver's own (NVIDIA: "
                   "__GL_SHADER_DISK_CACHE_PATH), so every cold row is cold")
    p.add_argument("--serial", action="store_true",
                   help="load the scene, then make the device (as before vkpbr.bake.ahead)")
    p.add_argument("--job-runs", default="cold,warm,sequential",
                   help="the job's rows besides one scene: cold, warm, sequential (no load ahead)")
    p.add_argument("--processes", type=_positive(int), nargs="*", default=[], metavar="N",
                   help="also the job's cold and warm rows (those in --job-runs) with N "
                        "renderer processes (render(address=PROCESSES)), for each N")
    p.add_argument("--process-encoders", type=_positive(int), metavar="N",
                   help="encoding threads of each renderer process (default: the cores shared)")
    p.add_argument("--profile-workers", type=Path, metavar="DIR",
                   help="run each renderer process's main thread under cProfile, its stats "
                        "into DIR (benchmarks/profile_summary.py sums them)")
    p.add_argument("--cache-dir", type=Path, metavar="DIR",
                   help="the job's bake and pipeline caches in DIR, kept between runs (default: "
                        "a new folder each run, so a run of --job-runs warm alone is cold)")
    p.add_argument("--time-vk-calls", type=Path, metavar="DIR",
                   help="time each renderer process's Vulkan calls by name (vk_call_timer.py), "
                        "their files in DIR; print the longest per item")
    p.add_argument("--no-in-process", action="store_true",
                   help="only the --processes rows (and one scene's, for the ratio)")
    p.add_argument("--depth", type=_positive(int), metavar="N",
                   help="items in flight a renderer process (default: processes.DEPTH)")
    p.add_argument("--encoders", type=_positive(int),
                   help="the actor's encoding threads (default: vkpbr's, distributed/actor.py)")
    p.add_argument("--no-switch", action="store_true",
                   help="the actor changes scene at the next item's start, not while the last "
                   "item's files encode (as before session 18)")
    p.add_argument("--switch-interval", type=_positive(float),
                   help="Python's GIL switch interval in seconds for the job (default 0.005)")
    p.add_argument("--actor-switch-interval", type=_positive(float),
                   help="the interval an actor renders its items with (vkpbr's SWITCH_INTERVAL)")
    p.add_argument("--child", help=argparse.SUPPRESS)
    p.add_argument("--cached", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args()
    unknown = set(args.rows.split(",")) - {r[0] for r in ROWS} if args.rows else set()
    if unknown:
        p.error(f"--rows: no row {', '.join(sorted(unknown))} (the rows: "
                f"{', '.join(r[0] for r in ROWS)})")
    size = tuple(int(v) for v in args.size.split("x"))
    if args.child:
        if args.profile is None:
            print(json.dumps(child(args.child, size, args.cached, args.serial)))
            return
        import cProfile
        import io
        import pstats

        prof = cProfile.Profile()
        got = prof.runcall(child, args.child, size, args.cached, args.serial)
        text = io.StringIO()
        pstats.Stats(prof, stream=text).sort_stats("cumulative").print_stats(60)
        args.profile.write_text(text.getvalue())
        print(json.dumps(got))
        return
    out: dict = {}
    if not args.no_load:
        out["load"] = load_table(args.scene, size, args.profile, args.serial,
                                 args.rows.split(",") if args.rows else None,
                                 args.fresh_driver_cache)
        print_load_table(args.scene, size, out["load"], args.serial)
        if args.builds:
            print_builds(out["load"])
    if not args.no_job:
        from vkpbr.distributed import actor

        if args.encoders:
            actor.ENCODERS = args.encoders
        from vkpbr.distributed import driver

        if args.process_encoders:
            driver.encoders_for = lambda n: args.process_encoders  # (the driver's name)
        if args.depth:
            driver.DEPTH = args.depth
        global PROFILE_WORKERS, TIME_VK_CALLS
        PROFILE_WORKERS, TIME_VK_CALLS = args.profile_workers, args.time_vk_calls
        if args.actor_switch_interval:
            actor.SWITCH_INTERVAL = args.actor_switch_interval
        if args.switch_interval:
            sys.setswitchinterval(args.switch_interval)
        if args.no_switch:
            actor.RendererActor._change_early = lambda self, ahead, later: None
        out["job"] = job_table(args)
    if args.json:
        args.json.write_text(json.dumps(out, indent=1, default=str))


if __name__ == "__main__":
    main()
