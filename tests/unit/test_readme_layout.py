"""The README's "Layout" section lists every module under src/vkpbr, and names none that is
gone (issue 30, item 8).

The rule, kept simple so that whoever adds a module knows what to write: the layout block is
the indented lines between "## Layout" and the next "## " heading; a module is listed when its
path relative to src/vkpbr/ (e.g. `scene/types.py`, `io.py`) is the first word of one of them.
Empty `__init__.py` files (package markers, no code) need no line."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "src" / "vkpbr"


def layout_block(readme: str) -> list[str]:
    """The indented lines of the README's Layout section."""
    section = readme.split("\n## Layout\n", 1)[1].split("\n## ", 1)[0]
    return [line for line in section.splitlines() if line.startswith("    ")]


def listed(block: list[str]) -> set[str]:
    """The first word of each line: the path the line is about."""
    return {line.split()[0] for line in block if line.strip()}


def modules() -> set[str]:
    """Every module file under src/vkpbr, as a path relative to it, less empty __init__.py."""
    return {p.relative_to(PACKAGE).as_posix() for p in PACKAGE.rglob("*.py")
            if not (p.name == "__init__.py" and not p.read_text(encoding="utf-8").strip())}


def test_the_rule_reads_the_block() -> None:
    readme = "# x\n## Layout\ntext\n\n    io.py   writers\n    scene/a.py  b\n\n## Next\n    c.py\n"
    assert listed(layout_block(readme)) == {"io.py", "scene/a.py"}
    assert len(modules()) > 90 and "scene/types.py" in modules() and "__init__.py" in modules()
    assert "app/__init__.py" not in modules()  # empty: a package marker


def test_every_module_is_in_the_readme_layout() -> None:
    names = listed(layout_block((ROOT / "README.md").read_text(encoding="utf-8")))
    missing = sorted(modules() - names)
    assert missing == [], f"README.md's Layout has no line for: {missing}"


def test_the_readme_layout_names_only_modules_that_exist() -> None:
    names = listed(layout_block((ROOT / "README.md").read_text(encoding="utf-8")))
    gone = sorted(n for n in names if re.fullmatch(r"[\w/]+\.py", n) and not (PACKAGE / n).is_file())
    assert gone == [], f"README.md's Layout names modules that do not exist: {gone}"
