"""vkpbr.bake.ahead without a GPU: which images are decoded ahead, and when a device takes
them (the same decode it would make) or decodes again."""

from __future__ import annotations

import io

import numpy as np
from PIL import Image as PilImage

from vkpbr.bake.ahead import scene_ahead
from vkpbr.scene.gltf_codecs import KTX2_MAGIC
from vkpbr.scene.types import Image, Scene


def _png(w: int, h: int) -> bytes:
    out = io.BytesIO()
    PilImage.fromarray(np.full((h, w, 4), 7, np.uint8)).save(out, "PNG")
    return out.getvalue()


def test_images_decoded_ahead_only_where_the_device_would_decode_them_the_same() -> None:
    def scene() -> Scene:
        return Scene("s", images=[Image("a.png", data=_png(8, 4)), Image("gone")])

    ahead = scene_ahead(scene)
    assert ahead.result().name == "s"
    pixels = ahead.decoded.result()
    assert pixels[0].shape == (4, 8, 4) and (pixels[0] == 7).all() and pixels[1] is None
    assert ahead.decoded_for(16384)[0] is pixels[0] and ahead.decoded is None  # handed over once
    small = scene_ahead(scene)
    assert small.decoded_for(4) is None  # a device whose images are smaller: decoded again
    ktx2 = scene_ahead(lambda: Scene("k", images=[Image("t", data=KTX2_MAGIC + b"...")]))
    ktx2.result()
    assert ktx2.decoded.result() is None and ktx2.decoded_for(16384) is None  # BC7 or not: the device's
    built_in = scene_ahead(lambda: None)
    assert built_in.result() is None and built_in.decoded_for(16384) is None
