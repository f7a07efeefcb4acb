# H200 run e (session 16, main with s16-swap merged): the 100-scene job's ratio to one scene
# in-process (the same run), Sponza's file to first frame (cold, warm, and again on the same
# Renderer through set_scene), the per-model swap cost, the readback copy's threads
# (bench_copy_out.py), then the GPU test pass on 8 workers. Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv,noheader
A=$PWD/.assets-final/models; S=$A/Sponza/glTF/Sponza.gltf
export VKPBR_ASSETS=$A
t() { timeout "$1" "${@:2}"; }
rows() { grep -E "^\||per model|cores" | grep -v "^|---"; }
echo "== copy"; t 60 python3 benchmarks/bench_copy_out.py --repeats 100 2>&1 | rows
echo "== job"; t 150 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | rows
echo "== Sponza load"; t 70 python3 benchmarks/bench_load.py --scene $S --no-job 2>&1 | rows | cut -c1-500
echo "== swap per model"; t 60 python3 benchmarks/profile_swap.py --rounds 5 --size 256x256 --views 16 \
    --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza 2>&1 | rows
echo "== tests"
HYPOTHESIS_PROFILE=report t 170 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -30
