# H200 run g2 (session 16): before (c702424, session 15's tree, .before1) and after (this
# session's main) alternating in one lease: Python a replayed CUDA worlds step (frames view),
# the 1,000-CesiumMan crowd, the walk with the sun (bench_shadows --only walk), Sponza's
# headline scenarios (vkpbr bench). Before the call:
#   rm -rf .before1 && mkdir .before1 && git archive c702424 src | tar -x -C .before1
# Carry .gl .whl .assets-s (Sponza, CesiumMilkTruck, DamagedHelmet) .assets-c (CesiumMan) .before1.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
S=$VKPBR_ASSETS/Sponza/glTF/Sponza.gltf
B="env PYTHONPATH=/tmp/site:$PWD/.before1/src"
rows() { grep -E "^\|" | grep -v "^|---"; }
clock() { nvidia-smi --query-gpu=clocks.sm --format=csv,noheader; }
P="benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 60 --bare --prepared --frames view"
for tree in before after before after; do
  run=""; [ $tree = before ] && run=$B
  echo "== $tree step ($(clock))"; timeout 40 $run python3 $P 2>&1 | grep -E "^\|" | grep -E "alone|short"
  echo "== $tree crowd ($(clock))"; timeout 45 $run python3 benchmarks/bench_living.py --assets $PWD/.assets-c/models --only crowd --crowds 1000 --shadow-steps --frames 60 2>&1 | rows | tail -2
done
for tree in before after; do
  run=""; [ $tree = before ] && run=$B
  echo "== $tree walk ($(clock))"; timeout 70 $run python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 300 2>&1 | rows
  echo "== $tree bench"; timeout 50 $run python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p 2>&1 | rows
done
