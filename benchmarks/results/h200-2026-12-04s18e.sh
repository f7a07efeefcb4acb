# H200 run e (session 18): the many-scene job (50 scenes of the 18 sample models x 16 views at
# 256x256, cold then warm bake cache) with the load's folder realpaths kept, by encoding
# threads (8, 4, 2) and Python's GIL switch interval (5 ms, 1 ms); then the warm job's phases.
# Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\|" | grep -v "^|---" | grep -v "^| run"; }
for cfg in "--encoders 8" "--encoders 4" "--encoders 2" "--encoders 8 --switch-interval 0.001" "--encoders 2 --switch-interval 0.001" "--encoders 2 --no-switch"; do
  echo "== job $cfg"
  timeout 100 python3 benchmarks/bench_load.py --models $A --no-load --scenes 50 --views 16 --job-runs cold,warm $cfg 2>&1 | rows
done
echo "== job phases"
timeout 120 python3 benchmarks/profile_job.py --models $A --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza \
   --scenes 42 --views 16 --size 256x256 --phases 2>&1 | grep -E "^\||per model" | tail -22
