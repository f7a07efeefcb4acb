# H200 run i (session 16, main with kept fences): the per-model scene change and the
# 100-scene job's ratio again (run g1: 79.5 ms mean, 27% warm). Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||per model" | grep -v "^|---"; }
echo "== swap per model"; timeout 60 python3 benchmarks/profile_swap.py --rounds 5 --size 256x256 --views 16 \
    --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza 2>&1 | rows
echo "== job"; timeout 150 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | rows
timeout -s INT 90 python3 -m pytest -q -n 8 -p no:cacheprovider tests/gpu/test_memory.py tests/gpu/test_scene_swap.py tests/gpu/test_leaks.py tests/gpu/test_load_ahead.py tests/gpu/test_worlds_cuda.py tests/gpu/test_shadow_cache.py 2>&1 | grep -E "^(FAILED|ERROR)|passed|failed|^E  " | head
