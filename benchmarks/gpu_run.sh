#!/usr/bin/env bash
# One device-tool run on the NVIDIA machine: unpack the carried loader/validation layer and
# wheels, then the benchmarks and the GPU test pass. Output files land in $OUT.
# Carry: .gl (debs), .whl (wheels), .assets (models in ../shared/assets' layout, Sponza's
# JPEGs re-encoded at quality 85), and optionally .before (`git archive <commit> src` of an
# earlier commit, benchmarked in the same run for before/after numbers).
# STEPS (default "paths env tests"): any of paths, env, bench, viewer, outputs, batch, ray,
# transmission, auto, ao, shadows, living, tests. SPONZA: the scene file (e.g. .assets-peers/models/...).
source benchmarks/gpu_env.sh
SPONZA=${SPONZA:-.assets/models/Sponza/glTF/Sponza.gltf}
STEPS=${STEPS:-paths env tests}
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
python3 -m vkpbr info | head -3
has() { [[ " $STEPS " == *" $1 "* ]]; }
if has paths; then
  echo "== frame paths x lighting: Sponza, GPU ms per step; cost per light"
  timeout ${PATHS_TIMEOUT:-300} python3 benchmarks/bench_paths.py --scene $SPONZA --frames ${FRAMES:-200} --json "$OUT/paths.json" 2>&1 | tee "$OUT/paths.txt"
fi
if has ao; then
  echo "== ambient occlusion (GTAO): Sponza frames and a 4,096-view 128x128 batch, on and off"
  timeout ${AO_TIMEOUT:-400} python3 benchmarks/bench_ao.py --scene $SPONZA --frames ${FRAMES:-200} --json "$OUT/ao.json" 2>&1 | tee "$OUT/ao.txt"
fi
if has shadows; then
  echo "== shadow maps: the raster units against compute shaders (Sponza 1080p: map ms, the walk with the sun, 100 moving nodes)"
  timeout ${SHADOWS_TIMEOUT:-500} python3 benchmarks/bench_shadows.py --scene $SPONZA --frames ${FRAMES:-300} --json "$OUT/shadows.json" 2>&1 | tee "$OUT/shadows.txt"
fi
if has living; then
  echo "== living scenes: set_poses, instances, Sponza with moving nodes, 2CylinderEngine, CesiumMan crowds"
  ASSETS=${ASSETS:-$(dirname "$(dirname "$(dirname "$SPONZA")")")}
  timeout ${LIVING_TIMEOUT:-540} python3 benchmarks/bench_living.py --assets "$ASSETS" --frames ${FRAMES:-300} --crowds 100,1000 --json "$OUT/living.json" 2>&1 | tee "$OUT/living.txt"
  if [ -d .before/src ]; then
    echo "== living scenes (before: .before; no instance rows)"
    PYTHONPATH=/tmp/site:$PWD/.before/src timeout ${LIVING_TIMEOUT:-540} python3 benchmarks/bench_living.py --assets "$ASSETS" --frames ${FRAMES:-300} --crowds 1000 --only poses,walk,crowd 2>&1 | tee "$OUT/living-before.txt"
  fi
fi
if has env; then
  echo "== environment pre-filter (2048x1024 panorama, the sky)"
  timeout 120 python3 benchmarks/bench_environment.py 2>&1 | tee "$OUT/env.txt"
fi
if has bench; then
  echo "== vkpbr bench (this commit)"
  python3 -m vkpbr bench --frames ${FRAMES:-200} --sponza $SPONZA 2>/dev/null
  if [ -d .before/src ]; then
    echo "== vkpbr bench (before: .before)"
    PYTHONPATH=/tmp/site:$PWD/.before/src python3 -m vkpbr bench --frames ${FRAMES:-200} --sponza $SPONZA 2>/dev/null
  fi
fi
if has viewer; then
  echo "== viewer loop, offscreen, Sponza 1920x1080, flying with the light animated"
  python3 -m vkpbr view $SPONZA --offscreen --size 1920x1080 --script benchmarks/viewer_fly.json
