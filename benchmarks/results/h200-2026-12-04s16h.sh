# H200 run h (session 16, main with gpu/memory.py): where a scene change still goes on NVIDIA
# (run g1: BoxAnimated's set_scene 10 ms, its first item 27 ms against 6 for the second):
# profile_swap.py's cProfile of the swaps and first items. Carry .gl .whl .assets-c3.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-c3/models
timeout 120 python3 benchmarks/profile_swap.py --models $VKPBR_ASSETS --names BoxAnimated,CesiumMan,CesiumMilkTruck,2CylinderEngine --rounds 4 --size 256x256 --views 16 --profile $OUT/swap-profile.txt 2>&1 | grep -E "^\|" | grep -v "^|---"
head -c 9000 $OUT/swap-profile.txt
