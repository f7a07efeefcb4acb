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
exec .venv/bin/python -m pytest -q "$@"
