# H200 run p (session 14): before (9895400, .before7/src) / after (HEAD) of shadow_masked's barycentrics and shadow_big's stored set-up (after run o's
# changes); the same benchmark scripts (unchanged between
# the two) run with each tree's src on PYTHONPATH. Carry .gl .whl .assets-peers .before7.
source benchmarks/gpu_env.sh
S=$PWD/.assets-peers/models/Sponza/glTF/Sponza.gltf; A=$PWD/.assets-peers/models
t() { timeout "$1" "${@:2}"; }
for round in 1 2; do for tree in before after; do
  run=""; [ $tree = before ] && run="env PYTHONPATH=/tmp/site:$PWD/.before7/src"
  t 70 $run python3 benchmarks/bench_shadows.py --scene $S --only maps --steps --frames 60 > $OUT/$tree-$round-shadows.txt 2>&1
  [ $round = 1 ] && t 100 $run python3 benchmarks/bench_living.py --assets $A --only crowd --crowds 1000 --frames 90 --shadow-steps > $OUT/$tree-crowd.txt 2>&1
  [ $round = 1 ] && t 50 $run python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p > $OUT/$tree-bench.txt 2>&1
  [ $round = 1 ] && t 90 $run python3 benchmarks/bench_world_batches.py --assets $A --rows helmet-64 --worlds 8192 --steps 10 --shadows on > $OUT/$tree-helmet.txt 2>&1
done; done
t 90 python3 benchmarks/bench_shadows.py --scene $S --frames 150 > $OUT/after-walk.txt 2>&1
VKPBR_ASSETS=$A timeout -s INT 120 python3 -m pytest -q -x -p no:cacheprovider tests/gpu/test_shadow_raster.py tests/gpu/test_world_shadows.py tests/gpu/test_compute_raster.py tests/gpu/test_shadows.py > $OUT/tests.log 2>&1
for f in $OUT/*.txt; do echo "== $f"; grep -E "^\||rror" $f | grep -v "^|---" | tail -6; done
tail -3 $OUT/tests.log
