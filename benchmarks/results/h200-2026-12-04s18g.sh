# H200 run g (session 18's code, with the encoding gate: 2 of 8 encoders while a scene loads
# ahead): the 100-scene job as run f for this tree and df46ebc (.before1: its versions of the
# files changed since) in the same lease; the warm job's phases; the tests that failed or
# changed since run f.
# Carry .gl .whl .assets-final .before1.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||per model" | grep -v "^|---"; }
echo "== job, this tree"; timeout 120 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | rows
mkdir -p /tmp/before && cp -r src /tmp/before/ && cp -r .before1/src /tmp/before/
echo "== job, df46ebc"; PYTHONPATH=/tmp/site:/tmp/before/src timeout 120 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | rows
echo "== job phases"
timeout 90 python3 benchmarks/profile_job.py --models $A --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza \
   --scenes 28 --views 16 --size 256x256 --phases 2>&1 | grep -E "^\||per model" | tail -22
timeout -s INT 60 python3 -m pytest -q -n 8 -p no:cacheprovider tests/gpu/test_kept.py tests/gpu/test_pipeline_cache.py tests/distributed tests/gpu/test_load_ahead.py tests/gpu/test_scene_swap.py 2>&1 | grep -E "^(FAILED|ERROR)|passed|failed|^E  " | head
