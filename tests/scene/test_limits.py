"""Issue 11, class 4: memory bombs are refused where they enter, with one line naming the
limit, before anything large is allocated."""

from __future__ import annotations

import resource
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

from vkpbr.errors import SceneError
from vkpbr.scene.loader import load_scene
from vkpbr.scene.textures import decode_image
from vkpbr.scene.types import Image


def _png_header_only(width: int, height: int) -> bytes:
    """A PNG that declares width x height RGBA pixels and holds almost nothing."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b"")


def test_a_declared_12000x12000_texture_is_refused_before_decoding() -> None:
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    pixels, notes = decode_image(Image("bomb.png", data=_png_header_only(12000, 12000)))
    grown_mib = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024
    assert pixels is None
    assert notes and notes[0][0] == "undecodable" and "texture limit" in notes[0][1], notes
    assert grown_mib < 100  # 12000 x 12000 RGBA would be 549 MiB


def test_the_texture_limit_can_be_raised_and_lowered(monkeypatch) -> None:  # noqa: ANN001
    img = Image("small", pixels=np.zeros((20, 20, 4), np.uint8))
    import io

    from PIL import Image as PILImage
    buf = io.BytesIO()
    PILImage.fromarray(img.pixels, "RGBA").save(buf, format="PNG")
    encoded = Image("small.png", data=buf.getvalue())
    assert decode_image(encoded)[0].shape == (20, 20, 4)
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_PIXELS", "399")
    assert decode_image(encoded)[0] is None
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_PIXELS", "400")
    assert decode_image(encoded)[0] is not None


def test_triangle_and_vertex_limits(tmp_path: Path, monkeypatch) -> None:  # noqa: ANN001
    obj = tmp_path / "m.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n")
    assert load_scene(obj).triangle_count == 2
    monkeypatch.setenv("VKPBR_MAX_TRIANGLES", "1")
    with pytest.raises(SceneError, match=r"2 triangles are over the limit of 1 \(VKPBR_MAX_TRIANGLES\)"):
        load_scene(obj)
    monkeypatch.delenv("VKPBR_MAX_TRIANGLES")
    monkeypatch.setenv("VKPBR_MAX_VERTICES", "3")
    with pytest.raises(SceneError, match="VKPBR_MAX_VERTICES"):
        load_scene(obj)
