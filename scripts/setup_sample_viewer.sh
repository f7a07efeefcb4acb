#!/usr/bin/env bash
# The sample-viewer extra: what tests/sample_viewer needs to render the outside reference, the
# Khronos glTF Sample Viewer, in a headless browser. Debian's chromium-headless-shell (WebGL 2
# through SwiftShader, no GPU) and, with npm, the pinned @khronosgroup/gltf-viewer of
# tests/sample_viewer/package-lock.json (7.5 MB, nothing built). scripts/setup.sh runs it when
# VKPBR_EXTRAS names sample-viewer; idempotent: a second run installs nothing.
set -euo pipefail
cd "$(dirname "$0")/.."

need=()
command -v chromium-headless-shell >/dev/null || command -v chromium >/dev/null \
  || need+=(chromium-headless-shell)
command -v npm >/dev/null || need+=(npm)
if ((${#need[@]})); then
  echo "setup: installing for the Sample Viewer reference: ${need[*]}"
  SUDO=""
  if [ "$(id -u)" != 0 ]; then
    command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install: ${need[*]}" >&2; exit 1; }
    SUDO=sudo
  fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi

dir=tests/sample_viewer
stamp=$dir/node_modules/.vkpbr-installed
want="$(sha256sum $dir/package-lock.json | cut -d' ' -f1)"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  echo "setup: installing the Khronos glTF Sample Viewer (npm ci in $dir)"
  npm ci --prefix "$dir" --no-audit --no-fund --loglevel=error >/dev/null
  echo "$want" > "$stamp"
fi
