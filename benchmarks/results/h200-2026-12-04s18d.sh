# H200 run d (session 18): which of run c's two changes moved the many-scene job: 50 scenes
# of the 18 sample models x 16 views at 256x256, cold then warm bake cache, with the early
# scene change on/off and 8/2 encoding threads (both off: session 17's job); then the warm
# job's phases with the loader thread's.
# Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\|" | grep -v "^|---" | grep -v "^| run"; }
for cfg in "" "--encoders 2" "--no-switch" "--encoders 2 --no-switch"; do
  echo "== job ${cfg:-(this tree: 8 encoders, early change)}"
  timeout 100 python3 benchmarks/bench_load.py --models $A --no-load --scenes 50 --views 16 --job-runs cold,warm $cfg 2>&1 | rows
done
echo "== job phases"
timeout 120 python3 benchmarks/profile_job.py --models $A --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza \
   --scenes 42 --views 16 --size 256x256 --phases 2>&1 | grep -E "^\||per model"
