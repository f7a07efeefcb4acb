#!/usr/bin/env bash
# The fuzz suite's long tier (issues 11 and 35): N seeded inputs (default 20000) spread evenly
# over every scene format (path tricks included, through load_scene) and every other surface
# (lights files, semantic mappings, poses files, job files, manifests in an out folder,
# environment files, command lines of every subcommand: tests/fuzz_surfaces.py); prints one
# row each (tried, clean errors, loaded or accepted, unclean, seconds) and the first unclean
# cases. Exit status 1 when any input was unclean. It fuzzes this checkout's src/
# (PYTHONPATH), with $PYTHON or .venv/bin/python. NAMES: only the rows starting so.
#   bash scripts/fuzz.sh [N] [SEED] [NAME...]      e.g. bash scripts/fuzz.sh 2000 1 "command"
set -euo pipefail
cd "$(dirname "$0")/.."
export PYTHONPATH="$PWD/src:$PWD/tests${PYTHONPATH:+:$PYTHONPATH}"
exec "${PYTHON:-.venv/bin/python}" tests/fuzzing.py "${1:-20000}" "${2:-1111}" "${@:3}"
