#!/usr/bin/env bash
# Peer benchmarks on the offline NVIDIA machine (cwd = repo root, results in $OUT): unpack the
# carried debs (.gl-peers/), wheels (.whl-peers/, from fetch_wheels.sh) and SAPIEN
# (.whl-sapien/: a slimmed tree, tar.xz, and its two pure-Python wheels), then
#  - "frames" (issue 6): pyrender and pygfx on Sponza at 1920x1080 and 640x480;
#  - "batch" (issue 14): the batch scenario of common.py, Sponza and DamagedHelmet at 128x128
#    and 512x512 on the same $VIEWS poses (written once to /tmp/peers-poses/): pyrender,
#    pygfx at pixel_scale 1 and 2, SAPIEN with B cameras in one scene and with a
#    RenderCameraGroup (one submission; needs CUDA, i.e. torch).
# SCENARIOS (default "frames batch") and PEERS (default "pyrender pygfx sapien") choose; peers
# whose files were not carried are skipped (so the 64 MiB carry can be split over two calls:
# README.md). Writes $OUT/peers.json (one JSON line per run) and $OUT/peers.log.
set -uo pipefail
OUT=${OUT:-out/peers}
FRAMES=${FRAMES:-100}
VIEWS=${VIEWS:-256}
REPS=${REPS:-3}
RUN_TIMEOUT=${RUN_TIMEOUT:-240}  # seconds a batch run may take
SCENARIOS=${SCENARIOS:-frames batch}
PEERS=${PEERS:-pyrender pygfx sapien}
mkdir -p "$OUT"
: > "$OUT/peers.json"

for f in .gl-peers/*.deb; do dpkg -x "$f" /; done
ldconfig

# Wheels the image may already hold: install only the missing ones (shadowing the image's own
# copies could upset its other packages).
wheels=()
for w in .whl-peers/*.whl .whl-sapien/*.whl; do
  [ -f "$w" ] || continue
  name=$(basename "$w")
  mod=${name%%-*}
  case $mod in
    six | jinja2 | markupsafe | packaging | typing_extensions | typing_inspect | mypy_extensions)
      python3 -c "import $mod" 2>/dev/null && continue ;;
  esac
  wheels+=("$w")
done
if [ ${#wheels[@]} -gt 0 ]; then
  python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/peers "${wheels[@]}" || exit 1
fi
mkdir -p /tmp/peers
for t in .whl-sapien/*.tar.xz; do [ -f "$t" ] && tar -xJf "$t" -C /tmp/peers; done
export PYTHONPATH=/tmp/peers${PYTHONPATH:+:$PYTHONPATH} PYTHONUNBUFFERED=1 PYOPENGL_PLATFORM=egl

# glvnd and the Vulkan loader look in /usr/share and /etc; the NVIDIA driver's files are mounted
# under /usr/local/nvidia. Point at them when the standard places have no NVIDIA entry.
nv=/usr/local/nvidia/share
if ! ls /usr/share/glvnd/egl_vendor.d/*nvidia* /etc/glvnd/egl_vendor.d/*nvidia* >/dev/null 2>&1 \
    && [ -f $nv/glvnd/egl_vendor.d/10_nvidia.json ]; then
  export __EGL_VENDOR_LIBRARY_FILENAMES=$nv/glvnd/egl_vendor.d/10_nvidia.json
fi
if ! ls /usr/share/vulkan/icd.d/*nvidia* /etc/vulkan/icd.d/*nvidia* >/dev/null 2>&1 \
    && [ -f $nv/vulkan/icd.d/nvidia_icd.json ]; then
  export VK_DRIVER_FILES=$nv/vulkan/icd.d/nvidia_icd.json
  export VK_ICD_FILENAMES=$VK_DRIVER_FILES  # SAPIEN's own check reads the older name
fi

nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
has() { [[ " $2 " == *" $1 "* ]]; }
# A peer runs when its module imports (its files were carried).
usable=()
for peer in $PEERS; do
  if python3 -c "import $peer" 2>>"$OUT/peers.log"; then usable+=("$peer")
  else echo "skipped $peer: not importable here (see peers.log)"; fi
done

if has frames "$SCENARIOS"; then
  echo "| Peer | Size | Render + read back into NumPy | Render only (GPU waited) | Load | GPU |"
  echo "|---|---|---|---|---|---|"
  for peer in "${usable[@]}"; do
    [ "$peer" = sapien ] && continue  # SAPIEN runs the batch scenario only
    for size in 1920x1080 640x480; do
      png=()
      [ "$size" = 640x480 ] && png=(--png "$OUT/${peer}_$size.png")
      timeout 120 python3 "benchmarks/peers/${peer}_bench.py" --size "$size" --frames "$FRAMES" \
        --json "$OUT/peers.json" "${png[@]}" 2>> "$OUT/peers.log" \
        || echo "| $peer | $size | failed (rc $?): see peers.log |"
    done
  done
fi

if has batch "$SCENARIOS"; then
  echo
  echo "| Peer | Scene | Size | Views | Views/s into NumPy | Views/s render only | How | Load | GPU |"
  echo "|---|---|---|---|---|---|---|---|---|"
  for scene in sponza helmet; do
    poses="/tmp/peers-poses/poses_$scene.npy"
    mkdir -p /tmp/peers-poses
    python3 benchmarks/peers/common.py --write-poses "$poses" --scene "$scene" --views "$VIEWS" >/dev/null
    for size in 128x128 512x512; do
      runs=()
      for peer in "${usable[@]}"; do
        case $peer in
          pygfx) runs+=("pygfx --pixel-scale 1" "pygfx --pixel-scale 2") ;;
          sapien) runs+=("sapien --mode cameras" "sapien --mode group") ;;
          *) runs+=("$peer") ;;
        esac
      done
      for run in "${runs[@]}"; do
        read -r peer extra <<< "$run"
        # View 0 of the helmet at 128x128 for a visual check, one per peer (the device tool
        # returns 8 files at most: peers.json, peers.log, 2 frame PNGs, these 3).
        png=()
        [ "$size" = 128x128 ] && [ "$scene" = helmet ] && [[ "$run" != *" 2" && "$run" != *group ]] \
          && png=(--png "$OUT/${peer}_helmet_batch.png")
        # shellcheck disable=SC2086
        timeout "$RUN_TIMEOUT" python3 "benchmarks/peers/${peer}_bench.py" --batch --scene "$scene" \
          --size "$size" --poses "$poses" --reps "$REPS" --json "$OUT/peers.json" $extra \
          "${png[@]}" 2>> "$OUT/peers.log" \
          || echo "| $run | $scene | $size | failed (rc $?): $(tail -1 "$OUT/peers.log") |"
      done
    done
  done
fi
