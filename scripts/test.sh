#!/usr/bin/env bash
# Set up (scripts/setup.sh) and run the whole test suite on lavapipe with the Khronos
# validation layer on. Extra arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
export VKPBR_EXTRAS=${VKPBR_EXTRAS:-test,codecs}
bash scripts/setup.sh
.venv/bin/ruff check --quiet src tests benchmarks
exec .venv/bin/python -m pytest -q "$@"
