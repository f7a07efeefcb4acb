# H200 run h (session 17): the walk's frames by layers redrawn with the compute shadow
# kernels timed apart (probe_stream.py --redraws-only); Python a CUDA worlds step (frames
# view) and its cProfile. Carry .gl .whl .assets-s.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
S=$VKPBR_ASSETS/Sponza/glTF/Sponza.gltf
timeout 80 python3 benchmarks/probe_stream.py --scene $S --frames 400 --redraws-only 2>&1 | grep -v "^|---"
P="benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 60 --bare --prepared --frames view"
timeout 120 python3 $P > $OUT/step.txt 2>&1; grep -E "^\|" $OUT/step.txt | grep -E "alone|short" || tail -5 $OUT/step.txt
timeout 120 python3 $P --cprofile 60 > $OUT/step-profile.txt 2>&1; tail -3 $OUT/step-profile.txt
