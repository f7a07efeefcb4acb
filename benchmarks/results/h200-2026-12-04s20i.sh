# H200 run i (session 20): the GPU test pass on this session's code (tests/gpu, tests/unit,
# tests/distributed, the path policy's tests, import graph; 8 workers, validation on): the
# frame graph now makes a recording's kernels on threads, on every path.
# Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
HYPOTHESIS_PROFILE=report timeout -s INT 400 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/distributed tests/scene/test_resource_paths.py tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -30
