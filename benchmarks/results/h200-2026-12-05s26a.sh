# H200 run a (session 26): render_many's frames collected by several threads side by side
# (render/frame_path.py COLLECTORS: 2 where there are 4 cores or more; before: 1). One tree,
# the collector count set before each benchmark (benchmarks/with_collectors.py; with 1 it
# is the tree before exactly),
# alternating 1, 2, 3 twice: probe_stream's walk, bench_shadows' walk (render_many),
# vkpbr bench's Sponza orbit. First the stream and frame-overlap tests (frames against
# render() with 1, 2 and 3 collectors); then set_poses' Python, and dataset outputs in
# batches (bench_batch_outputs.py: the compute batch's own outputs pass against the layered
# batch + view by view, the way before, in the same process). Carry .gl .whl .assets-peers.
source benchmarks/gpu_env.sh
S=$PWD/.assets-peers/models/Sponza/glTF/Sponza.gltf
export VKPBR_ASSETS=$PWD/.assets-peers/models
timeout 120 python3 -m pytest -q -n 4 -p no:cacheprovider -rfE --tb=short tests/gpu/test_stream.py tests/gpu/test_frame_overlap.py tests/gpu/test_batch_outputs.py > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR|E )|passed|failed" $OUT/tests.txt | cut -c1-300 | head -20
for i in 1 2; do
  for n in 1 2 3; do
    L=$OUT/c$n-$i.txt
    echo "## collectors $n ($i)" | tee $L
    timeout 80 python3 benchmarks/with_collectors.py $n benchmarks/probe_stream.py --scene $S --frames 600 --cameras walk >> $L 2>&1
    timeout 90 python3 benchmarks/with_collectors.py $n benchmarks/bench_shadows.py --scene $S --only walk --frames 600 >> $L 2>&1
    timeout 60 python3 benchmarks/with_collectors.py $n -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p >> $L 2>&1
    grep -E "^\| walk \| sun|^\| sponza" $L | cut -c1-150; grep -E "^\| walk \+" $L | cut -d'|' -f2-8
  done
done
timeout 60 python3 benchmarks/bench_living.py --assets $VKPBR_ASSETS --only poses > $OUT/poses.txt 2>&1
tail -8 $OUT/poses.txt
timeout 150 python3 benchmarks/bench_batch_outputs.py --scenes helmet,sponza --sizes 128x128 --batches 256,4096 > $OUT/batch-outputs.txt 2>&1
cat $OUT/batch-outputs.txt | tail -8