fi
if has outputs; then
  echo "== dataset outputs: the cost of each (Sponza 1920x1080)"
  timeout ${OUTPUTS_TIMEOUT:-200} python3 benchmarks/bench_outputs.py --scene $SPONZA --frames ${FRAMES:-50} --json "$OUT/outputs.json" 2>&1 | tee "$OUT/outputs.txt"
fi
if has batch; then
  echo "== batched views: render_batch into NumPy and torch (Sponza, DamagedHelmet; 128, 512)"
  timeout ${BATCH_TIMEOUT:-300} python3 benchmarks/bench_batch.py --pipeline "${PIPELINE:-auto}" --json "$OUT/batch.json" 2>&1 | tee "$OUT/batch.txt"
fi
if has ray; then
  echo "== Ray: 1, 2, 4 actors sharing the GPU; overhead against in-process rendering"
  [ "${RAY_ACTORS_TABLE:-1}" = 1 ] && timeout ${RAY_TIMEOUT:-300} python3 benchmarks/bench_ray.py 2>&1 | tee "$OUT/ray.txt"
  if [ -n "${RAY_MODELS:-}" ]; then  # the many-scenes job through `vkpbr batch`, 1, 2, 4 actors
    echo "== vkpbr batch: every model under $RAY_MODELS x ${RAY_VIEWS:-64} poses"
    mkdir -p /tmp/rayjob && (cd benchmarks && python3 ray_job.py "$PWD/../$RAY_MODELS" /tmp/rayjob/job.json --views ${RAY_VIEWS:-64})
    for cache in cold warm; do  # cold: each run bakes the scenes into a fresh bake cache
      for n in 1 2 4; do
        rm -rf /tmp/rayjob/out; [ $cache = cold ] && rm -rf /tmp/rayjob/cache
        echo "-- $n actor(s), num_gpus $(python3 -c "print(1 / $n)") each, $cache bake cache"
        VKPBR_CACHE_DIR=/tmp/rayjob/cache timeout ${RAY_TIMEOUT:-300} python3 -m vkpbr batch /tmp/rayjob/job.json \
          --actors $n --num-gpus $(python3 -c "print(1 / $n)") 2>&1 | grep -v WARNING | tail -2
      done
    done | tee "$OUT/ray-batch.txt"
  fi
fi
if has transmission; then
  echo "== screen-space transmission: Sponza with and without glass materials, GPU ms per step"
  timeout ${TRANSMISSION_TIMEOUT:-200} python3 benchmarks/bench_transmission.py --scene $SPONZA --frames ${FRAMES:-60} 2>&1 | tee "$OUT/transmission.txt"
fi
if has auto; then
  echo "== --pipeline auto: the first frame measures the frame paths (VKPBR_FRAME_PATHS=measure: a one-shot render otherwise takes the rule), the second reads the record"
  export VKPBR_CACHE_DIR=/tmp/vkpbr-auto; rm -rf $VKPBR_CACHE_DIR
  for i in 1 2; do
    t0=$(date +%s.%N)
    mode=$([ $i = 1 ] && echo measure || echo auto)
    VKPBR_FRAME_PATHS=$mode python3 -m vkpbr render $SPONZA --size 1920x1080 --pipeline auto --out /tmp/auto$i.png -v 2>&1 | grep -v "^$"
    echo "render $i wall: $(python3 -c "print(f'{$(date +%s.%N) - $t0:.3f}')") s"
  done
  cat $VKPBR_CACHE_DIR/frame-paths.json; python3 -m vkpbr info | grep -i autoFramePath; unset VKPBR_CACHE_DIR
fi
if has tests; then
  echo "== GPU test pass (validation on)"
  ASSETS=.assets; [ -d .assets-tests ] && ASSETS=.assets-tests  # models but Sponza, beside .whl-extra
  HYPOTHESIS_PROFILE=report VKPBR_ASSETS=$PWD/$ASSETS/models timeout ${TEST_TIMEOUT:-400} python3 -m pytest -q -p no:cacheprovider -rs tests/gpu tests/unit tests/test_import_graph.py > "$OUT/gpu-tests.log" 2>&1; tail -12 "$OUT/gpu-tests.log"
fi
