"""gpu/rendering.py tile_regions: the atlas copy's VkBufferImageCopy array, filled through a
NumPy view of the C structs, holds what the binding's own constructors would (every field)."""

from __future__ import annotations

import pytest
import vulkan as vk

from vkpbr.gpu.rendering import tile_regions


@pytest.mark.parametrize("tiles", [(1, 16, 8, 1), (7, 5, 3, 3), (70, 64, 32, 9)])
def test_regions_hold_each_tile_view_major(tiles) -> None:  # noqa: ANN001
    n, w, h, cols = tiles
    aspect = vk.VK_IMAGE_ASPECT_COLOR_BIT
    got = tile_regions(vk, tiles, 4096, 16, aspect, 2)
    for v in range(n):
        r = got[v]
        assert (r.bufferOffset, r.bufferRowLength, r.bufferImageHeight) == (4096 + v * w * h * 16, 0, 0)
        s = r.imageSubresource
        assert (s.aspectMask, s.mipLevel, s.baseArrayLayer, s.layerCount) == (aspect, 0, 0, 2)
        assert (r.imageOffset.x, r.imageOffset.y, r.imageOffset.z) == ((v % cols) * w, (v // cols) * h, 0)
        assert (r.imageExtent.width, r.imageExtent.height, r.imageExtent.depth) == (w, h, 1)
