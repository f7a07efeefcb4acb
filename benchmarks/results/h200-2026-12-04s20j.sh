# H200 run j (session 20): with the pipeline file merged by every process, a warm job's
# Vulkan calls (is vkCreateComputePipelines now the cache's hits?); Sponza's cold first frame
# again on the final code (a plan's kernels made on threads once).
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||not measured|failed|item's|processes;" | grep -v "^|---"; }
J="benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs warm --no-in-process --processes 6 --cache-dir /tmp/jc"
timeout 100 python3 $J > /dev/null 2>&1  # (fills the caches)
timeout 100 python3 $J --time-vk-calls /tmp/vkt 2>&1 | rows | head -14
ls -la /tmp/jc | grep pipelines
timeout 200 python3 benchmarks/bench_load.py --scene $A/Sponza/glTF/Sponza.gltf --no-job 2>&1 | grep -E "^\| (cold|warm)" 
