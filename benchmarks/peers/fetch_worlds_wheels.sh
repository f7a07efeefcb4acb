#!/usr/bin/env bash
# Download and pack what the MuJoCo Warp peers of the worlds benchmark (issue 32) need on the
# offline GPU machine (Python 3.12, manylinux x86_64), into the git-ignored .whl-worlds/.
# Run from the repo root on a machine with network access (Python 3.11+ with pip).
#
# What: mujoco 3.17.0, mujoco-warp 3.17.0 (mujoco-warp-pbr 0.2.0 pins mujoco-warp >= 3.16,
# < 3.18: one set serves MuJoCo Warp's own renderer and mujoco-warp-pbr), mujoco-warp-pbr
# 0.2.0, warp-lang 1.19.0 and etils 1.15.0 (mujoco-warp imports etils.epath). The device image
# already has numpy, absl-py, fsspec, zipp and typing-extensions; mujoco's glfw / PyOpenGL
# imports are optional (guarded) and not carried.
#
# Why packed: warp-lang's wheel is 149 MB (warp.so 299 MB unpacked: the CUDA runtime pieces,
# NVRTC and the kernels), over the device tool's 64 MiB a call. Dropped, as the GPU runs
# never use them: warp-clang.so (Warp's CPU JIT, 69 MB; warp loads it only if present and then
# has no CPU device, which these runs do not use), warp's tests and examples; mujoco's
# experimental studio (a web viewer, 7 MB of wasm) and its Filament renderer. The rest is one
# installed tree as tar.xz (~80 MiB), split into pieces of at most $PIECE_MIB (default 46):
#   .whl-worlds/stage/  every piece but the last: carried by a first call that only stores it
#                       on the warm machine (STEP=stage of run_worlds.sh)
#   .whl-worlds/last/   the last piece and the SHA-256 of the whole: carried by the call that
#                       joins, unpacks and runs (STEP=mujoco), beside .gl and .whl for vkpbr.
# (warp.so alone packs to 74 MiB with xz -9, so slimming alone cannot make one call's carry:
# the split is needed either way.)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUTDIR=${OUTDIR:-.whl-worlds}
PY=${PY:-3.12}
PIECE_MIB=${PIECE_MIB:-46}
PKGS=(warp-lang==1.19.0 mujoco==3.17.0 mujoco-warp==3.17.0 mujoco-warp-pbr==0.2.0 etils==1.15.0)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 -m pip download -q --no-deps --only-binary=:all: --python-version "$PY" --implementation cp \
  --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 --platform manylinux_2_17_x86_64 \
  --platform manylinux2014_x86_64 --platform any -d "$tmp/dl" "${PKGS[@]}"
python3 -m pip install -q --no-deps --no-compile --ignore-requires-python --only-binary=:all: --python-version "$PY" \
  --implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 \
  --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 --platform any \
  --target "$tmp/site" "$tmp"/dl/*.whl
(cd "$tmp/site" && rm -rf warp/bin/warp-clang.so warp/tests warp/examples mujoco/experimental \
  mujoco/_render_filament* bin)
(cd "$tmp/site" && tar -cf - . | xz -9 -T0 > "$tmp/worlds-site.tar.xz")
rm -rf "$OUTDIR"
mkdir -p "$OUTDIR/stage" "$OUTDIR/last"
(cd "$tmp" && split -b "${PIECE_MIB}M" -d worlds-site.tar.xz worlds-site.tar.xz.)
pieces=("$tmp"/worlds-site.tar.xz.*)
last=${pieces[${#pieces[@]}-1]}
for p in "${pieces[@]}"; do
  if [ "$p" = "$last" ]; then mv "$p" "$OUTDIR/last/"; else mv "$p" "$OUTDIR/stage/"; fi
done
(cd "$tmp" && sha256sum worlds-site.tar.xz | sed 's/ .*//') > "$OUTDIR/last/worlds-site.sha256"
printf '%s\n' "${PKGS[@]}" > "$OUTDIR/last/worlds-site.txt"
# The two sample models of the full tabletop (tabletop.MODELS), for STEP=sapien's carry.
ASSETS=${VKPBR_ASSETS:-../shared/assets}
mkdir -p .assets-worlds/models
for m in DamagedHelmet CesiumMilkTruck; do cp -r "$ASSETS/$m" .assets-worlds/models/; done
du -sh "$OUTDIR/stage" "$OUTDIR/last" .assets-worlds
