# H200 run b (session 20): Sponza's cold first frame with the frame graph making a
# recording's kernels at once (Step.kernels, gpu/compute.make_at_once; bench_load --builds);
# the 100-scene job on 6 renderer processes, cold and warm (each process's first frame
# compiles its kernels at once too).
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
timeout 200 python3 benchmarks/bench_load.py --scene $A/Sponza/glTF/Sponza.gltf --no-job --builds 2>&1 | grep -v "^|---" | grep -B2 -A30 "file to first frame\|#### cold"
rows() { grep -E "^\||not measured|failed|item's" | grep -v "^|---"; }
timeout 200 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs cold,warm --no-in-process --processes 6 2>&1 | rows
