"""The compute path's kernels as the driver compiled them (issue 13: how close to the limit):
registers, shared memory and whatever else the driver reports per kernel
(VK_KHR_pipeline_executable_properties: ncu profiles CUDA kernels, not Vulkan dispatches),
with the occupancy the registers allow on an SM of 65,536 registers and 64 warps (Hopper,
Ampere: the CUDA occupancy rule, registers allocated per warp in blocks of 256).

    python benchmarks/probe_kernels.py --scene Sponza.gltf [--size 1920x1080]

Renders a frame of each lighting on the compute path (compute rasteriser) so that every
kernel a frame uses is made, then prints a Markdown table. Not a test.
"""

from __future__ import annotations

import argparse

from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene

REGISTERS_PER_SM, WARPS_PER_SM, WARP, GRANULE = 65536, 64, 32, 256


def occupancy(registers: int) -> float:
    """Share of an SM's 64 warp slots that kernels of `registers` a thread can fill."""
    per_warp = -(-registers * WARP // GRANULE) * GRANULE
    return min(WARPS_PER_SM, REGISTERS_PER_SM // max(per_warp, 1)) / WARPS_PER_SM


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--size", default="1920x1080")
    args = ap.parse_args()
    size = tuple(int(x) for x in args.size.split("x"))
    with Renderer(load_scene(args.scene)) as r:
        if not r.device.pipeline_statistics:
            raise SystemExit(f"{r.device.info.name}: the driver reports no pipeline statistics")
        for lighting in ("course", "pbr"):
            r.render(size=size, lighting=lighting, pipeline="compute", raster="compute")
        stats = r.compute_scene().kernel_statistics()
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
