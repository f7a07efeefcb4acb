# H200 run a (session 21): Sponza's cold first frame, every row with an empty driver shader
# cache: the kernels compiled on 8 threads (as shipped), 1 (each kernel's compile alone) and
# 16; then the same with the SPIR-V optimised by glslc -O (.spvO, compiled here).
# Carry .gl .whl .assets-s .spvO.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
run() { echo "## $1, threads $2"; VKPBR_KERNEL_THREADS=$2 timeout 100 python3 benchmarks/bench_load.py --scene $S --no-job --rows cold,cold --fresh-driver-cache --builds 2>&1 | grep -E "^\| (cold|raster|shade|shadow|classify|ao|back|pre|brdf|env|post|irr|spec|lut)|done at|Traceback|Error" | cut -c1-200; }
run "as shipped" 8
run "as shipped" 1
run "as shipped" 16
cp .spvO/*.spv src/vkpbr/shaders/spv/
run "glslc -O" 8
run "glslc -O" 1
