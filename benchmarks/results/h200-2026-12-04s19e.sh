# H200 run e (session 19): the host's cores (threads a core), then the GPU test pass
# (tests/gpu, tests/unit, tests/distributed with the renderer-process tests, the path policy's
# tests, import graph; 8 workers, validation on).
# Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
lscpu | grep -E "^(Model name|Thread|Core|Socket|CPU\(s\))"
HYPOTHESIS_PROFILE=report timeout -s INT 330 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/distributed tests/scene/test_resource_paths.py tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -30
