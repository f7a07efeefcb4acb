# H200 run b (session 21): a first frame's kernels made while the scene uploads
# (render/kernels_ahead.py). Sponza's cold first frame, each row with an empty driver shader
# cache, alternating ahead on (the default) and off (VKPBR_KERNELS_AHEAD=0); then every row
# once with it on; then the GPU tests nearest to it with validation on.
# Carry .gl .whl .assets-s.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
load() { timeout 120 python3 benchmarks/bench_load.py --scene $S --no-job --fresh-driver-cache --builds "$@"; }
for i in 1 2; do
  echo "## ahead on ($i)"; load --rows cold,cold > $OUT/on$i.txt 2>&1; grep -E "^\| cold" $OUT/on$i.txt | head -2
  echo "## ahead off ($i)"; VKPBR_KERNELS_AHEAD=0 load --rows cold,cold > $OUT/off$i.txt 2>&1; grep -E "^\| cold" $OUT/off$i.txt | head -2
done
echo "## every row, ahead on"; load > $OUT/rows.txt 2>&1; grep -E "^\| (cold|warm|bake)" $OUT/rows.txt | head -5
export VKPBR_ASSETS=$PWD/.assets-s/models
timeout -s INT 280 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu/test_kernels_ahead.py tests/gpu/test_frame_kernels.py tests/gpu/test_scene_swap.py tests/gpu/test_pipeline_cache.py tests/gpu/test_kept.py tests/gpu/test_views.py tests/gpu/test_compute_path.py tests/gpu/test_compute_raster.py tests/gpu/test_shadow_raster.py tests/gpu/test_ao_paths.py tests/gpu/test_frame_path.py > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/tests.txt | cut -c1-250 | head -20
