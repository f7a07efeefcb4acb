"""The driver's statistics of compiled compute kernels (gpu/compute.py
ComputePipeline.statistics, VK_KHR_pipeline_executable_properties): what
benchmarks/probe_kernels.py reports as the compute path's registers and occupancy. Lavapipe
(Mesa 22.3) lacks the extension: there the request is a clear error; the statistics
themselves are checked in the GPU test pass."""

from __future__ import annotations

import numbers

import pytest

from vkpbr.errors import VkpbrError
from vkpbr.gpu.compute import ComputePipeline
from vkpbr.render.codegen import SPV_DIR


def test_every_kernel_a_frame_used_reports_numbers(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer()
    if not r.device.compute_path:
        pytest.skip(f"{r.device.info.name} lacks the compute path's features")
    r.render(size=(48, 32), pipeline="compute")
    scene = r.compute_scene()
    if not r.device.pipeline_statistics:
        with pytest.raises(VkpbrError, match="no pipeline statistics"):
            ComputePipeline(r.device, SPV_DIR / "classify_offsets.comp.spv", scene.layouts,
                            push_bytes=32, capture_statistics=True)
        pytest.skip(f"{r.device.info.name}'s driver lacks VK_KHR_pipeline_executable_properties "
                    "(its refusal is checked above)")
    stats = scene.kernel_statistics()
    assert {"classify_offsets", "classify_scatter"} <= set(stats)
    for kernel, values in stats.items():
        assert values, f"{kernel}: no statistics"
        assert all(isinstance(v, numbers.Number) for v in values.values()), (kernel, values)
