# H200 run d (session 19): where an item's time goes in the 100-scene job (warm bake cache)
# in this process, on 1 renderer process and on 6 (the item's phases, its thread's CPU).
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
J="benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16"
timeout 200 python3 $J --job-runs cold,warm --processes 1 6 2>&1 | grep -E "^\||not measured|failed|item's" | grep -v "^|---"
