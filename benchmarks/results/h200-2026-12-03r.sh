# H200 run r (session 14): before (.before8/src: a145280^1, before the shadow buffer read) /
# after (HEAD: the buffer read chosen per frame, 4x4 by-hand PCF; load3's load-ahead merged).
# Carry .gl .whl .assets-peers .before8.
source benchmarks/gpu_env.sh
S=$PWD/.assets-peers/models/Sponza/glTF/Sponza.gltf; A=$PWD/.assets-peers/models
t() { timeout "$1" "${@:2}"; }
for round in 1 2; do for tree in before after; do
  run=""; [ $tree = before ] && run="env PYTHONPATH=/tmp/site:$PWD/.before8/src"
  t 50 $run python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p > $OUT/$tree-$round-bench.txt 2>&1
  [ $round = 1 ] && t 90 $run python3 benchmarks/bench_shadows.py --scene $S --frames 150 --steps > $OUT/$tree-walk.txt 2>&1
done; done
t 60 python3 benchmarks/bench_load.py --scene $S --no-job > $OUT/after-load.txt 2>&1
t 60 python3 benchmarks/bench_load.py --scene $S --no-job --serial > $OUT/after-load-serial.txt 2>&1
VKPBR_ASSETS=$A timeout -s INT 100 python3 -m pytest -q -x -p no:cacheprovider tests/gpu/test_shadow_raster.py tests/gpu/test_shadow_cache.py tests/gpu/test_world_shadows.py tests/gpu/test_load_ahead.py tests/gpu/test_uploads.py > $OUT/tests.log 2>&1
for f in $OUT/*.txt; do echo "== $f"; grep -E "^\||rror" $f | grep -v "^|---" | tail -14; done
tail -3 $OUT/tests.log
