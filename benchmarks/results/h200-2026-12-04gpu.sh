# H200 GPU test pass (session 15): tests/gpu, tests/unit and the import graph with the
# validation layer, on 8 workers (pytest-xdist from .whl), the sample models of .assets-final.
source benchmarks/gpu_env.sh
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
HYPOTHESIS_PROFILE=report VKPBR_ASSETS=$PWD/.assets-final/models timeout -s INT 520 python3 -m pytest -q -n ${WORKERS:-8} -p no:cacheprovider -rfEs --tb=line --durations=15 tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  |^/.*Error" $OUT/gpu-tests.log | head -60
grep -E "^SKIPPED" $OUT/gpu-tests.log | cut -c1-160 | head -30
