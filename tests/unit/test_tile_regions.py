"""gpu/rendering.py tile_regions: the compute batch's atlas copy. Its VkBufferImageCopy array
(one region a column of tiles, filled through a NumPy view of the C structs) is applied here
as Vulkan applies it to a NumPy atlas whose every pixel names its view, and must lay the views
out one after another (view-major), each its own tile."""

from __future__ import annotations

import numpy as np
import pytest
import vulkan as vk

from vkpbr.gpu.rendering import tile_regions


def apply(regions, count: int, atlas: np.ndarray, nbytes: int, pixel_bytes: int) -> np.ndarray:  # noqa: ANN001
    """vkCmdCopyImageToBuffer of `atlas` (H, W, pixel_bytes) uint8 with tight rows."""
    out = np.zeros(nbytes, np.uint8)
    for i in range(count):
        r = regions[i]
        assert (r.bufferRowLength, r.bufferImageHeight) == (0, 0)
        x, y = r.imageOffset.x, r.imageOffset.y
        w, h = r.imageExtent.width, r.imageExtent.height
        block = atlas[y:y + h, x:x + w].reshape(-1)
        out[r.bufferOffset:r.bufferOffset + block.size] = block
    return out


@pytest.mark.parametrize("tiles", [(1, 16, 8, 1), (7, 5, 3, 3), (70, 6, 4, 9), (64, 3, 2, 8)])
def test_regions_lay_the_tiles_out_view_after_view(tiles) -> None:  # noqa: ANN001
    n, w, h, rows = tiles
    cols = -(-n // rows)
    pb, offset = 4, 64
    atlas = np.full((rows * h, cols * w, pb), 255, np.uint8)  # unused tiles: 255
    for v in range(n):
        c, r = divmod(v, rows)  # column-major, as raster.comp / shade.comp tile_origin
        tile = atlas[r * h:(r + 1) * h, c * w:(c + 1) * w]
        tile[..., 0] = v
        tile[..., 1] = np.arange(h)[:, None]  # row within the tile
        tile[..., 2] = np.arange(w)[None, :]  # column within the tile
    regions = tile_regions(vk, tiles, offset, pb, vk.VK_IMAGE_ASPECT_COLOR_BIT)
    assert len(regions) == cols
    got = apply(regions, cols, atlas, offset + n * w * h * pb, pb)[offset:].reshape(n, h, w, pb)
    assert (got[..., 0] == np.arange(n)[:, None, None]).all()
    assert (got[..., 1] == np.arange(h)[None, :, None]).all()
    assert (got[..., 2] == np.arange(w)[None, None, :]).all()
    s = regions[0].imageSubresource
    assert (s.aspectMask, s.mipLevel, s.baseArrayLayer, s.layerCount) == (vk.VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1)
