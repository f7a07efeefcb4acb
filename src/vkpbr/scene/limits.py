"""Resource limits for untrusted scenes (issue 11, memory bombs): checked where data enters.

A 1 KB JPEG can declare 12000x12000 pixels (2.3 GiB decoded); a small OBJ can expand to
millions of faces. vkpbr refuses such inputs with one line naming the file, the size and the
limit, instead of exhausting memory. The defaults are far above real assets (Sponza: 2048x2048
textures, 0.26 M triangles); raise them through the environment:

    VKPBR_MAX_TEXTURE_PIXELS  pixels in one texture (default 2**26 = 8192 x 8192)
    VKPBR_MAX_TRIANGLES       triangles in one scene (default 2**26, 67 M)
    VKPBR_MAX_VERTICES        vertices in one scene (default 2**26)
    VKPBR_MAX_TEXTURE_FILE_BYTES  bytes read of one texture file (default 2**30)
    VKPBR_MAX_TEXTURE_BYTES   decoded RGBA8 bytes of all of one scene's textures (default
                              2**32, 4 GiB: 256 textures of 2048 x 2048)

The OBJ reader checks its statement counts against the vertex and triangle limits before it
builds any array; every format's loaded scene is checked again (scene/validate.py).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

__all__ = ["MAX_MORPH_TARGETS", "Limits", "limits"]

# Morph targets one mesh may have: the GPU's budget (the deformation step reads every target's
# displacements each frame), fixed rather than configurable. Real assets use a few dozen at
# most (facial rigs: 50-60); a file with more is refused in one line (docs/animation.md).
MAX_MORPH_TARGETS = 64


@dataclass(frozen=True)
class Limits:
    max_texture_pixels: int = 1 << 26
    max_triangles: int = 1 << 26
    max_vertices: int = 1 << 26
    max_texture_file_bytes: int = 1 << 30
    max_texture_bytes: int = 1 << 32


def _env_int(name: str, default: int) -> int:
    text = os.environ.get(name)
    if not text:
        return default
    try:
        value = int(text)
    except ValueError:
        return default
    return value if value > 0 else default


def limits() -> Limits:
    """The limits in force (read from the environment each call: cheap, and tests can set it)."""
    d = Limits()
    return Limits(_env_int("VKPBR_MAX_TEXTURE_PIXELS", d.max_texture_pixels),
                  _env_int("VKPBR_MAX_TRIANGLES", d.max_triangles),
                  _env_int("VKPBR_MAX_VERTICES", d.max_vertices),
                  _env_int("VKPBR_MAX_TEXTURE_FILE_BYTES", d.max_texture_file_bytes),
                  _env_int("VKPBR_MAX_TEXTURE_BYTES", d.max_texture_bytes))
