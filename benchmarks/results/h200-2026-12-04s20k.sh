# H200 run k (session 20): the pipeline cache's tests on a driver that keeps pipelines (the
# merge, the save interval), then the warm job with saves only of new data at most every 5 s,
# twice, against the cold job once (each its own cache folder).
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
timeout -s INT 100 python3 -m pytest -q -p no:cacheprovider -rs tests/gpu/test_pipeline_cache.py tests/distributed/test_scenes_ahead.py 2>&1 | grep -E "^(FAILED|ERROR|SKIPPED)|passed|failed|^E  " | cut -c1-250 | head -20
rows() { grep -E "^\||not measured|failed|item's|processes;" | grep -v "^|---"; }
timeout 150 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs cold,warm --no-in-process --processes 6 --cache-dir /tmp/jc 2>&1 | rows
timeout 100 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs warm --no-in-process --processes 6 --cache-dir /tmp/jc --time-vk-calls /tmp/vkt 2>&1 | rows | head -9
