# H200 run i (session 18's code): Sponza's file to first frame with the Python bytecode
# compiled first (COMPILE_BYTECODE=1: the device's PYTHONDONTWRITEBYTECODE made every process
# compile the binding and vkpbr, which a pip install does once), and the binding's import.
# Carry .gl .whl .assets-s.
export COMPILE_BYTECODE=1
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
for i in 1 2; do python3 -X importtime -c "import vulkan" 2>&1 | tail -1; done
timeout 100 python3 benchmarks/bench_load.py --scene $S --no-job 2>&1 | grep -E "^\||^###" | grep -v "^|---"
