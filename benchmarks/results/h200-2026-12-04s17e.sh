# H200 run e (session 17's last code): the GPU test pass (tests/gpu, tests/unit, import graph;
# 8 workers, validation on), the walk with cascades snapped to 1/8 of the map
# (bench_shadows --only walk; probe_stream.py), vkpbr bench's Sponza rows, the crowd.
# Carry .gl .whl .assets-final .assets-c.
source benchmarks/gpu_env.sh
S=$PWD/.assets-final/models/Sponza/glTF/Sponza.gltf
rows() { grep -E "^\|" | grep -v "^|---"; }
HYPOTHESIS_PROFILE=report VKPBR_ASSETS=$PWD/.assets-final/models timeout -s INT 170 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -30
timeout 100 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 600 2>&1 | rows
timeout 80 python3 benchmarks/probe_stream.py --scene $S --frames 400 2>&1 | grep -v "^|---"
timeout 60 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p 2>&1 | rows
timeout 45 python3 benchmarks/bench_living.py --assets $PWD/.assets-c/models --only crowd --crowds 1000 --shadow-steps --frames 60 2>&1 | rows | tail -2
