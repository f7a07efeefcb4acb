#!/usr/bin/env bash
# Ray for the GPU machine (benchmarks/bench_ray.py there): its image has no Ray, and Ray's
# wheel (79 MB) exceeds the device tool's 64 MiB carry. This downloads Ray and the packages
# it needs that the image lacks, drops what vkpbr.distributed never imports (the Java jars,
# rllib, serve, tune, train, data, llm, the dashboard's web client) and re-zips it: 39 MiB in
# .whl-extra/, installed by benchmarks/gpu_env.sh. Carry [".gl", ".whl", ".whl-extra"].
set -euo pipefail
VERSION=${RAY_VERSION:-2.60.0}
out=.whl-extra
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pip_dl() {
  python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 \
    --implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 \
    --platform manylinux2014_x86_64 -d "$1" "${@:2}"
}
pip_dl "$tmp" "ray==$VERSION"
mkdir -p "$tmp/x" "$out"
(cd "$tmp/x" && unzip -q "$tmp"/ray-*.whl \
  && rm -rf ray/jars ray/rllib ray/serve ray/llm ray/data ray/train ray/tune ray/dashboard/client \
  && zip -q -r -9 "$tmp/slim.whl" .)
cp "$tmp/slim.whl" "$out/$(basename "$tmp"/ray-*.whl)"
pip_dl "$out" jsonschema jsonschema-specifications referencing rpds-py
grep -qx '/.whl-extra/' .git/info/exclude 2>/dev/null || echo /.whl-extra/ >> .git/info/exclude
du -sh "$out"
