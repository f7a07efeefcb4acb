"""The suite's own layout: pytest imports test modules by basename (rootdir-relative
imports without packages), so two test files of one name in different folders stop the
whole run at collection. A fresh clone's CI found one; this keeps it from coming back."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

TESTS = Path(__file__).resolve().parent.parent


def test_test_module_basenames_are_unique() -> None:
    names = Counter(p.name for p in TESTS.rglob("test_*.py"))
    twice = sorted(n for n, k in names.items() if k > 1)
    assert not twice, f"test modules sharing a basename: {twice}"
