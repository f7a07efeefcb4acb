# H200 run b (session 19): the 100-scene job on renderer processes: 3 to 6 processes (two
# items in flight each, changing scene while the files encode), 4 processes with one item in
# flight (as run a) and with 2 encoders each; the in-process warm job as the reference.
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||not measured|failed" | grep -v "^|---"; }
J="benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16"
echo "== processes 3-6"; timeout 200 python3 $J --job-runs cold,warm --processes 3 4 5 6 2>&1 | rows
echo "== 4, depth 1"; timeout 60 python3 $J --job-runs warm --processes 4 --depth 1 2>&1 | rows | grep processes
echo "== 4, 2 encoders each"; timeout 60 python3 $J --job-runs warm --processes 4 --process-encoders 2 2>&1 | rows | grep processes
echo "== 4, 8 encoders each"; timeout 60 python3 $J --job-runs warm --processes 4 --process-encoders 8 2>&1 | rows | grep processes
