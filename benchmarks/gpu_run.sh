#!/usr/bin/env bash
# One device-tool run on the NVIDIA machine: unpack the carried loader/validation layer and
# wheels, then the GPU test pass and the benchmarks. Output files land in $OUT.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl 2>/dev/null || exit 1
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1
# The NVIDIA ICD (libGLX_nvidia) needs the glvnd libraries carried in .gl/.
if [ -z "$(python3 -m vkpbr info --json 2>/dev/null | grep -i nvidia)" ]; then
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
python3 -m vkpbr info | head -3
echo "== GPU test pass (validation on)"
# .assets/models: the sample models in ../shared/assets' layout (Sponza's JPEGs re-encoded at
# quality 85, BoomBox without its unused spec-gloss maps) to fit the transfer limit.
VKPBR_ASSETS=$PWD/.assets/models python3 -m pytest -q -p no:cacheprovider -rs tests/gpu tests/unit > "$OUT/gpu-tests.log" 2>&1; tail -5 "$OUT/gpu-tests.log"
echo "== viewer loop, offscreen, Sponza 1920x1080, flying with the light animated (600 frames)"
python3 -m vkpbr view .assets/models/Sponza/glTF/Sponza.gltf --offscreen --size 1920x1080 --script benchmarks/viewer_fly.json
echo "== vkpbr bench (no peers)"
python3 -m vkpbr bench --frames 200 --sponza .assets/models/Sponza/glTF/Sponza.gltf 2>/dev/null
echo "== bench_core"
python3 benchmarks/bench_core.py --frames 100 --json "$OUT/core.json"
echo "== Sponza 1920x1080"
python3 -m vkpbr render .assets/models/Sponza/glTF/Sponza.gltf --camera 9,1.8,-0.4,-9,3.5,-0.4 --fov 45 --light 0,4,0 --size 1920x1080 --frames 100 --out "$OUT/sponza.png"
python3 -m vkpbr render .assets/models/Sponza/glTF/Sponza.gltf --camera 9,1.8,-0.4,-9,3.5,-0.4 --fov 45 --light 0,4,0 --size 1920x1080 --frames 100 --tbn packed --out "$OUT/sponza_packed.png"
echo "== bench_sponza"
python3 benchmarks/bench_sponza.py --frames 50 2>&1 | tail -18
