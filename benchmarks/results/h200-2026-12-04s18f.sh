# H200 run f (session 18's code): the 100-scene job as session 17's run l (18 sample models x
# 16 views at 256x256; cold, warm, no load ahead) for this tree and for df46ebc (session 17's
# last code: .before1 holds its versions of the files changed since) in the same lease; Sponza's
# file to first frame; then the GPU test pass (tests/gpu, tests/unit, tests/distributed, the
# path policy's tests, import graph; 8 workers, validation on).
# Carry .gl .whl .assets-final .before1.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||per model" | grep -v "^|---"; }
echo "== job, this tree"; timeout 120 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | rows
mkdir -p /tmp/before && cp -r src /tmp/before/ && cp -r .before1/src /tmp/before/
echo "== job, df46ebc"; PYTHONPATH=/tmp/site:/tmp/before/src timeout 120 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | rows
echo "== load"; timeout 100 python3 benchmarks/bench_load.py --scene $A/Sponza/glTF/Sponza.gltf --no-job 2>&1 | rows
HYPOTHESIS_PROFILE=report timeout -s INT 170 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/distributed tests/scene/test_resource_paths.py tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -30
