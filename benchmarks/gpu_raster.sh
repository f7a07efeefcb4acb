#!/usr/bin/env bash
# One device-tool run for the compute rasteriser (issue 13): bench_paths' frame rows (GPU ms
# per pass) for this checkout and for .before (`git archive <commit> src`, unpacked), then the
# compute-raster GPU tests. Carry .gl .whl .assets-peers .before.
source benchmarks/gpu_env.sh
SPONZA=.assets-peers/models/Sponza/glTF/Sponza.gltf
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
for which in now before; do
  [ $which = before ] && { [ -d .before/src ] || continue; export PYTHONPATH=/tmp/site:$PWD/.before/src; }
  echo "== bench_paths ($which)"
  timeout ${PATHS_TIMEOUT:-150} python3 benchmarks/bench_paths.py --scene $SPONZA --frames ${FRAMES:-60} \
    --sizes ${SIZES:-1920x1080,640x480,128x128} --lights 1 --json "$OUT/paths-$which.json" 2>&1 | tee "$OUT/paths-$which.txt"
done
unset PYTHONPATH; source benchmarks/gpu_env.sh
echo "== compute-raster GPU tests"
timeout ${TEST_TIMEOUT:-120} python3 -m pytest -q -p no:cacheprovider tests/gpu/test_compute_raster.py \
  tests/gpu/test_compute_batch.py > "$OUT/raster-tests.log" 2>&1; tail -4 "$OUT/raster-tests.log"
