"""The dataset outputs (`render(outputs=...)`, docs/outputs.md): their names, the check of
a request, the arrays made from a target's output images, and what each instance id is.

The outputs come from the compute path's visibility pass (render/layouts.py OUTPUT_IMAGES);
`check_outputs` says why a target cannot have them, or makes their images on first use.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.gpu.target import OffscreenTarget
from vkpbr.render import layouts as L
from vkpbr.render.gpu_scene import GpuScene
from vkpbr.render.path_choice import FramePaths
from vkpbr.render.targets import Targets
from vkpbr.scene.types import Scene

__all__ = ["OUTPUTS", "OUTPUT_PARTS", "check_outputs", "frame_outputs", "instances", "max_id",
           "output_images", "to_camera"]

# Dataset outputs of render(outputs=...): name -> what it is (docs/outputs.md).
OUTPUTS = {
    "color": "the frame's colour, as render returns it",
    "depth": "(H, W) float32 distance along the view axis; inf where nothing was drawn",
    "range": "(H, W) float32 distance to the camera centre; inf where nothing was drawn",
    "instance": "(H, W) uint32 instance id: Renderer.instances[id - 1]; 0 = background",
    "semantic": "(H, W) uint32 semantic id (Renderer(semantics=...): by default the mesh's index + 1; "
                "Renderer.semantic_labels names them); 0 = background or no class",
    "normal": "(H, W, 3) float32 world shading normal (normal-mapped); 0 = background",
    "normal_camera": "(H, W, 3) float32 the shading normal in camera axes (OpenGL: x right, "
                     "y up, z towards the viewer); 0 = background",
    "normal_geometric": "(H, W, 3) float32 world interpolated vertex normal (before normal "
                        "mapping); 0 = background",
    "motion": "(H, W, 2) float32 where each surface point was in the previous frame's image, "
              "in pixels from where it is now (x right, y down): camera, node, skin and morph "
              "motion; 0 = background and on a renderer's first frame",
    "ao": "(H, W) float32 screen-space ambient occlusion (GTAO, render/ao.py): visibility of "
          "the image-based light, 1 unoccluded; 1 = background",
}


# Where each output is in the output images (render/layouts.py OUTPUT_IMAGES, written by
# shade.comp's OUTPUTS builds and the GTAO step): (image, channels).
OUTPUT_PARTS: dict[str, tuple[str, int | slice]] = {
    "depth": ("out_depth_range", 0), "range": ("out_depth_range", 1),
    "instance": ("out_ids", 0), "semantic": ("out_ids", 1),
    "normal": ("out_normal", slice(0, 3)), "normal_camera": ("out_normal", slice(0, 3)),
    "normal_geometric": ("out_normal_geometric", slice(0, 3)),
    "motion": ("out_depth_range", slice(2, 4)), "ao": ("out_ao", 0)}


def output_images(wanted: Iterable[str]) -> tuple[str, ...]:
    """The output images `wanted` reads, in OUTPUT_IMAGES' order ("color": none)."""
    names = {OUTPUT_PARTS[n][0] for n in wanted if n in OUTPUT_PARTS}
    return tuple(n for n in L.OUTPUT_IMAGES if n in names)


def check_outputs(outputs: Iterable[str] | None, target: OffscreenTarget, paths: FramePaths,
                  targets: Targets) -> tuple[str, ...]:
    """The dataset outputs asked for, checked (UsageError: unknown, or not available for
    frames of `target`); their images of `target` made on first use."""
    if outputs is None:
        return ()
    if not isinstance(outputs, str | Iterable):
        raise UsageError(f"outputs: expected names from {', '.join(OUTPUTS)}, got "
                         f"{type(outputs).__name__}")
    wanted = tuple(outputs) if not isinstance(outputs, str) else (outputs,)
    unknown = [n for n in wanted if n not in OUTPUTS]
    if unknown:
        raise UsageError(f"unknown output {unknown[0]!r}; choose from {', '.join(OUTPUTS)}")
    why = paths.compute_unavailable(target)
    if why is not None:
        raise UsageError(f"dataset outputs are not available here: the compute path's "
                         f"visibility pass makes them and {why}")
    targets.ensure_outputs(target)
    return wanted


def frame_outputs(images: dict[str, np.ndarray], color: np.ndarray, wanted: tuple[str, ...],
                  camera_rotation: np.ndarray) -> dict[str, np.ndarray]:
    """The outputs' arrays from the target's output images (render/layouts.py OUTPUT_IMAGES;
    a frame's (H, W, C) with its camera's (3, 3) rotation, or a batch's (B, H, W, C) with
    each view's (B, 3, 3)).
    Blended and background pixels are not in the ids (only what the visibility pass draws:
    opaque and alpha-masked surfaces, alpha-masked texels cut out as from the colour)."""
    def part(name: str) -> np.ndarray:
        image, channels = OUTPUT_PARTS[name]
        return images[image][..., channels]

    def made(name: str) -> np.ndarray:
        if name == "color":
            return color
        if name == "normal_camera":
            # float32 throughout: a float64 rotation made NumPy promote and loop (40 ms at
            # 1080p on the CI machine, against 7 ms; within 5e-7 of it).
            return to_camera(part(name), camera_rotation)
        return part(name).copy()

    return {name: made(name) for name in wanted}


def to_camera(normal: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """World normals (..., 3) in camera axes: `normal @ rotation`, one (3, 3) rotation for a
    frame's or one per view (B, 3, 3) for a batch's (B, H, W, 3)."""
    r = np.asarray(rotation, np.float32)
    if r.ndim == 2:
        return normal @ r
    return (normal.reshape(len(r), -1, 3) @ r).reshape(normal.shape)


def instances(scene: Scene, gpu_scene: GpuScene, semantic_ids: np.ndarray,
              semantic_labels: dict[int, str]) -> list[dict[str, Any]]:
    """What each instance id of the outputs is: [{"id", "node", "mesh", "material",
    "semantic", "label"}], id = index + 1 (0 is the background)."""
    out = []
    for i, d in enumerate(gpu_scene.draws):
        mesh = scene.meshes[d.mesh]
        sem = int(semantic_ids[i])
        out.append({"id": i + 1, "mesh": mesh.name, "semantic": sem,
                    "label": semantic_labels.get(sem, ""),
                    "material": gpu_scene.materials[d.material].name,
                    "node": scene.nodes[d.node].name if 0 <= d.node < len(scene.nodes) else ""})
    return out


def max_id(gpu_scene: GpuScene, semantic_ids: np.ndarray) -> int:
    """The largest instance or semantic id the outputs can hold (id images must fit it)."""
    return max(len(gpu_scene.draws), int(semantic_ids.max(initial=0)))
