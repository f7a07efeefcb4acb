# H200 run s (session 14): the walk's GPU time per frame (bench_paths) for before8 (a145280^1),
# before9 (58bb7bc: the per-frame read choice, before load3's merge) and HEAD; the shadow-cache
# test's failure in run r, printed. Carry .gl .whl .assets-s (Sponza, CesiumMilkTruck, DamagedHelmet) .before8 .before9.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf; A=$PWD/.assets-s/models
t() { timeout "$1" "${@:2}"; }
VKPBR_ASSETS=$A timeout -s INT 60 python3 -m pytest -q -x -p no:cacheprovider tests/gpu/test_shadow_cache.py 2>&1 | grep -E "^E |Error|assert|passed|failed" | head -24
for tree in before8 before9 after before8 before9 after; do
  run=""; [ $tree != after ] && run="env PYTHONPATH=/tmp/site:$PWD/.$tree/src"
  echo "== $tree"; t 60 $run python3 benchmarks/bench_paths.py --scene $S --frames 300 --sizes 1920x1080 --rows pbr/sun/moving,pbr/sun/still --paths compute/compute --lights 1 2>&1 | grep -E "^\|" | grep -v "^|---"
done
# pystep2 (merged): the worlds step's Python on CUDA, and its CUDA tests.
export VKPBR_ASSETS=$A
t 60 python3 benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 30 --bare 2>&1 | grep -E "^\|" | grep -v "^|---"
t 60 python3 benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 30 --bare --prepared 2>&1 | grep -E "^\|" | grep -v "^|---"
timeout -s INT 90 python3 -m pytest -q -p no:cacheprovider tests/gpu/test_worlds_cuda.py tests/gpu/test_batch_cache.py 2>&1 | grep -E "^E |passed|failed" | head -12
