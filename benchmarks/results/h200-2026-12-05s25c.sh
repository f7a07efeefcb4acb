# H200 run c (session 25): frames that overlap the one before's readback copy (this tree,
# branch `overlap` merged: gpu/graph.py's first uses wait for every stage but copies, the
# compute path's early clears are kernels) against the tree before (40bb7ba, carried as
# .old/src: `git archive 40bb7ba src | tar -x -C .old`),
# alternating twice: probe_stream's walk, bench_shadows' walk (render_many), vkpbr bench's
# Sponza orbit. First the stream and frame-path tests on the new tree (frames in flight
# against render()). Carry .gl .whl .assets-s .old.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
NEW=$PYTHONPATH; OLD=/tmp/site:$PWD/.old/src
export VKPBR_ASSETS=$PWD/.assets-s/models
PYTHONPATH=$NEW timeout 120 python3 -m pytest -q -n 4 -p no:cacheprovider -rfE --tb=short tests/gpu/test_frame_overlap.py tests/gpu/test_stream.py tests/gpu/test_frame_sequences.py tests/gpu/test_shadow_raster.py > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR|E )|passed|failed" $OUT/tests.txt | cut -c1-300 | head -20
for i in 1 2; do
  for tree in old new; do
    if [ $tree = old ]; then export PYTHONPATH=$OLD; else export PYTHONPATH=$NEW; fi
    L=$OUT/$tree$i.txt
    echo "## $tree ($i)" | tee $L
    timeout 80 python3 benchmarks/probe_stream.py --scene $S --frames 600 --cameras walk >> $L 2>&1
    timeout 90 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 600 >> $L 2>&1
    timeout 60 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p >> $L 2>&1
    grep -E "^\| walk \| sun|^\| sponza" $L | cut -c1-150; grep -E "^\| walk \+" $L | cut -d'|' -f2-8
  done
done
