# H200 run g (session 22, after run f's three failures were fixed: the worlds_input snippet of
# docs/batch.md runs as written, renderer.py back under its 300 lines): those tests and their
# neighbours, and Sponza's load warm (bake cache and pipelines).
# Carry .gl .whl .assets-s.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-s/models
export VKPBR_ASSETS=$A
timeout -s INT 200 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu/test_doc_snippets.py tests/unit/test_render_structure.py tests/gpu/test_stream.py tests/gpu/test_worlds_cuda.py tests/gpu/test_frame_path.py > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR|E )|passed|failed" $OUT/tests.txt | cut -c1-200 | head -20
timeout 120 python3 benchmarks/bench_load.py --scene $A/Sponza/glTF/Sponza.gltf --no-job --rows "bake (first)","warm bake + pipelines","warm bake + pipelines","warm pipelines" > $OUT/load.txt 2>&1
grep -E "^\| (cold|warm|bake|row)" $OUT/load.txt | cut -c1-220 | head -10
