#!/usr/bin/env bash
# The worlds benchmark (issue 32, must-have 4) on the offline NVIDIA machine: vkpbr beside
# SAPIEN, MuJoCo Warp and mujoco-warp-pbr on the tabletop worlds (benchmarks/tabletop.py), the
# same poses (tabletop.Motion, one seed), the same pixels. cwd = repo root; results in $OUT:
# worlds.json (one JSON line a row: worlds_common.py), worlds-<STEP>.log, gallery-<STEP>.png
# (world 0 of each renderer, side by side, at the first size and W).
#
# The 64 MiB carry does not hold SAPIEN beside the MuJoCo Warp tree, so three calls, back to
# back (the machine stays warm 30 s; BENCHMARKS.md / docs/batch.md have them verbatim):
#   STEP=sapien  carry .gl .whl .whl-sapien .assets-worlds: vkpbr on the full tabletop, then
#                SAPIEN's camera group (shadows off, as ManiSkill's default, and on).
#   STEP=stage   carry .whl-worlds/stage: stores the first pieces of the MuJoCo Warp tree
#                (fetch_worlds_wheels.sh) in /tmp/worlds-stage on the warm machine. Nothing else.
#   STEP=mujoco  carry .gl .whl .whl-worlds/last: joins the pieces (SHA-256 checked), unpacks
#                them into /tmp/worlds-site, then vkpbr, MuJoCo Warp's renderer and
#                mujoco-warp-pbr (tiled and world order) on the primitives-only tabletop.
# WORLDS (default 1024,4096) and SIZES (default 128x128) choose the rows; RUN_TIMEOUT (s) caps
# each run; BUDGET (s, default 540: one device call has 600) skips what would start later, one
# line each; SHADOW_WORLDS (default the last W) the W values of SAPIEN's run with shadow maps
# (SAPIEN_SHADOW_MAP, default 1024: one map a sub-scene, 4 MiB each, 16 GiB for 4,096 worlds).
set -uo pipefail
STEP=${STEP:-sapien}
OUT=${OUT:-out/worlds}
WORLDS=${WORLDS:-1024,4096}
SIZES=${SIZES:-128x128}
RUN_TIMEOUT=${RUN_TIMEOUT:-150}
BUDGET=${BUDGET:-540}
SHADOW_WORLDS=${SHADOW_WORLDS:-${WORLDS##*,}}
mkdir -p "$OUT" /tmp/worlds-png
LOG=$OUT/worlds-$STEP.log
export VKPBR_ASSETS=$PWD/.assets-worlds/models

if [ "$STEP" = stage ]; then
  mkdir -p /tmp/worlds-stage && cp .whl-worlds/stage/* /tmp/worlds-stage/ && ls -l /tmp/worlds-stage
  exit
fi

source benchmarks/gpu_env.sh  # .gl, .whl -> /tmp/site; PYTHONPATH; the NVIDIA ICD
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee -a "$LOG"
first_w=${WORLDS%%,*}
first_size=${SIZES%%,*}
peer_runs() {  # script, label, then its extra arguments: every W and size
  local script=$1 label=$2; shift 2
  for w in ${RUN_WORLDS:-${WORLDS//,/ }}; do
    for size in ${SIZES//,/ }; do
      if (( SECONDS > BUDGET )); then
        echo "| $label | $size | $w | skipped: past BUDGET=$BUDGET s of this call |"
        continue
      fi
      png=()
      [ "$w" = "$first_w" ] && [ "$size" = "$first_size" ] && png=(--png "/tmp/worlds-png/$label.png")
      timeout "$RUN_TIMEOUT" python3 "benchmarks/peers/$script" --worlds "$w" --size "$size" \
        --json "$OUT/worlds.json" "${png[@]}" "$@" 2>> "$LOG" \
        || echo "| $label | $size | $w | failed (rc $?): $(tail -1 "$LOG") |"
    done
  done
}
vkpbr_rows() {  # the variant
  timeout $((RUN_TIMEOUT * 2)) python3 benchmarks/bench_worlds.py --variant "$1" --worlds "$WORLDS" \
    --sizes "$SIZES" --json "$OUT/worlds.json" --png-dir /tmp/worlds-png 2>> "$LOG" \
    || echo "| vkpbr | $1 | failed (rc $?): $(tail -1 "$LOG") |"
}
gallery() {  # world 0 of every renderer at the first size and W, left to right
  python3 - "$OUT/gallery-$STEP.png" "$first_size" "$first_w" /tmp/worlds-png/*.png <<'EOF'
import sys
from PIL import Image
out, size, w, files = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
files = [f for f in files if "vkpbr" not in f
         or (f"-{size}-{w}-" in f and ("numpy" in f or f.endswith("-worlds.png")))] or files
ims = [Image.open(f).convert("RGB") for f in sorted(files)]
if ims:
    sheet = Image.new("RGB", (sum(i.width for i in ims), max(i.height for i in ims)))
    x = 0
    for i in ims:
        sheet.paste(i, (x, 0))
        x += i.width
    sheet.save(out)
    print(out, [f.rsplit("/", 1)[-1] for f in sorted(files)])
EOF
}

echo "| peer | variant | size | W | world-views/s | host us/step | GPU MiB (NVML) | how |"
echo "|---|---|---|---|---|---|---|---|"
if [ "$STEP" = sapien ]; then
  vkpbr_rows tabletop
  mkdir -p /tmp/peers
  python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/peers .whl-sapien/*.whl || exit 1
  for t in .whl-sapien/*.tar.xz; do tar -xJf "$t" -C /tmp/peers; done
  export PYTHONPATH=/tmp/peers:$PYTHONPATH
  peer_runs sapien_worlds.py sapien --variant tabletop --shadows 0
  first_w=none RUN_WORLDS=${SHADOW_WORLDS//,/ } peer_runs sapien_worlds.py sapien-shadows \
    --variant tabletop --shadows "${SAPIEN_SHADOW_MAP:-1024}"
elif [ "$STEP" = mujoco ]; then
  pieces=$(printf '%s\n' /tmp/worlds-stage/worlds-site.tar.xz.* .whl-worlds/last/worlds-site.tar.xz.* \
    | awk -F/ '{print $NF " " $0}' | sort | cut -d' ' -f2)
  # shellcheck disable=SC2086
  cat $pieces > /tmp/worlds-site.tar.xz
  if [ "$(sha256sum /tmp/worlds-site.tar.xz | cut -d' ' -f1)" != "$(cat .whl-worlds/last/worlds-site.sha256)" ]; then
    echo "run_worlds.sh: the MuJoCo Warp tree's pieces do not join (run STEP=stage first, on this warm machine)"
    exit 1
  fi
  mkdir -p /tmp/worlds-site && tar -xJf /tmp/worlds-site.tar.xz -C /tmp/worlds-site
  vkpbr_rows primitives
  export PYTHONPATH=/tmp/worlds-site:$PYTHONPATH MUJOCO_GL=disable  # no GL context: Warp renders
  peer_runs mujoco_worlds.py mujoco-warp --renderer mjwarp
  peer_runs mujoco_worlds.py mujoco-warp-pbr --renderer pbr --render-order tiled
  first_w=none peer_runs mujoco_worlds.py mujoco-warp-pbr-world --renderer pbr --render-order world
else
  echo "run_worlds.sh: STEP=$STEP: choose sapien, stage or mujoco"
  exit 2
fi
gallery
tail -5 "$LOG"
