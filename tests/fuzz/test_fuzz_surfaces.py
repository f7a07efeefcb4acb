"""The fuzz suite's quick tier for the surfaces besides scene files (issue 35): lights files,
semantic mappings, poses files, job files, manifests in an out folder, environment files
(40 cases each) and command lines of every subcommand (30); each must be accepted or end in
vkpbr's one-line error naming the file (tests/fuzz_surfaces.py). The long tier is
`scripts/fuzz.sh N`, which runs these after the scene formats."""

from __future__ import annotations

from pathlib import Path

import pytest
from fuzz_surfaces import SURFACES
from fuzzing import fuzz_surfaces, table

CLI = "command lines (every subcommand)"


@pytest.mark.timeout(300)  # a hang on some input fails the tier
def test_quick_surface_tier(tmp_path: Path) -> None:
    per = {name: 30 if name == CLI else 40 for name in SURFACES}
    counts, failures = fuzz_surfaces(tmp_path, per, seed=35)
    assert not failures, "\n".join(failures[:20]) + "\n" + table(counts)
    for name, c in counts.items():
        assert c["tried"] == per[name], name
        # Both outcomes on every surface: mutations that never got past the front door (or
        # never reached it) would test nothing.
        assert c["clean"] >= 5 and c["loaded"] >= 1, (name, dict(c))
