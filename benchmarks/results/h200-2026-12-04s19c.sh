# H200 run c (session 19): the 100-scene job on 6, 7 and 8 renderer processes (cold and
# warm), with the CPU cores each run kept busy; 6 warm again with the default process count.
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||not measured|failed" | grep -v "^|---"; }
J="benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16"
echo "== processes 6-8"; timeout 200 python3 $J --job-runs cold,warm --processes 6 7 8 2>&1 | rows
echo "== 6 again"; timeout 90 python3 $J --job-runs warm --processes 6 6 2>&1 | rows
