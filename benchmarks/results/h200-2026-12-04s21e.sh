# H200 run e (session 21, the final code): SIGTERM 1.5 s into a cold `vkpbr render` (empty
# driver and vkpbr caches each time: the first frame still compiling), four times; Sponza's
# cold first frame, each row with an empty driver shader cache, four times, then every row
# once; then the GPU test pass (tests/gpu, tests/unit, tests/distributed) with validation on.
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
for i in 1 2 3 4; do
  d=$(mktemp -d); ( cd $d; VKPBR_CACHE_DIR=$d/c __GL_SHADER_DISK_CACHE_PATH=$d/g python3 -X faulthandler -m vkpbr -v render --size 16x16 --frames 1000000 --out r.png 2> err.txt &
  pid=$!; sleep 1.5; kill -TERM $pid; wait $pid; rc=$?; echo "sigterm $i rc=$rc"; if [ $rc != 143 ]; then head -c 3000 err.txt; fi )
done
S=$A/Sponza/glTF/Sponza.gltf
load() { timeout 150 python3 benchmarks/bench_load.py --scene $S --no-job --fresh-driver-cache --builds "$@"; }
load --rows cold,cold,cold,cold > $OUT/cold.txt 2>&1; grep -E "^\| cold" $OUT/cold.txt | head -4
load > $OUT/rows.txt 2>&1; grep -E "^\| (cold|warm|bake)" $OUT/rows.txt | head -5
export VKPBR_ASSETS=$A
timeout -s INT 330 python3 -m pytest -q -n 12 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/distributed > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR)|passed|failed" $OUT/tests.txt | cut -c1-200 | head -30
