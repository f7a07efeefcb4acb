# H200 run d (session 25): the GPU test pass (tests/gpu, tests/unit, the import graph;
# validation on, 8 workers) of branch `overlap` (main 40bb7ba with the files in .bar laid
# over it: the frames that overlap the readback copy), then the worlds' kept map on the
# tabletop (probe_world_kept.py, keep_still alternating in one process).
# Carry .gl .whl .assets-g .bar (the sample models but Sponza and BoomBox: their tests skip).
source benchmarks/gpu_env.sh
rm -rf /tmp/bar && mkdir /tmp/bar && cp -r . /tmp/bar/ && cp -r .bar/. /tmp/bar/ && cd /tmp/bar || exit 1
export PYTHONPATH=/tmp/site:$PWD/src VKPBR_ASSETS=$PWD/.assets-g/models
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
HYPOTHESIS_PROFILE=report timeout -s INT 400 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -40
timeout 120 python3 benchmarks/probe_world_kept.py --worlds 1024 --size 128x128 --steps 4 --rounds 2 --steps-apart > $OUT/kept-tabletop.txt 2>&1; tail -6 $OUT/kept-tabletop.txt
