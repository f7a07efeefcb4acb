# H200 run d (session 16): batch_step's short way, was it taken (run c: the step got 10 us
# slower)? The replayed CUDA step's cProfile with --bare (no phase timers), after only.
# Carry .gl .whl .assets-c.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-c/models
P="benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 60 --bare --prepared --frames view"
timeout 60 python3 $P 2>&1 | grep -E "^\|" | grep -E "Python|replayed|short"
timeout 60 python3 $P --cprofile 45 2>&1 | grep -v "^|" | tail -52
