# H200 run h (session 19): where a renderer process's rendering thread spends its time in
# the 100-scene job (warm), with 1 process and with 6: each worker under cProfile
# (bench_load.py --profile-workers), summed per item (profile_summary.py).
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||not measured|failed|item's" | grep -v "^|---"; }
timeout 200 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs cold,warm --no-in-process --processes 1 6 --profile-workers $OUT/prof 2>&1 | rows
for n in 1 6; do echo "== $n, tottime"; python3 benchmarks/profile_summary.py "$OUT/prof/$n-processes-job--warm-" --items 100 --top 22 | grep -v "^|---"; done
echo "== 6, cumulative"; python3 benchmarks/profile_summary.py "$OUT/prof/6-processes-job--warm-" --items 100 --top 40 --sort cumulative | grep -v "^|---" | tail -32
