# H200 run b (session 16): where the Python of a replayed CUDA worlds step goes
# (batch_step(frames="view"), 4,096 tabletop worlds at 128x128): cProfile's top 70 by own time.
# Carry .gl .whl .assets-worlds.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-worlds/models
timeout 120 python3 benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 60 --prepared --frames view --cprofile 70 2>&1 | tail -95
