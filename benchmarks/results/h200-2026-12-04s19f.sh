# H200 run f (session 19): the 100-scene job on 6 renderer processes that load up to two
# scenes ahead (the default now), against one ahead (as runs a-d), and with three items in
# flight a process; then 7 processes; the in-process rows as the reference.
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||not measured|failed|item's" | grep -v "^|---"; }
J="benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs cold,warm"
echo "== 6, two ahead (default)"; timeout 150 python3 $J --processes 6 2>&1 | rows
echo "== 6, one ahead"; timeout 60 python3 $J --no-in-process --processes 6 --loads-ahead 1 2>&1 | rows
echo "== 6, two ahead, 3 in flight"; timeout 60 python3 $J --no-in-process --processes 6 --depth 3 2>&1 | rows
echo "== 7 and 8, two ahead"; timeout 80 python3 $J --no-in-process --processes 7 8 2>&1 | rows
