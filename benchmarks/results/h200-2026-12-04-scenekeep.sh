# H200 run (session 15, branch scenekeep, issue 32): a new scene on the same Renderer, before
# and after keeping what depends on no scene across set_scene (gpu/kept.py: layouts,
# pipelines, samplers; render/parts.py DeviceParts: frame ring and slots, environments,
# shadow map images, offscreen targets, compute-batch atlases).
# Before = main without the branch (b1433b1 when written; after merging, the merge's first
# parent), made next to this tree first:
#   rm -rf .before2 && mkdir .before2 && git archive b1433b1 src benchmarks tests/assets_path.py | tar -x -C .before2
# Carry .gl .whl .assets-final .before2. About 5 min (at most 9.7 with every timeout): the
# 100-scene job once per tree (bench_load.py, about 2 min each), then bench_scene_swap.py
# twice per tree, interleaved (a few s each; the before tree runs this tree's script).
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
t() { timeout "$1" "${@:2}"; }
B="env PYTHONPATH=/tmp/site:$PWD/.before2/src"
for tree in before after; do
  if [ $tree = before ]; then cd .before2; run=$B; else run=""; fi
  echo "== job ($tree)"
  t 150 $run python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | grep -E "^\||per model" | grep -v "^|---"
  [ $tree = before ] && cd - >/dev/null
done
echo "== one Renderer, set_scene over the models (bench_scene_swap.py: 16 views at 256x256 a scene)"
for round in 1 2; do for tree in before after; do
  if [ $tree = before ]; then run=$B; else run=""; fi
  h=""; [ $round = 1 ] && [ $tree = before ] && h=--header
  t 60 $run python3 benchmarks/bench_scene_swap.py --models $A --count 17 --rounds 2 --views 16 --size 256x256 --label "$tree $round" $h 2>&1 | grep -E "^\||rror" | grep -v "^|---"
done; done
echo "== tests"; VKPBR_ASSETS=$A timeout -s INT 45 python3 -m pytest -q -p no:cacheprovider --tb=line tests/gpu/test_scene_swap.py tests/gpu/test_pipeline_cache.py tests/gpu/test_leaks.py 2>&1 | grep -E "^E |Error|passed|failed" | head -12
