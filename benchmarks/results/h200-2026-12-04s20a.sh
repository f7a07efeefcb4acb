# H200 run a (session 20): which pipelines Sponza's cold first frame builds, when and how
# long each takes (bench_load --builds); the 100-scene job on 6 renderer processes with
# session 19's fewer Vulkan objects a scene change (not yet measured on the H200).
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
timeout 200 python3 benchmarks/bench_load.py --scene $A/Sponza/glTF/Sponza.gltf --no-job --builds 2>&1 | grep -v "^|---"
rows() { grep -E "^\||not measured|failed|item's" | grep -v "^|---"; }
timeout 200 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs cold,warm --no-in-process --processes 6 2>&1 | rows
