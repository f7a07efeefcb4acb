# H200 run g (session 21, after the review: one enumeration of the draws for GpuScene and
# the guess, one kernels_ahead.start): Sponza's cold first frame three times (an empty
# driver cache each), alternating with the guess off, the GPU tests nearest to it with validation on.
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
load() { timeout 150 python3 benchmarks/bench_load.py --scene $A/Sponza/glTF/Sponza.gltf --no-job --fresh-driver-cache --builds --rows cold,cold "$@"; }
for i in 1 2; do
  echo "## ahead on ($i)"; load > $OUT/on$i.txt 2>&1; grep -E "^\| cold" $OUT/on$i.txt | head -2
  echo "## ahead off ($i)"; VKPBR_KERNELS_AHEAD=0 load > $OUT/off$i.txt 2>&1; grep -E "^\| cold" $OUT/off$i.txt | head -2
done
export VKPBR_ASSETS=$A
timeout -s INT 300 python3 -m pytest -q -n 12 -p no:cacheprovider -rfE --tb=short tests/gpu/test_kernels_ahead.py tests/gpu/test_scene_swap.py tests/gpu/test_frame_kernels.py tests/gpu/test_cli_signals.py tests/gpu/test_compute_path.py tests/gpu/test_material_layers.py tests/gpu/test_instances.py tests/gpu/test_scenes.py tests/gpu/test_living_scene.py tests/unit > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR)|passed|failed" $OUT/tests.txt | cut -c1-200 | head -20
