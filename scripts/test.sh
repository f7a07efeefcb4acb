#!/usr/bin/env bash
# Set up (scripts/setup.sh) and run the whole test suite on lavapipe with the Khronos
# validation layer on. Extra arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
# The tests install the codecs and ray extras as well (tests/distributed start a real
# local Ray cluster) and sample-viewer (tests/sample_viewer: Debian's headless Chromium and the
# Khronos glTF Sample Viewer from npm); a plain `scripts/setup.sh` stays lean.
export VKPBR_EXTRAS=${VKPBR_EXTRAS:-test,codecs,ray,sample-viewer}
bash scripts/setup.sh
.venv/bin/ruff check --quiet src tests benchmarks
# On every core, at most 4 (pytest-xdist; tests/conftest.py keeps each module, and the
# folders that share a machine-wide thing, in one worker): on a 2-core machine, 2 workers.
# VKPBR_TEST_WORKERS=0: one process, no workers.
cores=$(nproc 2>/dev/null || echo 1)
workers=${VKPBR_TEST_WORKERS:-$(( cores < 4 ? cores : 4 ))}
exec .venv/bin/python -m pytest -q -n "$workers" "$@"
