# H200 run a (session 25; sessions 23 and 24 had no device): the GPU test pass at this
# tree (the scrolling cascades, kept maps, the headlight's NaN fix, frames beside the readback copy,
# the caches' random-sequence tests, worlds' masked alpha), validation on; then the worlds'
# kept map on the tabletop (probe_world_kept.py, keep_still alternating in one process).
# Carry .gl .whl .assets-g (the sample models but Sponza and BoomBox: their tests skip here).
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-g/models
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; git log -1 --format=%h 2>/dev/null
HYPOTHESIS_PROFILE=report timeout -s INT 400 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -40
timeout 120 python3 benchmarks/probe_world_kept.py --worlds 1024 --size 128x128 --steps 4 --rounds 2 --steps-apart > $OUT/kept-tabletop.txt 2>&1; tail -6 $OUT/kept-tabletop.txt
