# H200 run c (session 22): the streamed walk before (.old/src: run b's tree, git archive of
# 3a375f5) and after (the working tree: recordings through the C entry points, frames
# collected on the stream's thread), alternating in one lease: probe_stream's walk rows,
# bench_shadows' walk rows, vkpbr bench's Sponza rows; then the GPU tests nearest to it.
# Carry .gl .whl .assets-s .old.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
NEW=$PYTHONPATH; OLD=/tmp/site:$PWD/.old/src
rows() { grep -E "^\|" | grep -v "^|---"; }
for i in 1 2; do
  for tree in old new; do
    if [ $tree = old ]; then export PYTHONPATH=$OLD; else export PYTHONPATH=$NEW; fi
    echo "## $tree ($i)"
    timeout 100 python3 benchmarks/probe_stream.py --scene $S --frames 600 --cameras walk > $OUT/probe-$tree$i.txt 2>&1; grep -E "^\| walk" $OUT/probe-$tree$i.txt
    timeout 120 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 600 > $OUT/walk-$tree$i.txt 2>&1; grep -E "^\| walk" $OUT/walk-$tree$i.txt | cut -d'|' -f2-7
    timeout 60 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p > $OUT/bench-$tree$i.txt 2>&1; rows < $OUT/bench-$tree$i.txt | tail -2
  done
done
export PYTHONPATH=$NEW VKPBR_ASSETS=$PWD/.assets-s/models
timeout 200 python3 -m pytest -q -n 12 -p no:cacheprovider -rfE --tb=short tests/gpu/test_stream.py tests/gpu/test_shadow_raster.py tests/gpu/test_shadow_cache.py tests/gpu/test_shadows.py tests/gpu/test_frame_path.py tests/gpu/test_compute_path.py tests/gpu/test_leaks.py tests/gpu/test_worlds_cuda.py tests/gpu/test_views.py tests/unit > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR)|passed|failed" $OUT/tests.txt | cut -c1-200 | head -20
