# H200 run s (session 14): the walk's GPU time per frame (bench_paths) for before8 (a145280^1),
# before9 (58bb7bc: the per-frame read choice, before load3's merge) and HEAD; the shadow-cache
# test's failure in run r, printed. Carry .gl .whl .assets-peers .before8 .before9.
source benchmarks/gpu_env.sh
S=$PWD/.assets-peers/models/Sponza/glTF/Sponza.gltf; A=$PWD/.assets-peers/models
t() { timeout "$1" "${@:2}"; }
VKPBR_ASSETS=$A timeout -s INT 60 python3 -m pytest -q -x -p no:cacheprovider tests/gpu/test_shadow_cache.py 2>&1 | grep -E "^E |assert|passed|failed" | head -20
for tree in before8 before9 after before8 before9 after; do
  run=""; [ $tree != after ] && run="env PYTHONPATH=/tmp/site:$PWD/.$tree/src"
  echo "== $tree"; t 60 $run python3 benchmarks/bench_paths.py --scene $S --frames 300 --sizes 1920x1080 --rows pbr/sun/moving,pbr/sun/still --paths compute/compute --lights 1 2>&1 | grep -E "^\|" | grep -v "^|---"
done
