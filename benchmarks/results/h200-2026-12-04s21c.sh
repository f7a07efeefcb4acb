# H200 run c (session 21): the shading kernels begun with the others, from the scene before
# its upload (kernels_ahead.start_shading). Sponza's cold first frame, each row with an
# empty driver shader cache, ahead on (the default) and off; then the GPU tests (tests/gpu,
# tests/unit) with validation on.
# Carry .gl .whl .assets-s.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
load() { timeout 120 python3 benchmarks/bench_load.py --scene $S --no-job --fresh-driver-cache --builds "$@"; }
for i in 1 2; do
  echo "## ahead on ($i)"; load --rows cold,cold > $OUT/on$i.txt 2>&1; grep -E "^\| cold" $OUT/on$i.txt | head -2
  echo "## ahead off ($i)"; VKPBR_KERNELS_AHEAD=0 load --rows cold > $OUT/off$i.txt 2>&1; grep -E "^\| cold" $OUT/off$i.txt | head -1
done
export VKPBR_ASSETS=$PWD/.assets-s/models
timeout -s INT 400 python3 -m pytest -q -n 12 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/tests.txt | cut -c1-250 | head -30
