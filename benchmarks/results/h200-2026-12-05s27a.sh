# H200 run (session 27, for the next lease: none was lent in session 27): blended materials in
# the compute batch (AlphaBlendModeTest, 128x128, 256 and 4,096 views; the layered batch,
# auto's choice for such scenes before, in the same run), after the session's tests of them
# and of the renderer's bounds on what it keeps. Run session 26's h200-2026-12-05s26a.sh and
# s26b.sh (the GPU test pass) too. Carry .gl .whl .assets-peers (with AlphaBlendModeTest:
# benchmarks/fetch_device_carry.sh).
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-peers/models
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
timeout 120 python3 -m pytest -q -n 4 -p no:cacheprovider -rfE --tb=short tests/gpu/test_compute_batch.py tests/gpu/test_batch.py tests/gpu/test_leaks.py -k "blended or ever_new or many_sizes or recordings" > $OUT/tests27.txt 2>&1
grep -E "^(FAILED|ERROR|E )|passed|failed" $OUT/tests27.txt | cut -c1-300 | head -10
for p in forward compute forward compute; do
  timeout 120 python3 benchmarks/bench_batch.py --scenes alphablend --sizes 128x128 --batches 256,4096 --pipeline $p --many-max 0 >> $OUT/alphablend-$p.txt 2>&1
  grep -E "^\| alphablend" $OUT/alphablend-$p.txt | tail -2
done
