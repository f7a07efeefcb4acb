# H200 run c (session 18): the many-scene job with the scene changed while an item's files
# encode and 8 encoding threads (this tree) against session 17's last code (df46ebc's src:
# .before1 holds its versions of the files changed since) in the same lease: bench_load.py's 100-scene job over the 18 sample models (as
# session 17's run l), then this tree's main thread by phase (profile_job.py --phases).
# Carry .gl .whl .assets-final .before1.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||per model" | grep -v "^|---"; }
echo "== job, this tree"; timeout 150 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | rows
# .before1 holds df46ebc's versions of the files this session changed (the rest is the same)
mkdir -p /tmp/before && cp -r src /tmp/before/ && cp -r .before1/src /tmp/before/
echo "== job, df46ebc"; PYTHONPATH=/tmp/site:/tmp/before/src timeout 150 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | rows
echo "== job phases"
timeout 120 python3 benchmarks/profile_job.py --models $A --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza \
   --scenes 42 --views 16 --size 256x256 --phases 2>&1 | grep -E "^\||per model"
