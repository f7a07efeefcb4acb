# H200 run h (session 20): Python a CUDA worlds step (4,096 tabletop worlds, 128x128,
# batch_step frames="view"), twice, then under cProfile (its 30 costliest functions).
# Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-final/models
P="benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 200 --prepared --frames view"
for i in 1 2; do echo "== step $i"; timeout 60 python3 $P --bare 2>&1 | grep -E "^\|" | grep -v "^|---" | tail -4; done
echo "== cProfile"; timeout 60 python3 $P --bare --cprofile 30 2>&1 | tail -45
