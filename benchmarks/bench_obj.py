"""OBJ reader benchmark (issue 15): load_obj on a Sponza OBJ, tinyobjloader's parse alone,
and the geometry load breakdown.

    python benchmarks/bench_obj.py [--obj PATH] [--repeat N]

Without --obj it uses the course's Sponza OBJ if $VKPBR_SPONZA_OBJ names one, else writes
one (22.6 MB, 262k triangles, no vn) from the glTF Sponza with trimesh into
$TMPDIR/vkpbr-bench-obj/ (once; trimesh needed for that only). Not a test: prints, asserts
nothing.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))
from assets_path import ASSETS  # noqa: E402


def sponza_obj() -> Path:
    given = os.environ.get("VKPBR_SPONZA_OBJ")
    if given:
        return Path(given)
    out = Path(tempfile.gettempdir()) / "vkpbr-bench-obj" / "sponza.obj"
    if not out.exists():
        import trimesh
        from trimesh.exchange.obj import export_obj

        out.parent.mkdir(parents=True, exist_ok=True)
        scene = trimesh.load_scene(ASSETS / "Sponza" / "glTF" / "Sponza.gltf")
        text, files = export_obj(scene, include_texture=True, return_texture=True,
                                 mtl_name="sponza.mtl")
        for name, data in files.items():
            (out.parent / name).write_bytes(data)
        out.write_text(text)
    return out


def best(fn, repeat: int) -> float:  # noqa: ANN001
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--obj", type=Path)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    path = args.obj or sponza_obj()
    warnings.simplefilter("ignore")
    import tinyobjloader

    from vkpbr.scene.obj import load_obj

    data = path.read_bytes()
    text = data.decode("latin-1")

    def parse_only() -> None:
        config = tinyobjloader.ObjReaderConfig()
        config.triangulate = False
        assert tinyobjloader.ObjReader().ParseFromString(text, "", config)

    scene = load_obj(path)
    print(f"{path} ({len(data) / 1e6:.1f} MB): {len(scene.meshes)} meshes, "
          f"{scene.triangle_count:,} triangles")
    print(f"tinyobjloader parse only                     {best(parse_only, args.repeat):.3f} s")
    print(f"load_obj (geometry + MTL, no texture decode) {best(lambda: load_obj(path), args.repeat):.3f} s")


if __name__ == "__main__":
    main()
