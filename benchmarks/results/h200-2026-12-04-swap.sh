# H200 run (session 16, branch s16-swap, issue 32 must-have 7): a scene change's CPU cost,
# before (main 4220a20) and after (this branch): the 100-scene job's ratio, Sponza's file to
# first frame again on the same Renderer (set_scene, "again, device kept"), the per-model swap
# cost (profile_swap.py: set_scene + first item - second item, wall and main-thread CPU) and
# where the job's time goes (profile_job.py under cProfile, into $OUT).
# Make the before tree next to this one first:
#   rm -rf .before3 && mkdir .before3 && git archive 4220a20 src | tar -x -C .before3
# Carry .gl .whl .assets-final .before3. About 7 min (each step has its own timeout).
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models; S=$A/Sponza/glTF/Sponza.gltf
export VKPBR_ASSETS=$A
t() { timeout "$1" "${@:2}"; }
rows() { grep -E "^\||per model" | grep -v "^|---"; }
B="env PYTHONPATH=/tmp/site:$PWD/.before3/src"
for tree in before after; do
  run=""; [ $tree = before ] && run=$B
  echo "== job ($tree)"; t 150 $run python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | rows
  echo "== Sponza file to first frame, again on the same Renderer ($tree)"
  t 60 $run python3 benchmarks/bench_load.py --scene $S --no-job 2>&1 | rows | cut -c1-400
  echo "== swap per model ($tree; 16 views at 256x256 an item, the job's batch)"
  t 60 $run python3 benchmarks/profile_swap.py --rounds 5 --size 256x256 --views 16 \
    --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza 2>&1 | rows
done
echo "== where the job's time goes (after; cProfile into \$OUT)"
t 120 python3 benchmarks/profile_job.py --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza \
  --scenes 28 --views 16 --size 256x256 --profile $OUT/job-profile.txt 2>&1 | rows
t 60 python3 benchmarks/profile_swap.py --rounds 3 --size 256x256 --views 16 --profile $OUT/swap-profile.txt 2>&1 | rows
