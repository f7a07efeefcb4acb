#!/usr/bin/env bash
# Device-tool runs for batched views (issue 14): vkpbr's render_batch beside SAPIEN, pygfx and
# pyrender on the same poses, and vkpbr's batch table. The 64 MiB carry does not hold SAPIEN
# beside the others, and one command has 10 minutes, so three calls (BENCHMARKS.md, "Batched
# views", has them verbatim):
#   STEP=sapien  carry .whl-sapien .gl-peers .assets-peers: SAPIEN alone (run_peers.sh, both
#                modes), rows in $OUT/peers.json: copy it back here as out/sapien-peers.json.
#   STEP=peers   carry .gl .whl .whl-peers .gl-peers .assets-peers out/sapien-peers.json:
#                `vkpbr bench --batch --peers` (pyrender and pygfx live, SAPIEN's rows read back).
#   STEP=table   carry .gl .whl .assets-peers: benchmarks/bench_batch.py (PIPELINE=compute: the
#                compute batch; B = 1..4096, into
#                NumPy and torch, render_many, host us/view, GPU MiB).
# .assets-peers/models holds Sponza (JPEGs at quality 85, as .assets) and DamagedHelmet only.
# VIEWS (poses per scene, default 128) must be the same in the sapien and peers steps.
set -uo pipefail
STEP=${STEP:-peers}
export VKPBR_ASSETS=$PWD/.assets-peers/models
SPONZA=$VKPBR_ASSETS/Sponza/glTF/Sponza.gltf
VIEWS=${VIEWS:-128}
if [ "$STEP" = sapien ]; then
  PEERS=sapien SCENARIOS=batch VIEWS=$VIEWS RUN_TIMEOUT=${RUN_TIMEOUT:-70} bash benchmarks/peers/run_peers.sh
  exit
fi
source benchmarks/gpu_env.sh  # .gl, .whl -> /tmp/site; PYTHONPATH; the NVIDIA ICD
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
if [ "$STEP" = table ]; then
  timeout ${BATCH_TIMEOUT:-540} python3 benchmarks/bench_batch.py --pipeline "${PIPELINE:-auto}" --json "$OUT/batch.json" 2>&1 | tee "$OUT/batch.txt"
  exit
fi
source benchmarks/peers_env.sh  # .gl-peers, .whl-peers -> /tmp/peers; PYTHONPATH, EGL
extra=()
[ -f out/sapien-peers.json ] && extra=(--peers-json out/sapien-peers.json)
echo "== vkpbr bench --batch --peers: $VIEWS poses, ${BATCH_VIEWS:-1024} views a call"
timeout ${BENCH_TIMEOUT:-560} python3 -m vkpbr bench --batch --sponza "$SPONZA" --views "$VIEWS" \
  --batch-views "${BATCH_VIEWS:-1024}" --frames "${FRAMES:-4096}" --poses-dir /tmp/bench-poses \
  --peer-timeout 120 --peers "${extra[@]}" 2> "$OUT/bench.err" | tee "$OUT/bench.txt"
tail -8 "$OUT/bench.err"
