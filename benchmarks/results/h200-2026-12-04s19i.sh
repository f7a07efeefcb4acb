# H200 run i (session 19): the tests that failed in run e or changed since (tests/distributed
# with the renderer-process tests, the import graph, the README's layout), 8 workers,
# validation on.
# Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-final/models
timeout -s INT 200 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/distributed tests/test_import_graph.py tests/unit/test_readme_layout.py 2>&1 | grep -E "^(FAILED|ERROR)|passed|failed|^E  " | cut -c1-300 | head -30
