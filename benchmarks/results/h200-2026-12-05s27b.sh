# H200 run b (session 27): session 26's run a (h200-2026-12-05s26a.sh, never lent) in three
# output files: the stream, frame-overlap and batch-outputs tests; render_many's collectors
# (render/frame_path.py COLLECTORS) 1, 2, 3 alternating twice on probe_stream's walk,
# bench_shadows' walk and vkpbr bench's Sponza orbit; set_poses' Python, the batch outputs
# (bench_batch_outputs.py) and blended materials in the compute batch against the layered
# batch (bench_batch.py --scenes alphablend). Carry .gl .whl .assets-peers (with
# AlphaBlendModeTest: benchmarks/fetch_device_carry.sh).
source benchmarks/gpu_env.sh
S=$PWD/.assets-peers/models/Sponza/glTF/Sponza.gltf
export VKPBR_ASSETS=$PWD/.assets-peers/models
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
timeout 100 python3 -m pytest -q -n 4 -p no:cacheprovider -rfE --tb=short tests/gpu/test_stream.py tests/gpu/test_frame_overlap.py tests/gpu/test_batch_outputs.py > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR|E )|passed|failed" $OUT/tests.txt | cut -c1-300 | head -20
L=$OUT/collectors.txt
for i in 1 2; do
  for n in 1 2 3; do
    echo "## collectors $n ($i)" | tee -a $L
    timeout 45 python3 benchmarks/with_collectors.py $n benchmarks/probe_stream.py --scene $S --frames 600 --cameras walk > /tmp/one.txt 2>&1
    timeout 60 python3 benchmarks/with_collectors.py $n benchmarks/bench_shadows.py --scene $S --only walk --frames 600 >> /tmp/one.txt 2>&1
    timeout 40 python3 benchmarks/with_collectors.py $n -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p >> /tmp/one.txt 2>&1
    cat /tmp/one.txt >> $L
    grep -E "^\| walk \| sun|^\| sponza" /tmp/one.txt | cut -c1-150; grep -E "^\| walk \+" /tmp/one.txt | cut -d'|' -f2-8
  done
done
B=$OUT/bench.txt
timeout 50 python3 benchmarks/bench_living.py --assets $VKPBR_ASSETS --only poses > /tmp/one.txt 2>&1; cat /tmp/one.txt >> $B; tail -6 /tmp/one.txt
timeout 100 python3 benchmarks/bench_batch_outputs.py --scenes helmet,sponza --sizes 128x128 --batches 256,4096 > /tmp/one.txt 2>&1; cat /tmp/one.txt >> $B; tail -8 /tmp/one.txt
for p in forward compute; do
  timeout 60 python3 benchmarks/bench_batch.py --scenes alphablend --sizes 128x128 --batches 256,4096 --pipeline $p --many-max 0 > /tmp/one.txt 2>&1; cat /tmp/one.txt >> $B
  grep -E "^\| alphablend" /tmp/one.txt
done
