#!/usr/bin/env bash
# Make the git-ignored folders the device tool's runs carry (gpu_run.sh, gpu_raster.sh,
# bench_raster.py; the lent H200 has Python 3.12 with NumPy, PyTorch and pytest, no Vulkan
# loader and nothing fetchable): run once from the repo root on a machine with network
# access and the shared assets. What each is (carry at most 64 MiB a call with the tree):
#   .gl           Debian debs: the Vulkan loader, glvnd, the validation layer, glslc (7 MiB)
#   .whl          vkpbr's core wheels the device lacks (3 MiB)
#   .whl-extra    imagecodecs, a core dependency, apart for its size (28 MiB)
#   .assets-tests the sample models but Sponza and BoomBox: the GPU test pass (14 MiB)
#   .assets-peers Sponza with its JPEGs at quality 75 and PNGs recompressed, DamagedHelmet and
#                 AlphaBlendModeTest (bench_batch.py's alphablend): the benchmarks (30 MiB)
set -euo pipefail
cd "$(dirname "$0")/.."
ASSETS=${VKPBR_ASSETS:-../shared/assets}
PY=${PY:-3.12}
o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64-lists'
mkdir -p /tmp/amd64-lists/partial .gl .whl .whl-extra
# shellcheck disable=SC2086
apt-get $o update -qq
# shellcheck disable=SC2086
(cd .gl && apt-get $o download -qq libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 \
  libgles2 libbsd0 libmd0 vulkan-validationlayers glslc libshaderc1)
wheels() {  # destination, then pinned requirements
  local dst=$1; shift
  for p in "$@"; do
    python3 -m pip download -q --no-deps --only-binary=:all: --python-version "$PY" \
      --implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 \
      --platform manylinux2014_x86_64 --platform any -d "$dst" "$p"
  done
}
# pyproject's dependencies and what they need beyond the device's image (marshmallow < 4:
# dataclasses-json's bound).
wheels .whl vulkan==1.3.275.1 cffi pycparser pygltflib dataclasses-json "marshmallow<4" \
  deprecated glfw "OpenEXR>=3.5" tinyobjloader==2.0.0rc13
wheels .whl-extra "imagecodecs>=2024.1"
mkdir -p .assets-tests/models .assets-peers/models/Sponza/glTF
for m in AlphaBlendModeTest DamagedHelmet MetalRoughSpheresNoTextures NormalTangentMirrorTest \
         NormalTangentTest OrientationTest TextureCoordinateTest; do
  cp -r "$ASSETS/$m" .assets-tests/models/
done
cp -r "$ASSETS/DamagedHelmet" "$ASSETS/AlphaBlendModeTest" .assets-peers/models/
.venv/bin/python - "$ASSETS/Sponza/glTF" .assets-peers/models/Sponza/glTF <<'EOF'
import shutil
import sys
from pathlib import Path

from PIL import Image

src, dst = Path(sys.argv[1]), Path(sys.argv[2])
for f in src.iterdir():
    if f.suffix == ".jpg":
        Image.open(f).save(dst / f.name, quality=75)
    elif f.suffix == ".png":
        Image.open(f).save(dst / f.name, optimize=True)
    else:
        shutil.copy(f, dst / f.name)
EOF
du -sh .gl .whl .whl-extra .assets-tests .assets-peers
