"""The viewer's heads-up display: a bitmap font made from Pillow's default font, and text
laid out into quads for `vkpbr.gpu.text_overlay.QuadOverlay`.

Glyphs are rasterised once (printable ASCII) into an atlas; text is laid out with NumPy, one
vectorised pass per line, and scaled by a whole number that grows with the window so the HUD
stays readable (and crisp, with nearest sampling) from 160x120 to 4K. Each block of text sits
on a translucent dark panel so it reads over any image.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FontAtlas", "TextBlock", "layout_blocks", "hud_scale"]

_FIRST, _LAST = 32, 126  # printable ASCII; anything else is drawn as '?'


class FontAtlas:
    """Printable ASCII rasterised with Pillow's default font (FreeType when available).

    `pixels` is the (H, W, 4) uint8 atlas (coverage in every channel); `advance[i]` is the
    pen advance of character 32 + i in pixels; every glyph cell is `cell_w` x `line_h`.
    A 4x4 white block at the bottom-left corner is sampled by solid panels.
    """

    def __init__(self, size: int = 14) -> None:
        from PIL import Image, ImageDraw, ImageFont

        try:
            font = ImageFont.load_default(size=size)
        except TypeError:  # Pillow < 10.1: the fixed bitmap font
            font = ImageFont.load_default()
        chars = [chr(c) for c in range(_FIRST, _LAST + 1)]
        ascent, descent = font.getmetrics() if hasattr(font, "getmetrics") else (size, 3)
        self.line_h = int(ascent + descent + 2)
        self.pad = 2  # cells start `pad` px left of the pen: glyphs may overhang it
        widths = [font.getbbox(c)[2] for c in chars]
        self.cell_w = int(max(widths)) + 2 * self.pad
        cols = 16
        rows = (len(chars) + cols - 1) // cols + 1  # + 1 row for the white block
        image = Image.new("L", (cols * self.cell_w, rows * self.line_h), 0)
        draw = ImageDraw.Draw(image)
        for i, c in enumerate(chars):
            x, y = (i % cols) * self.cell_w, (i // cols) * self.line_h
            draw.text((x + self.pad, y + 1), c, fill=255, font=font)
        white_y = (rows - 1) * self.line_h
        draw.rectangle((0, white_y, 3, white_y + 3), fill=255)
        cov = np.asarray(image, dtype=np.uint8)
        self.pixels = np.repeat(cov[:, :, None], 4, axis=2)
        h, w = cov.shape
        self.advance = np.array([round(font.getlength(c)) for c in chars], dtype=np.float32)
        idx = np.arange(len(chars))
        self._u0 = (idx % cols) * self.cell_w / w
        self._v0 = (idx // cols) * self.line_h / h
        self._du, self._dv = self.cell_w / w, self.line_h / h
        self.white_uv = ((1.5 / w), (white_y + 1.5) / h)

    def _indices(self, text: str) -> np.ndarray:
        """Glyph indices (character - 32); newlines stay -22, other non-printables are '?'."""
        codes = np.frombuffer(text.encode("ascii", "replace"), dtype=np.uint8).astype(np.int64)
        codes[((codes < _FIRST) | (codes > _LAST)) & (codes != 10)] = ord("?")
        return codes - _FIRST

    def text_width(self, text: str) -> float:
        return float(self.advance[np.clip(self._indices(text), 0, None)].sum())

    def glyph_quads(self, x: float, y: float, lines: tuple[str, ...], color: tuple[float, ...],
                    scale: int) -> np.ndarray:
        """(6 * characters, 8) vertices for `lines`, the first with its top-left corner at
        (x, y); one vectorised pass for all lines."""
        text = "\n".join(lines)
        idx = self._indices(text)
        newline = idx == ord("\n") - _FIRST
        adv = np.where(newline, 0.0, self.advance[np.clip(idx, 0, _LAST - _FIRST)] * scale)
        row = np.concatenate(([0], np.cumsum(newline)[:-1]))
        total = np.concatenate(([0.0], np.cumsum(adv)[:-1]))
        # Pen position = advance so far minus the advance up to the start of this line.
        starts = np.concatenate(([0.0], total[1:][newline[:-1]]))
        keep = ~newline & (idx != 0)  # newlines and spaces draw nothing
        pen = x + total - starts[row]
        x0 = (pen - self.pad * scale)[keep]
        x1 = x0 + self.cell_w * scale
        y0 = (y + row * self.line_h * scale)[keep].astype(np.float64)
        y1 = y0 + self.line_h * scale
        gi = idx[keep]
        u0, v0 = self._u0[gi], self._v0[gi]
        return _quads(x0, y0, x1, y1, u0, v0, u0 + self._du, v0 + self._dv, color)

    def panel_quad(self, x0: float, y0: float, x1: float, y1: float,
                   color: tuple[float, ...]) -> np.ndarray:
        u, v = self.white_uv
        a = np.array
        return _quads(a([x0]), a([y0]), a([x1]), a([y1]), a([u]), a([v]), a([u]), a([v]), color)


def _quads(x0: np.ndarray, y0: np.ndarray, x1: np.ndarray, y1: np.ndarray, u0: np.ndarray,
           v0: np.ndarray, u1: np.ndarray, v1: np.ndarray, color: tuple[float, ...]) -> np.ndarray:
    n = len(x0)
    out = np.empty((n, 6, 8), dtype=np.float32)
    corners = ((x0, y0, u0, v0), (x1, y0, u1, v0), (x1, y1, u1, v1),
               (x0, y0, u0, v0), (x1, y1, u1, v1), (x0, y1, u0, v1))
    for k, (cx, cy, cu, cv) in enumerate(corners):
        out[:, k, 0], out[:, k, 1], out[:, k, 2], out[:, k, 3] = cx, cy, cu, cv
    out[:, :, 4:] = color
    return out.reshape(-1, 8)


@dataclass(frozen=True)
class TextBlock:
    """Lines of text anchored to a window corner: "top-left", "top-right", "bottom-left"."""

    lines: tuple[str, ...]
    corner: str = "top-left"
    color: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)


def hud_scale(size: tuple[int, int]) -> int:
    """Whole-number text scale: 1 up to ~1080p, 2 at 1440p-4K, more beyond."""
    return max(1, int(min(size[0] / 1280, size[1] / 720) + 0.25))


_PANEL = (0.0, 0.0, 0.0, 0.85)  # blended in linear light: 0.85 reads as a dark panel


def layout_blocks(font: FontAtlas, blocks: list[TextBlock], size: tuple[int, int]) -> np.ndarray:
    """All blocks as one (N, 8) float32 vertex array for a window of `size` pixels. A block
    laid out before for the same size is reused (the help panel never changes)."""
    parts = [_layout_block(font, b, size) for b in blocks if b.lines]
    if not parts:
        return np.zeros((0, 8), dtype=np.float32)
    return np.concatenate(parts)


_cache: dict[tuple, np.ndarray] = {}


def _layout_block(font: FontAtlas, block: TextBlock, size: tuple[int, int]) -> np.ndarray:
    key = (id(font), block, size)
    hit = _cache.get(key)
    if hit is not None:
        return hit
    s = hud_scale(size)
    margin, gap = 6 * s, 4 * s
    # A tab splits a line into two columns (the help panel's keys and what they do).
    cols = list(zip(*(line.split("\t", 1) if "\t" in line else (line, "") for line in block.lines),
                    strict=True))
    col_w = [max(font.text_width(t) for t in col) * s for col in cols]
    w = col_w[0] + (3 * gap + col_w[1] if any(cols[1]) else 0)
    h = len(block.lines) * font.line_h * s
    x = margin if block.corner.endswith("left") else size[0] - margin - w
    y = margin if block.corner.startswith("top") else size[1] - margin - h
    parts = [font.panel_quad(x - gap, y - gap, x + w + gap, y + h + gap, _PANEL),
             font.glyph_quads(x, y, cols[0], block.color, s)]
    if any(cols[1]):
        parts.append(font.glyph_quads(x + col_w[0] + 3 * gap, y, cols[1], block.color, s))
    out = np.concatenate(parts)
    if len(_cache) > 32:
        _cache.clear()
    _cache[key] = out
    return out
