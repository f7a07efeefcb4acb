# The shape of render/ (issue 30, item 6), read with ast: nothing is imported.
#
# `Renderer` (render/renderer.py) is a facade: its concerns are modules of render/ given what
# they need (render/parts.py makes them), so the rule is one-way. render/renderer.py is the
# package's public surface: vkpbr/__init__.py and the layers above render/ (app/,
# distributed/, display.py; benchmarks, examples, tests) import it, and no module under
# render/ does, in any form (module level, inside a function, under TYPE_CHECKING), nor
# stands in for it with a `Renderer = Any` alias. renderer.py stays small (MAX_RENDERER_LINES)
# and no function under render/ grows past MAX_FUNCTION_LINES.

from __future__ import annotations

import ast
from pathlib import Path

RENDER = Path(__file__).resolve().parents[2] / "src" / "vkpbr" / "render"
RENDERER = RENDER / "renderer.py"
MAX_RENDERER_LINES = 300
MAX_FUNCTION_LINES = 60  # from its first decorator or `def` to its last line, docstring included


def render_modules() -> list[Path]:
    return sorted(RENDER.rglob("*.py"))


def function_lengths(path: Path) -> list[tuple[int, str]]:
    """(lines, "file:line name") of every function and method in `path`, nested ones too."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            first = min([node.lineno] + [d.lineno for d in node.decorator_list])
            out.append((node.end_lineno - first + 1, f"{path.name}:{node.lineno} {node.name}"))
    return out


def imports_renderer(path: Path) -> list[str]:
    """How `path` imports vkpbr.render.renderer, if it does (every import statement)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [a.name for a in node.names if a.name.startswith("vkpbr.render.renderer")]
        elif isinstance(node, ast.ImportFrom):
            module = node.module or ""
            names = {a.name for a in node.names}
            if module.startswith("vkpbr.render.renderer") or (
                    module == "vkpbr.render" and "renderer" in names) or (
                    node.level == 1 and (module == "renderer" or (not module and "renderer" in names))):
                found.append(f"from {'.' * node.level}{module} import {', '.join(sorted(names))}")
    return found


def renderer_aliases(path: Path) -> list[str]:
    """Module-level names `Renderer` bound in `path` by an assignment (`Renderer = Any`)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    out = []
    for node in ast.walk(tree):
        targets = (node.targets if isinstance(node, ast.Assign) else
                   [node.target] if isinstance(node, ast.AnnAssign | ast.AugAssign) else [])
        out += [f"{path.name}:{node.lineno}" for t in targets
                if isinstance(t, ast.Name) and t.id == "Renderer"]
    return out


def test_the_checks_find_what_they_look_for(tmp_path: Path) -> None:
    """The checkers themselves, on a file of every form they must catch."""
    probe = tmp_path / "probe.py"
    probe.write_text("from typing import Any\nRenderer = Any\n"
                     "def f():\n    from vkpbr.render.renderer import Renderer\n"
                     "    from . import renderer\n    import vkpbr.render.renderer\n"
                     "    from vkpbr.render import renderer as r\n" + "    x = 1\n" * 60,
                     encoding="utf-8")
    assert renderer_aliases(probe) == ["probe.py:2"]
    assert len(imports_renderer(probe)) == 4
    assert function_lengths(probe) == [(65, "probe.py:3 f")]


def test_renderer_is_small() -> None:
    lines = len(RENDERER.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_RENDERER_LINES, \
        f"render/renderer.py has {lines} lines: move a concern into its own module"


def test_no_long_functions_in_render() -> None:
    long = sorted((n, where) for path in render_modules() for n, where in function_lengths(path)
                  if n > MAX_FUNCTION_LINES)
    assert long == [], f"functions over {MAX_FUNCTION_LINES} lines: {long}"


def test_render_modules_do_not_reach_back_into_the_renderer() -> None:
    bad = {p.name: imports_renderer(p) + renderer_aliases(p)
           for p in render_modules() if p != RENDERER}
    assert {k: v for k, v in bad.items() if v} == {}, \
        "render/ modules are given what they need: none imports render/renderer.py or aliases Renderer"
