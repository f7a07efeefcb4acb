# H200 run f (session 16): where a scene swap's first item goes on NVIDIA (run e: the first
# item after set_scene 39-98 ms against 5-16 ms for the second; lavapipe's far less):
# profile_swap.py's cProfile of the swaps and first items. Carry .gl .whl .assets-c.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-c/models
timeout 120 python3 benchmarks/profile_swap.py --models $VKPBR_ASSETS --names DamagedHelmet,CesiumMilkTruck,CesiumMan --rounds 4 --size 256x256 --views 16 --profile $OUT/swap-profile.txt 2>&1 | grep -E "^\|" | grep -v "^|---"
head -c 14000 $OUT/swap-profile.txt
