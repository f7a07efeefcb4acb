# The GPU layer (src/vkpbr/gpu) knows Vulkan and nothing of the renderer (issue 30, item 7):
# it imports no vkpbr.render / vkpbr.app module and no string literal in it is a GLSL
# identifier the renderer declares (a block, a binding, an output image). Read with ast:
# nothing is imported, so the test also covers code behind lazy imports.

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from vkpbr.render import layouts as L

GPU = Path(__file__).resolve().parents[2] / "src" / "vkpbr" / "gpu"
FILES = sorted(GPU.glob("*.py"))


def glsl_identifiers() -> set[str]:
    """Every name render/layouts.py gives the shaders: blocks, compute-set bindings, outputs."""
    names = {name for _, _, name in L.COMPUTE_SET} | set(L.OUTPUT_IMAGES)
    names |= {b.name for b in L.BLOCKS} | {b.glsl_name for b in L.BLOCKS if hasattr(b, "glsl_name")}
    return names


def test_the_identifier_list_is_not_empty() -> None:
    # A renamed attribute in layouts.py must not make the check below vacuous.
    assert {"out_ids", "out_depth_range", "visibility", "Settings"} <= glsl_identifiers()


def docstrings(tree: ast.AST) -> set[int]:
    """id() of the docstring constants of a module and its classes and functions (prose may
    say who uses a helper; code may not name the renderer)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                out.add(id(body[0].value))
    return out


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_gpu_names_no_renderer(path: Path) -> None:
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    names = glsl_identifiers()
    prose = docstrings(tree)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import | ast.ImportFrom):
            modules = ([a.name for a in node.names] if isinstance(node, ast.Import)
                       else [node.module or ""])
            for m in modules:
                assert not m.startswith(("vkpbr.render", "vkpbr.app")), \
                    f"{path.name}:{node.lineno} imports {m}"
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            assert node.value not in names, \
                f"{path.name}:{node.lineno} names the GLSL identifier {node.value!r}"
        if isinstance(node, ast.Constant) and isinstance(node.value, str) \
                and id(node) not in prose and "render/" in node.value:
            pytest.fail(f"{path.name}:{node.lineno} names a render/ module: {node.value!r}")
