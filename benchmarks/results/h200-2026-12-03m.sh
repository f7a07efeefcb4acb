# H200 run m (session 14): before/after of the shadow kernels' work split (shadow_small a work
# group a chunk of one caster row; shadow_big a subgroup a band). Carry .gl .whl .assets-peers
# .before5 (git archive 5dfe6d5: src, bench_paths/bench_shadows/peers/common.py, tests/assets_path.py,
# and this tree's bench_living.py for --shadow-steps). About 420 s.
source benchmarks/gpu_env.sh
S=$PWD/.assets-peers/models/Sponza/glTF/Sponza.gltf; A=$PWD/.assets-peers/models
t() { timeout "$1" "${@:2}"; }
for round in 1 2; do for tree in before after; do
  if [ $tree = before ]; then cd .before5; run="env PYTHONPATH=/tmp/site:$PWD/src"; else run=""; fi
  t 70 $run python3 benchmarks/bench_shadows.py --scene $S --only maps --steps --frames 60 > $OUT/$tree-$round-shadows.txt 2>&1
  [ $round = 1 ] && t 100 $run python3 benchmarks/bench_living.py --assets $A --only crowd --crowds 1000 --frames 90 --shadow-steps > $OUT/$tree-crowd.txt 2>&1
  [ $round = 1 ] && t 50 $run python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p > $OUT/$tree-bench.txt 2>&1
  [ $tree = before ] && cd - >/dev/null
done; done
t 40 python3 benchmarks/probe_kernels.py --scene $A/CesiumMan/glTF/CesiumMan.gltf --others > $OUT/kernels.txt 2>&1
VKPBR_ASSETS=$A timeout -s INT 90 python3 -m pytest -q -x -p no:cacheprovider tests/gpu/test_shadow_raster.py tests/gpu/test_world_shadows.py tests/gpu/test_compute_raster.py > $OUT/tests.log 2>&1
for f in $OUT/*.txt; do echo "== $f"; grep -E "^\||rror" $f | tail -12; done
tail -4 $OUT/tests.log
