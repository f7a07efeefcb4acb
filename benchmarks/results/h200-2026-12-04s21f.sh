# H200 run f (session 21, the final code): the GPU tests nearest to the kernels made ahead
# with validation on; then the 100-scene job on 6 processes (each process's first scene now
# compiles its first frame's likely kernels ahead), cold and warm.
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
timeout -s INT 200 python3 -m pytest -q -n 12 -p no:cacheprovider -rfE --tb=short tests/gpu/test_kernels_ahead.py tests/gpu/test_scene_swap.py tests/gpu/test_frame_kernels.py tests/gpu/test_cli_signals.py tests/gpu/test_views.py tests/gpu/test_pipeline_cache.py tests/gpu/test_kept.py tests/unit/test_make_at_once.py tests/gpu/test_compute_path.py tests/gpu/test_material_layers.py > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR)|passed|failed" $OUT/tests.txt | cut -c1-200 | head -20
timeout 330 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs cold,warm --processes 6 --no-in-process > $OUT/job.txt 2>&1
grep -E "^\|" $OUT/job.txt | head -12
