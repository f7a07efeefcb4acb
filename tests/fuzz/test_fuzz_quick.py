"""The fuzz suite's quick tier (issue 11): 60 seeded inputs of each of 12 formats (path tricks and codec payloads included) through
`load_scene`; every one must load or fail with vkpbr's one-line error naming the file
(tests/fuzzing.py). The long tier is `scripts/fuzz.sh N`."""

from __future__ import annotations

from pathlib import Path

import pytest
from fuzzing import fuzz, table


@pytest.mark.timeout(180)  # a hang on some input fails the tier
def test_quick_fuzz_tier(tmp_path: Path) -> None:
    counts, failures = fuzz(tmp_path, per_format=60)
    assert not failures, "\n".join(failures[:20]) + "\n" + table(counts)
    for name, c in counts.items():
        assert c["tried"] == 60, name
    # Mutations must reach both outcomes: a suite whose inputs all fail at the first byte
    # would test nothing past the parsers' front doors.
    assert sum(c["clean"] for c in counts.values()) > 300
    assert sum(c["loaded"] for c in counts.values()) > 50


def test_mutating_empty_bytes_gives_bytes() -> None:
    # A manifest line an earlier edit cut to nothing, mutated again (seed 4242 of the long
    # tier stopped the whole run there: randrange of an empty range).
    import random

    from fuzzing import mutate_bytes

    rng = random.Random(0)
    assert all(isinstance(mutate_bytes(b"", rng), bytes) for _ in range(200))
