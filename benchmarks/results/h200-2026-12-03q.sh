# H200 run q (session 14): before (the pre-merge HEAD^1, .before8/src) / after (shadowbuf merged:
# compute-drawn maps read from the rasteriser's buffer, no copy). Carry .gl .whl .assets-peers .before8.
source benchmarks/gpu_env.sh
S=$PWD/.assets-peers/models/Sponza/glTF/Sponza.gltf; A=$PWD/.assets-peers/models
t() { timeout "$1" "${@:2}"; }
for round in 1 2; do for tree in before after; do
  run=""; [ $tree = before ] && run="env PYTHONPATH=/tmp/site:$PWD/.before8/src"
  t 50 $run python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p > $OUT/$tree-$round-bench.txt 2>&1
  [ $round = 1 ] && t 90 $run python3 benchmarks/bench_shadows.py --scene $S --frames 150 --steps > $OUT/$tree-walk.txt 2>&1
done; done
for f in $OUT/*.txt; do echo "== $f"; grep -E "^\||rror" $f | grep -v "^|---" | tail -12; done
