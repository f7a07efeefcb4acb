# H200 final run (session 15, the merged tree): the 100-scene job (scenekeep: what set_scene
# keeps), Python a worlds step (pystep3), the headline frames, then the GPU test pass on 8
# workers. No before tree (the carry limit): the job's ratio is to one scene in the same run;
# the step's and frames' before are session 14's runs s/t (another lease).
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models; S=$A/Sponza/glTF/Sponza.gltf
echo "== job"; timeout 150 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | grep -E "^\||per model" | grep -v "^|---"
echo "== step"; timeout 60 python3 benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 30 --bare 2>&1 | grep -E "^\|" | grep -v "^|---"
echo "== bench"; timeout 40 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p 2>&1 | grep -E "^\|" | grep -v "^|---"
echo "== tests"
HYPOTHESIS_PROFILE=report VKPBR_ASSETS=$A timeout -s INT 240 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=line tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  |^/.*Error" $OUT/gpu-tests.log | cut -c1-300 | head -30
