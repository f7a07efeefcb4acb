# H200 run g (session 17): where Sponza's scene change goes (profile_swap.py --ahead, cProfile)
# and its file to first frame (bench_load.py, the load table: "again" is set_scene on the same
# Renderer); Python a CUDA worlds step (frames view) with its cProfile.
# Carry .gl .whl .assets-s.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
timeout 100 python3 benchmarks/profile_swap.py --models $PWD/.assets-s/models --names Sponza --rounds 3 --pipeline compute --ahead --profile $OUT/swap-sponza.txt 2>&1 | grep -E "^\|" | grep -v "^|---"
timeout 120 python3 benchmarks/bench_load.py --scene $S --no-job 2>&1 | grep -E "^\|" | grep -v "^|---"
P="benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 60 --bare --prepared --frames view"
timeout 120 python3 $P > $OUT/step.txt 2>&1; grep -E "^\|" $OUT/step.txt | grep -E "alone|short" || tail -5 $OUT/step.txt
timeout 120 python3 $P --cprofile 60 > $OUT/step-profile.txt 2>&1; tail -3 $OUT/step-profile.txt
