#!/usr/bin/env bash
# Set up everything vkpbr needs on a Debian/Ubuntu machine: system packages (only those
# missing; needs root or sudo) and a Python virtual environment in .venv with vkpbr installed.
# Idempotent: a second run installs nothing and takes about a second.
set -euo pipefail
cd "$(dirname "$0")/.."

# Debian package -> a file it provides; a package is installed only when its file is missing.
declare -A probes=(
  [libvulkan1]=/usr/lib/x86_64-linux-gnu/libvulkan.so.1
  [mesa-vulkan-drivers]=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
  [vulkan-validationlayers]=/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json
  [glslc]=/usr/bin/glslc
  [xvfb]=/usr/bin/Xvfb
  [python3-venv]=/usr/lib/python3/dist-packages/venv
)
missing=()
for pkg in "${!probes[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done
# python3-venv is only needed when the interpreter has no working venv module.
if python3 -c "import venv, ensurepip" 2>/dev/null; then
  missing=("${missing[@]/python3-venv}")
fi
missing=($(printf '%s\n' "${missing[@]}" | grep -v '^$' || true))
if ((${#missing[@]})); then
  echo "setup: installing system packages: ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" != 0 ]; then
    command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
    SUDO=sudo
  fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# VKPBR_EXTRAS may name sample-viewer (not a pip extra): the outside reference of
# tests/sample_viewer, a headless browser and the Khronos glTF Sample Viewer's npm package.
extras=${VKPBR_EXTRAS:-test}
if [[ ",$extras," == *",sample-viewer,"* ]]; then
  bash scripts/setup_sample_viewer.sh
  extras=$(echo ",$extras," | sed 's/,sample-viewer,/,/; s/^,//; s/,$//')
  extras=${extras:-test}
fi

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv"
  "$PY" -m venv .venv
fi
# Reinstall only when pyproject.toml changed since the last install.
stamp=.venv/.vkpbr-installed
want="$(sha256sum pyproject.toml | cut -d' ' -f1)-$extras"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  echo "setup: installing vkpbr[$extras] into .venv"
  .venv/bin/python -m pip install -q --upgrade pip >/dev/null
  .venv/bin/python -m pip install -q -e ".[$extras]"
  # Optional: meshoptimizer (vertex-cache order for `vkpbr bake`) builds from source.
  if ! .venv/bin/python -m pip install -q -e ".[$extras,bake]" >/dev/null 2>&1; then
    echo "setup: meshoptimizer could not be built (needs g++); vkpbr bake keeps the source triangle order"
  fi
  echo "$want" > "$stamp"
fi
