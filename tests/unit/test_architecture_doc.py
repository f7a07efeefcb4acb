# docs/architecture.md draws each frame path's steps; its generated part must be what
# render/paths.py declares now (issue 30, item 8: a map that stays true).

from __future__ import annotations

from pathlib import Path

from vkpbr.render.paths import COPY_PATHS, GENERATED_BEGIN, GENERATED_END, PATHS, architecture_text
from vkpbr.render.steps import FrameSteps

DOC = Path(__file__).resolve().parents[2] / "docs" / "architecture.md"


def test_the_generated_part_is_current() -> None:
    text = DOC.read_text(encoding="utf-8")
    start, end = text.index(GENERATED_BEGIN), text.index(GENERATED_END) + len(GENERATED_END)
    assert text[start:end] + "\n" == architecture_text(), \
        "docs/architecture.md is stale: regenerate it with python -m vkpbr.render.paths"


def test_every_declared_group_has_a_maker() -> None:
    # A group no FrameSteps method makes would fail only when a frame takes that path.
    from vkpbr.render.passes import PASSES

    passes = {p.name for p in PASSES}
    caller_made = {"cull", "chunks"}  # the layered batch's own (render/batch.py)
    for groups in PATHS.values():
        for g in groups:
            assert g in passes or g in caller_made or hasattr(FrameSteps, "_" + g), g
    assert COPY_PATHS["forward"][-1] == COPY_PATHS["compute"][-1] == "mips"
