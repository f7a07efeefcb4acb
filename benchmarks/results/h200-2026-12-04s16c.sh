# H200 run c (session 16): before (c702424, session 15's tree, in .before1) and after this
# session's first changes, in one lease: Python a replayed CUDA worlds step (batch_step's
# short way; torch's stream in one call; the CUDA runtime found once), the 1,000-CesiumMan
# crowd (the shadow kernel's box before its bias); then the CUDA and shadow GPU tests.
# Before the call: rm -rf .before1 && mkdir .before1 && git archive c702424 src | tar -x -C .before1
# Carry .gl .whl .assets-c (CesiumMan, CesiumMilkTruck, DamagedHelmet) .before1.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-c/models
P="benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 60 --bare --prepared"
rows() { grep -E "^\|" | grep -E "Python|replayed"; }
for tree in before after before after; do
  run=""; [ $tree = before ] && run="env PYTHONPATH=/tmp/site:$PWD/.before1/src"
  echo "== $tree step, frames view"; timeout 60 $run python3 $P --frames view 2>&1 | rows
done
echo "== after step, frames copy"; timeout 60 python3 $P 2>&1 | rows
for tree in before after; do
  run=""; [ $tree = before ] && run="env PYTHONPATH=/tmp/site:$PWD/.before1/src"
  echo "== $tree crowd"; timeout 90 $run python3 benchmarks/bench_living.py --assets $VKPBR_ASSETS --only crowd --crowds 1000 --shadow-steps --frames 100 2>&1 | grep -E "^\|" | grep -v "^|---"
done
G=tests/gpu; timeout -s INT 150 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short $G/test_worlds_cuda.py $G/test_batch_cache.py $G/test_shadow_raster.py $G/test_world_shadows.py $G/test_batch.py 2>&1 | grep -E "^(FAILED|ERROR)|passed|failed|^E  " | cut -c1-300 | head -30
