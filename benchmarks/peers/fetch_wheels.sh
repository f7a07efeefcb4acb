#!/usr/bin/env bash
# Download everything the peer benchmarks need on the offline GPU machine (Python 3.12,
# manylinux x86_64) into .whl-peers/ (wheels), .whl-sapien/ (SAPIEN, slimmed) and .gl-peers/
# (Debian debs), all git-ignored.
# Run from the repo root on a machine with network access. The GPU machine already has numpy,
# pillow, scipy, imageio, requests, networkx, pyyaml, tqdm and rich, so those are not fetched.
set -euo pipefail
cd "$(dirname "$0")/../.."
WHL=${WHL:-.whl-peers}
GL=${GL:-.gl-peers}
PY=${PY:-3.12}
mkdir -p "$WHL" "$GL"

# Exact pins: the versions measured in shared/notes/peers.md and what their metadata requires.
PKGS=(
  # pyrender and its deps (pyrender itself is installed with --no-deps: it pins PyOpenGL 3.1.0)
  pyrender==0.1.45 PyOpenGL==3.1.10 trimesh==5.2.0 pyglet==1.5.31 freetype-py==2.5.1
  # pygfx, wgpu and the glTF loader
  pygfx==0.17.0 wgpu==0.32.0 rendercanvas==2.7.2 pylinalg==0.6.8 uharfbuzz==0.57.0
  hsluv==5.0.5 cffi==2.1.1 pycparser==3.12 gltflib==1.0.13 dataclasses-json==0.6.7
  marshmallow==3.26.2 typing-inspect==0.9.0 mypy-extensions==1.2.0
  # usually present already (torch brings most); run_peers.sh installs them only if missing
  six==1.17.0 jinja2==3.1.6 markupsafe==3.0.3 packaging==25.0 typing-extensions==4.15.0
)
for p in "${PKGS[@]}"; do
  python3 -m pip download -q --no-deps --only-binary=:all: --python-version "$PY" \
    --implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 \
    --platform manylinux2014_x86_64 --platform any -d "$WHL" "$p"
done

# SAPIEN 3 (a 51 MB wheel: more than the device tool's 64 MiB carry beside the assets) is
# unpacked and slimmed to what rendering needs, then packed as one tar.xz (~27 MiB): dropped are
# its C++ headers (include/), the depth-sensor patterns (sensor/assets/), OIDN's CUDA denoiser
# device, its bundled Vulkan loader (the one from .gl-peers is used) and the macOS loader. Its
# pure-Python needs the GPU image lacks (transforms3d, pyperclip) are carried as wheels beside
# it; lxml, networkx, opencv-python-headless and requests are in the image.
SAP=${SAP:-.whl-sapien}
mkdir -p "$SAP"
tmp=$(mktemp -d)
python3 -m pip download -q --no-deps --only-binary=:all: --python-version "$PY" --implementation cp \
  --platform manylinux_2_28_x86_64 -d "$tmp" sapien==3.0.3
for p in transforms3d==0.4.2 pyperclip==1.11.0; do
  python3 -m pip download -q --no-deps --only-binary=:all: --python-version "$PY" \
    --implementation cp --platform any -d "$SAP" "$p"
done
mkdir -p "$tmp/tree"
python3 -m zipfile -e "$tmp"/sapien-3.0.3-*.whl "$tmp/tree"
(cd "$tmp/tree" && rm -rf sapien-3.0.3.data sapien/include sapien/sensor/assets \
  sapien/oidn_library/libOpenImageDenoise_device_cuda.so.* sapien/vulkan_library/libvulkan.* \
  && tar -cf - sapien sapien.libs sapien-3.0.3.dist-info | xz -9 -T0 > "../sapien-3.0.3-slim.tar.xz")
mv "$tmp/sapien-3.0.3-slim.tar.xz" "$SAP/"
rm -rf "$tmp"

# libGLU for pyglet's import (pulled in by `import pyrender`), glvnd EGL/GL for PyOpenGL on EGL,
# the Vulkan loader for wgpu, and libbsd0/libmd0 that libglx0's X11 chain needs (the same set
# as .gl/, so run_peers.sh does not depend on it).
o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64-lists -oAPT::Sandbox::User=root'
mkdir -p /tmp/amd64-lists/partial
# shellcheck disable=SC2086
apt-get $o update -qq
# shellcheck disable=SC2086
(cd "$GL" && apt-get $o download -qq libglu1-mesa libegl1 libglvnd0 libgl1 libopengl0 libglx0 libgles2 \
  libvulkan1 libbsd0 libmd0)

du -sh "$WHL" "$SAP" "$GL"
