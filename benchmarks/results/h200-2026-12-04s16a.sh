# H200 run a (session 16, the merged tree c702424): the numbers session 15 could not take
# (Python a worlds step after pystep3; the 1,000-CesiumMan crowd since its frames read the
# compute-drawn maps from their buffer), the walk with the sun, then the GPU test pass.
# Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
A=$PWD/.assets-final/models; S=$A/Sponza/glTF/Sponza.gltf
export VKPBR_ASSETS=$A
P="benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 30 --bare"
rows() { grep -E "^\|" | grep -v "^|---"; }
echo "== step plain"; timeout 90 python3 $P 2>&1 | rows
echo "== step prepared"; timeout 60 python3 $P --prepared 2>&1 | rows
echo "== step prepared, frames view"; timeout 60 python3 $P --prepared --frames view 2>&1 | rows
echo "== crowd"; timeout 90 python3 benchmarks/bench_living.py --assets $A --only crowd --crowds 1000 --shadow-steps --frames 100 2>&1 | rows
echo "== walk"; timeout 90 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 300 2>&1 | rows
echo "== tests"
G=tests/gpu; HYPOTHESIS_PROFILE=report timeout -s INT 170 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=line tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  |^/.*Error" $OUT/gpu-tests.log | cut -c1-300 | head -30
