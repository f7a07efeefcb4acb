# H200 run j (session 17's last code: GTAO's automatic radius from the scene as loaded, so
# an animated crowd no longer re-records its frame each frame): the crowd twice (each its own
# process), vkpbr bench's Sponza rows, then the GPU test pass (tests/gpu, tests/unit, import
# graph; 8 workers, validation on). Carry .gl .whl .assets-final .assets-c.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-final/models
S=$VKPBR_ASSETS/Sponza/glTF/Sponza.gltf
rows() { grep -E "^\|" | grep -v "^|---"; }
clock() { nvidia-smi --query-gpu=clocks.sm,power.draw --format=csv,noheader; }
for i in 1 2; do
  echo "== crowd $i ($(clock))"; timeout 45 python3 benchmarks/bench_living.py --assets $PWD/.assets-c/models --only crowd --crowds 1000 --shadow-steps --frames 120 2>&1 | rows | tail -2
done
timeout 60 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p 2>&1 | rows
HYPOTHESIS_PROFILE=report timeout -s INT 170 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -30
