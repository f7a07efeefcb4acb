"""The post steps: each a class here, its kernel shaders/post_<name>.comp and its option
(render/options.py POST_OPTIONS); the machinery they run on is render/post_stage.py.

Bloom: bright light spreading over its surroundings, as a lens and an eye see it:
Filament's and pygfx's physically based bloom (shaders/post_bloom.comp): no threshold; the
radiance downsampled into up to BLOOM_LEVELS half-size images, upsampled back averaging
them, and the result mixed in: color = mix(color, bloom, strength). Each step keeps the
image's mean but at the last row or column of an odd size, counted twice, so the frame's
total radiance is kept within 0.5% at 64 pixels a side and more (3% in a 5 x 5 frame). `--bloom STRENGTH` (0..1; 0: off).
"""

from __future__ import annotations

import numpy as np

from vkpbr.gpu.graph import Step
from vkpbr.render.options import POST_OPTIONS
from vkpbr.render.post_stage import PostContext, PostStep

__all__ = ["Bloom", "BLOOM_LEVELS", "post_steps"]

BLOOM_LEVELS = 6  # the smallest is 1/64 of the frame: a glow some tens of pixels wide
_DOWN, _UP, _MIX = 0, 1, 2


def level_sizes(extent: tuple[int, int]) -> list[tuple[int, int]]:
    """The chain's sizes: each half the one above (rounded up), while at least 2 x 2."""
    sizes, (w, h) = [], extent
    while len(sizes) < BLOOM_LEVELS and min(w, h) >= 4:
        w, h = -(-w // 2), -(-h // 2)
        sizes.append((w, h))
    return sizes


class Bloom(PostStep):
    option = "bloom"

    def steps(self, ctx: PostContext, value: float) -> list[Step]:
        sizes = level_sizes(ctx.extent)
        if not sizes:
            return []
        names = [f"bloom{i}" for i in range(len(sizes))]
        views = [ctx.transient(n, s) for n, s in zip(names, sizes, strict=True)]
        steps, src, src_name = [], ctx.color_view, "color"
        for name, view, size in zip(names, views, sizes, strict=True):
            push = np.array([_DOWN, 0, 0], np.uint32)
            steps.append(Step(f"bloom_down.{name}", ctx.dispatch("post_bloom", push, src, view, size),
                              ((src_name, "storage_read"), (name, "storage")), timed=False))
            src, src_name = view, name
        for k in range(len(sizes) - 2, -1, -1):  # level k becomes the mean of levels k..
            push = np.array([_UP, 0, 0], np.uint32)
            push.view(np.float32)[2] = 1.0 / (len(sizes) - k)
            steps.append(Step(f"bloom_up.{names[k]}",
                              ctx.dispatch("post_bloom", push, views[k + 1], views[k], sizes[k]),
                              ((names[k + 1], "storage_read"), (names[k], "storage")), timed=False))
        push = np.array([_MIX, 0, 0], np.uint32)
        push.view(np.float32)[1] = value
        steps.append(Step("bloom", ctx.dispatch("post_bloom", push, views[0], ctx.color_view,
                                                ctx.extent),
                          ((names[0], "storage_read"), ("color", "storage"))))
        return steps


def post_steps() -> dict[str, type[PostStep]]:
    """Every post step by its option, in POST_OPTIONS' order (each row needs its class)."""
    classes = {cls.option: cls for cls in PostStep.__subclasses__()}
    return {row.field: classes[row.field] for row in POST_OPTIONS}
