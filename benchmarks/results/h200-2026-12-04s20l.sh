# H200 run l (session 20, the final code): Sponza's cold first frame first (on a fresh lease
# the driver's own shader cache is empty too), then the tests of kernels made ahead (every
# path, raster and shadow choice, post steps, batches), the batch and post tests, with
# validation on.
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
timeout 200 python3 benchmarks/bench_load.py --scene $A/Sponza/glTF/Sponza.gltf --no-job 2>&1 | grep -E "^\| (cold|warm|bake)"
timeout -s INT 250 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu/test_frame_kernels.py tests/gpu/test_batch.py tests/gpu/test_compute_batch.py tests/gpu/test_post.py tests/gpu/test_noise.py tests/gpu/test_lens_render.py 2>&1 | grep -E "^(FAILED|ERROR)|passed|failed|^E  " | cut -c1-250 | head -20
