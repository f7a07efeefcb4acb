"""Frames that run beside the readback copy of the frame before (gpu/graph.py): a frame's
first use of a resource waits for every earlier command but copies, unless a copy can touch
it last (`copied`: the readback's images and buffers); a recording that leaves another
resource last touched by a copy closes with a barrier after it (`TAIL_WAITS`).

Checked here, on lavapipe with validation and synchronization validation on:
- the frames users render most (the compute path with its rasteriser, compute-drawn maps of
  a sun and a spot light that a walk redraws and scrolls, GTAO; the forward path; frames in
  flight through render_many; depth; a batch) need no closing barrier: every resource a copy
  touches last says so, and the early clears are kernels;
- frames in flight equal render()'s frame by frame, bit for bit (they share the kernels'
  buffers, which the next frame clears while the copy before may still run).
This machine's validation layer checks hazards within a submission only, so the
cross-submission rule is checked by the tracker's barriers (tests/unit/test_frame_graph.py)
and by the frames' pixels here; on a GPU the frames do overlap (BENCHMARKS.md).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from shadow_scenes import BLOCK, CAMERA, CARD, GROUND, LIGHTS, rect_scene

from vkpbr.gpu import graph

SIZE = (96, 72)
LIGHTS_ON = [LIGHTS["directional"], LIGHTS["spot"]]
WALK = [dataclasses.replace(CAMERA, eye=(0.3 * i, 4.0 + 0.1 * i, 6.0 - 0.25 * i)) for i in range(6)]


@pytest.fixture(scope="module")
def renderer():
    from vkpbr import Renderer

    r = Renderer(rect_scene((GROUND, BLOCK, CARD)), validation=True, sync_validation=True)
    yield r
    instance = r.device.instance
    r.close()
    assert instance.errors == [], instance.errors[:3]


@pytest.mark.parametrize("pipeline", ["compute", "forward"])
def test_frames_in_flight_need_no_closing_barrier_and_equal_render(renderer, pipeline: str) -> None:  # noqa: ANN001
    opts = {"pipeline": pipeline, "shadow_raster": "compute", "shadow_resolution": 256,
            "env": "sky", "ao": "gtao"}
    if pipeline == "compute":
        opts["raster"] = "compute"
    before = dict(graph.TAIL_WAITS)
    streamed = [(c.copy(), d.copy()) for c, d in
                renderer.render_many(WALK, LIGHTS_ON, size=SIZE, depth=True, **opts)]
    alone = [renderer.render(cam, LIGHTS_ON, size=SIZE, depth=True, **opts) for cam in WALK]
    batch = renderer.render_batch(WALK[:3], SIZE, LIGHTS_ON, **opts)
    assert before == graph.TAIL_WAITS, "a copy touched a resource last that is not `copied`"
    for i, ((c, d), (c1, d1)) in enumerate(zip(streamed, alone, strict=True)):
        assert np.array_equal(c, c1), f"frame {i}: render_many's colour differs from render()'s"
        assert np.array_equal(d, d1), f"frame {i}: render_many's depth differs from render()'s"
    assert not np.array_equal(streamed[0][0], streamed[-1][0])  # the walk moved
    assert len(batch) == 3


def test_a_copy_of_a_resource_not_marked_copied_closes_its_recording(renderer) -> None:  # noqa: ANN001
    """The ambient occlusion output copies the AO image (not `copied`: no other frame copies
    it): that frame closes with a barrier after the copy, and the next frame is as render()
    alone makes it."""
    opts = {"pipeline": "compute", "raster": "compute", "shadow_raster": "compute",
            "shadow_resolution": 256, "ao": "gtao"}
    before = graph.TAIL_WAITS.get("ao", 0)
    out = renderer.render(WALK[0], LIGHTS_ON, size=SIZE, outputs=("ao",), **opts)
    assert graph.TAIL_WAITS.get("ao", 0) > before
    assert "ao" in out
    after = renderer.render(WALK[1], LIGHTS_ON, size=SIZE, **opts)
    from vkpbr import Renderer

    fresh = Renderer(rect_scene((GROUND, BLOCK, CARD)), validation=True)
    instance = fresh.device.instance
    try:
        assert np.array_equal(after, fresh.render(WALK[1], LIGHTS_ON, size=SIZE, **opts))
    finally:
        fresh.close()
    assert instance.errors == [], instance.errors[:3]
