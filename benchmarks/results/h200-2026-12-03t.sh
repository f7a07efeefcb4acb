# H200 run t (session 14, the merged tree: shadow kernels, the per-frame shadow read choice,
# load ahead, batch replays, GTAO's depth MIPs): GTAO's passes, the 100-scene job, the headline
# rows, the GPU tests of the merged modules. Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
S=$PWD/.assets-final/models/Sponza/glTF/Sponza.gltf; A=$PWD/.assets-final/models
t() { timeout "$1" "${@:2}"; }
echo "== shadow_cache"; VKPBR_ASSETS=$A timeout -s INT 25 python3 -m pytest -q -x -p no:cacheprovider --tb=short tests/gpu/test_shadow_cache.py 2>&1 | grep -E "^E |Error|assert |passed|failed" | head -12
echo "== ao"; t 70 python3 benchmarks/bench_ao.py --scene $S --views 0 --sizes 1920x1080 --modes off,gtao,gtao-low,gtao-full --profile --fuse both --mip-offsets 2.3,3.3 --frames 200 2>&1 | grep -E "^\|" | grep -v "^|---"
echo "== bench"; t 40 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p 2>&1 | grep -E "^\|" | grep -v "^|---"
echo "== job"; t 130 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | grep -E "^\||per model" | grep -v "^|---"
echo "== tests"; VKPBR_ASSETS=$A timeout -s INT 70 python3 -m pytest -q -p no:cacheprovider --tb=line tests/gpu/test_ao.py tests/gpu/test_ao_paths.py tests/gpu/test_load_ahead.py tests/gpu/test_shadow_raster.py 2>&1 | grep -E "^E |Error|passed|failed" | head -12
