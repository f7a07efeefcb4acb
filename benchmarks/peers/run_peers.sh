#!/usr/bin/env bash
# Peer benchmarks on the offline NVIDIA machine (cwd = repo root, results in $OUT): unpack the
# carried debs (.gl-peers/) and wheels (.whl-peers/, from fetch_wheels.sh), then pyrender and
# pygfx at 1920x1080 and 640x480. Writes $OUT/peers.json (one JSON line per run) and
# $OUT/peers.log. Takes about a minute on an H200; well under 5 minutes.
set -uo pipefail
OUT=${OUT:-out/peers}
FRAMES=${FRAMES:-100}
mkdir -p "$OUT"
: > "$OUT/peers.json"

for f in .gl-peers/*.deb; do dpkg -x "$f" /; done
ldconfig

# Wheels the image may already hold: install only the missing ones (shadowing the image's own
# copies could upset its other packages).
wheels=()
for w in .whl-peers/*.whl; do
  name=$(basename "$w")
  mod=${name%%-*}
  case $mod in
    six | jinja2 | markupsafe | packaging | typing_extensions | typing_inspect | mypy_extensions)
      python3 -c "import $mod" 2>/dev/null && continue ;;
  esac
  wheels+=("$w")
done
python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/peers "${wheels[@]}" || exit 1
export PYTHONPATH=/tmp/peers PYTHONUNBUFFERED=1 PYOPENGL_PLATFORM=egl

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
fi

nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
echo "| Peer | Size | Render + read back into NumPy | Render only (GPU waited) | Load | GPU |"
echo "|---|---|---|---|---|---|"
for peer in pyrender pygfx; do
  for size in 1920x1080 640x480; do
    png=()
    [ "$size" = 640x480 ] && png=(--png "$OUT/${peer}_$size.png")
    timeout 120 python3 "benchmarks/peers/${peer}_bench.py" --size "$size" --frames "$FRAMES" \
      --json "$OUT/peers.json" "${png[@]}" 2>> "$OUT/peers.log" \
      || echo "| $peer | $size | failed (rc $?): see peers.log |"
  done
done
