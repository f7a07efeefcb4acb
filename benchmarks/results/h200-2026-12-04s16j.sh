# H200 run j (session 16's last tree): the GPU test pass on 8 workers (tests/gpu, tests/unit,
# the import graph), validation on. Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
HYPOTHESIS_PROFILE=report VKPBR_ASSETS=$PWD/.assets-final/models timeout -s INT 150 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -30
