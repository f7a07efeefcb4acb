# H200 run g1 (session 16, main with gpu/memory.py's kept allocations, s16-swap, the step's
# short way): the 100-scene job's ratio (run e: 25% warm, 16% cold), the per-model swap
# (run e: 113.6 ms mean), Sponza's load rows, then the GPU test pass. Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
nvidia-smi --query-gpu=clocks.sm,clocks.max.sm --format=csv,noheader
A=$PWD/.assets-final/models; S=$A/Sponza/glTF/Sponza.gltf
export VKPBR_ASSETS=$A
t() { timeout "$1" "${@:2}"; }
rows() { grep -E "^\||per model" | grep -v "^|---"; }
echo "== job"; t 150 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | rows
echo "== swap per model"; t 60 python3 benchmarks/profile_swap.py --rounds 5 --size 256x256 --views 16 \
    --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza 2>&1 | rows
echo "== Sponza load"; t 70 python3 benchmarks/bench_load.py --scene $S --no-job 2>&1 | rows | head -7 | cut -c1-400
echo "== tests"
HYPOTHESIS_PROFILE=report t 170 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -30
