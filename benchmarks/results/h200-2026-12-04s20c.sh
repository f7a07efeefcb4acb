# H200 run c (session 20): which Vulkan calls a renderer process waits in, one process
# against six (bench_load --time-vk-calls: every binding call timed by name), on the warm
# 100-scene job; then the job again untimed for its rate.
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||not measured|failed|item's|processes;" | grep -v "^|---"; }
timeout 250 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs cold,warm --no-in-process --processes 1 6 --time-vk-calls /tmp/vkt 2>&1 | rows
timeout 150 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs warm --no-in-process --processes 6 2>&1 | rows
