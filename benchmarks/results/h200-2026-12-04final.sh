# H200 final run (session 15, the merged tree): the 100-scene job (scenekeep: what set_scene
# keeps), Python a worlds step (pystep3), the headline frames, then the GPU test pass on 8
# workers. No before tree (the carry limit): the job's ratio is to one scene in the same run;
# the step's and frames' before are session 14's runs s/t (another lease). Budget: ~6 min of device time left.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models; S=$A/Sponza/glTF/Sponza.gltf
echo "== job"; timeout 120 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 2>&1 | grep -E "^\||per model" | grep -v "^|---"
echo "== step"; for f in "" "--prepared"; do timeout 40 python3 benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 30 --bare $f 2>&1 | grep -E "^\|" | grep -v "^|---"; done
echo "== bench"; timeout 40 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p 2>&1 | grep -E "^\|" | grep -v "^|---"
echo "== tests"
G=tests/gpu; HYPOTHESIS_PROFILE=report VKPBR_ASSETS=$A timeout -s INT 150 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=line $G/test_shadow_raster.py $G/test_shadows.py $G/test_shadow_cache.py $G/test_world_shadows.py $G/test_batch.py $G/test_compute_path.py $G/test_scene_swap.py $G/test_kept.py $G/test_worlds.py $G/test_worlds_cuda.py $G/test_batch_cache.py $G/test_ao_paths.py $G/test_ao.py $G/test_leaks.py $G/test_instances.py $G/test_tbn_paths.py $G/test_frames_folder.py $G/test_material_layers.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  |^/.*Error" $OUT/gpu-tests.log | cut -c1-300 | head -30
