# H200 run l (session 13, the merged tree): benchmarks, then the GPU tests the earlier passes
# did not reach plus this session's. Carry .gl .whl .assets-final. About 560 s.
source benchmarks/gpu_env.sh
S=.assets-final/models/Sponza/glTF/Sponza.gltf; A=$PWD/.assets-final/models
t() { timeout "$1" "${@:2}"; }
t 60 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p > $OUT/bench.txt 2>&1
t 90 python3 benchmarks/bench_shadows.py --scene $S --frames 200 --steps --json $OUT/shadows.json > $OUT/shadows.txt 2>&1
t 80 python3 benchmarks/bench_world_batches.py --assets $A --rows helmet-64 --worlds 8192 --steps 10 --shadows both > $OUT/helmet.txt 2>&1
t 60 python3 benchmarks/bench_living.py --assets $A --only crowd --crowds 1000 --frames 60 --json $OUT/living.json > $OUT/living.txt 2>&1
t 40 python3 benchmarks/bench_ao.py --scene $S --views 0 --sizes 1920x1080 --modes off,gtao --profile --fuse both > $OUT/ao.txt 2>&1
t 70 python3 benchmarks/bench_load.py --scene $S --no-job --json $OUT/load.json > $OUT/load.txt 2>&1
for f in $OUT/*.txt; do echo "== $f"; grep -E "^\|" $f | tail -12; done > $OUT/summary.md
VKPBR_ASSETS=$A HYPOTHESIS_PROFILE=report timeout -s INT ${TESTS_S:-240} python3 -m pytest -q -rs -p no:cacheprovider \
  tests/gpu/test_batch_cache.py tests/gpu/test_world_shadows.py tests/gpu/test_worlds_cuda.py tests/gpu/test_ao_paths.py \
  tests/gpu/test_lens_render.py tests/gpu/test_deform.py tests/gpu/test_path_choice.py tests/gpu/test_uploads.py \
  tests/gpu/test_compute_raster.py tests/gpu/test_shadow_raster.py tests/gpu/test_worlds.py \
  tests/gpu/test_many_materials.py tests/gpu/test_motion.py tests/gpu/test_new_user.py tests/gpu/test_noise.py \
  tests/gpu/test_orientation.py tests/gpu/test_output_cli.py tests/gpu/test_outputs.py tests/gpu/test_post.py \
  tests/gpu/test_scenes.py tests/gpu/test_shadows.py tests/gpu/test_transmission.py tests/gpu/test_views.py > $OUT/gpu-tests.log 2>&1
tail -25 $OUT/gpu-tests.log; cat $OUT/summary.md
