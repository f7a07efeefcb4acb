# H200 run g (session 20): this session's GPU-layer tests with validation on (pipeline cache
# merge, kept handles made on threads, kept memory, the frame graph's kernels, the scene
# swap and AO and compute-path tests that build kernels at once); then the 100-scene job,
# warm, 6 processes, alternating the tree at 03c5be2 (.before2's files) and this one, each
# tree with its own cache folder filled by a run of its own first.
# Carry .gl .whl .assets-final .before2.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
timeout -s INT 200 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu/test_pipeline_cache.py tests/gpu/test_kept.py tests/gpu/test_memory.py tests/unit/test_frame_graph.py tests/gpu/test_scene_swap.py tests/gpu/test_ao.py tests/gpu/test_compute_path.py 2>&1 | grep -E "^(FAILED|ERROR)|passed|failed|^E  " | cut -c1-300 | head -30
rows() { grep -E "^\||not measured|failed|item's|processes;" | grep -v "^|---"; }
mkdir -p /tmp/old && cp -r src /tmp/old/ && cp -r .before2/src /tmp/old/
python3 -m compileall -q -j 0 /tmp/old/src > /dev/null 2>&1
job() { PYTHONPATH=/tmp/site:$1 timeout 100 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs warm --no-in-process --processes 6 --cache-dir /tmp/cache-$2 2>&1; }
job /tmp/old/src old > /dev/null; job $PWD/src new > /dev/null  # (each tree's caches filled)
for t in old new old new; do
  [ $t = old ] && P=/tmp/old/src || P=$PWD/src
  echo "== $t"; job $P $t | rows | grep -v "^| run"
done
ls -la /tmp/cache-old /tmp/cache-new | grep pipelines
