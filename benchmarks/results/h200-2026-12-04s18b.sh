# H200 run b (session 18): the many-scene job's main thread by phase (profile_job.py
# --phases, 7 models with Sponza, 256x256 x 16 views), Sponza's file to first frame with the
# pipeline cache opened on a thread and the binding's import timed apart.
# Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
for i in 1 2; do python3 -X importtime -c "import vulkan" 2>&1 | tail -1; done
echo "== job phases"
timeout 200 python3 benchmarks/profile_job.py --models $A --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza \
   --scenes 42 --views 16 --size 256x256 --phases 2>&1 | grep -E "^\||per model"
echo "== load"
timeout 150 python3 benchmarks/bench_load.py --scene $A/Sponza/glTF/Sponza.gltf --no-job 2>&1 | grep -E "^\|" | grep -v "^|---"
