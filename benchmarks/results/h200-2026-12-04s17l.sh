# H200 run l (session 17's last code: the copy threads kept, mapped memory kept longest):
# a scene change per model (profile_swap.py as session 16's run i) and the 100-scene job
# (bench_load.py), then the memory / swap / leak / load-ahead GPU tests.
# Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||per model" | grep -v "^|---"; }
echo "== swap per model"; timeout 60 python3 benchmarks/profile_swap.py --rounds 5 --size 256x256 --views 16 \
    --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza 2>&1 | rows
echo "== job"; timeout 150 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | rows
timeout -s INT 90 python3 -m pytest -q -n 8 -p no:cacheprovider tests/gpu/test_memory.py tests/gpu/test_scene_swap.py tests/gpu/test_leaks.py tests/gpu/test_load_ahead.py tests/unit/test_copy_out.py 2>&1 | grep -E "^(FAILED|ERROR)|passed|failed|^E  " | head
