# H200 run a (session 19): the 100-scene job (18 sample models x 16 views at 256x256) in this
# process (cold, warm) and on 2, 4 and 8 renderer processes (render(address=PROCESSES),
# cold and warm); Sponza's file to first frame with the bytecode compiled first.
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||per model|not measured|failed" | grep -v "^|---"; }
nproc; echo "== job"; timeout 300 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs cold,warm --processes 2 4 8 2>&1 | rows
echo "== load"; timeout 100 python3 benchmarks/bench_load.py --scene $A/Sponza/glTF/Sponza.gltf --no-job 2>&1 | rows
