"""The compute path's kernels as the driver compiled them (issue 13: how close to the limit):
registers, shared memory and whatever else the driver reports per kernel
(VK_KHR_pipeline_executable_properties: ncu profiles CUDA kernels, not Vulkan dispatches),
with the occupancy the registers allow on an SM of 65,536 registers and 64 warps (Hopper,
Ampere: the CUDA occupancy rule, registers allocated per warp in blocks of 256).

    python benchmarks/probe_kernels.py --scene Sponza.gltf [--size 1920x1080]
    python benchmarks/probe_kernels.py --scene CesiumMan.gltf --others   (+ shadow maps, skinning)

Renders a frame of each lighting on the compute path (compute rasteriser) so that every
kernel a frame uses is made, then prints a Markdown table. `--others` adds the compute
shadow rasteriser's kernels (a frame with shadow_raster="compute") and the deform kernel
(a scene with skins or morph targets). Not a test.
"""

from __future__ import annotations

import argparse

from vkpbr.gpu.compute import ComputePipeline
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene

REGISTERS_PER_SM, WARPS_PER_SM, WARP, GRANULE = 65536, 64, 32, 256


def occupancy(registers: int) -> float:
    """Share of an SM's 64 warp slots that kernels of `registers` a thread can fill."""
    per_warp = -(-registers * WARP // GRANULE) * GRANULE
    return min(WARPS_PER_SM, REGISTERS_PER_SM // max(per_warp, 1)) / WARPS_PER_SM


def twin_statistics(device, spv: str, layouts: list, push_bytes: int) -> dict:  # noqa: ANN001
    """The driver's statistics of kernel `spv` built again with capture on."""
    twin = ComputePipeline(device, SPV_DIR / spv, layouts, push_bytes=push_bytes,
                           capture_statistics=True)
    try:
        return twin.statistics()
    finally:
        twin.destroy()


def other_statistics(r: Renderer, size: tuple[int, int]) -> dict[str, dict]:
    """The compute shadow rasteriser's kernels and the deform kernel, where the scene has them."""
    from vkpbr.render.shadow_raster import PUSH_BYTES

    r.render(size=size, pipeline="compute", raster="compute", shadow_raster="compute")
    out = {}
    raster = r.shadows._raster
    if raster is not None:
        for name in ("small", "big", "masked"):
            out[f"shadow_{name}"] = twin_statistics(r.device, f"shadow_{name}.comp.spv",
                                                    raster.layouts, PUSH_BYTES)
    deform = r.recorder.deform
    if deform is not None:
        out["deform"] = twin_statistics(r.device, "deform.comp.spv", [deform.set_layout], 8)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--others", action="store_true", help="shadow raster and deform kernels too")
    args = ap.parse_args()
    size = tuple(int(x) for x in args.size.split("x"))
    with Renderer(load_scene(args.scene)) as r:
        if not r.device.pipeline_statistics:
            raise SystemExit(f"{r.device.info.name}: the driver reports no pipeline statistics")
        for lighting in ("course", "pbr"):
            r.render(size=size, lighting=lighting, pipeline="compute", raster="compute")
        stats = r.compute_scene().kernel_statistics()
        if args.others:
            stats.update(other_statistics(r, size))
    names = list(dict.fromkeys(k for s in stats.values() for k in s))
    register_key = next((k for k in names if "register" in k.lower()), None)
    print(f"device: {r.device.info.name}")
    print("| kernel | " + " | ".join(names) + (" | occupancy (registers) |" if register_key else " |"))
    print("|" + "---|" * (len(names) + 1 + bool(register_key)))
    for kernel, s in stats.items():
        cells = [str(s.get(k, "")) for k in names]
        if register_key:
            cells.append(f"{occupancy(int(s[register_key])):.0%}" if register_key in s else "")
        print(f"| {kernel} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
