# H200 run c (session 17): async readback (the copy engine's queue): the GPU test pass on
# 8 workers (tests/gpu, tests/unit, import graph; validation on), then probe_stream.py
# (readback on / off, the walk's frames by layers redrawn) with it and with
# VKPBR_ASYNC_READBACK=0. Carry .gl .whl .assets-final (imagecodecs left out: the limit).
source benchmarks/gpu_env.sh
S=$PWD/.assets-final/models/Sponza/glTF/Sponza.gltf
HYPOTHESIS_PROFILE=report VKPBR_ASSETS=$PWD/.assets-final/models timeout -s INT 170 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -30
timeout 80 python3 benchmarks/probe_stream.py --scene $S --frames 400 2>&1 | grep -v "^|---"
VKPBR_ASYNC_READBACK=0 timeout 60 python3 benchmarks/probe_stream.py --scene $S --frames 400 2>&1 | grep -v "^|---" | head -10
