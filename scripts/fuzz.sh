#!/usr/bin/env bash
# The fuzz suite's long tier (issue 11): N seeded inputs (default 20000) spread over every
# input format (path tricks included), through load_scene; prints one table per format (tried,
# clean errors, loaded, unclean) and the first unclean cases. Exit status 1 when any input was
# unclean. It fuzzes this checkout's src/ (PYTHONPATH), with $PYTHON or .venv/bin/python.
#   bash scripts/fuzz.sh [N] [SEED]
set -euo pipefail
cd "$(dirname "$0")/.."
export PYTHONPATH="$PWD/src:$PWD/tests${PYTHONPATH:+:$PYTHONPATH}"
exec "${PYTHON:-.venv/bin/python}" tests/fuzzing.py "${1:-20000}" "${2:-1111}"
