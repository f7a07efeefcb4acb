# H200 run a (session 22): where the sun walk's host time goes through render_many (a frame's
# draw, wait, readback and the rest; cProfile of the walk into NumPy), the walk's rows, and
# Python a CUDA worlds step with its cProfile. Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-final/models
S=$VKPBR_ASSETS/Sponza/glTF/Sponza.gltf
nvidia-smi --query-gpu=name,clocks.sm,clocks.mem,pstate --format=csv > $OUT/smi.txt
timeout 150 python3 benchmarks/probe_stream.py --scene $S --frames 600 --cameras still,walk --profile $OUT/walk-profile.txt > $OUT/probe.txt 2>&1
grep -v "^|---" $OUT/probe.txt | head -12
timeout 150 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 600 > $OUT/walk.txt 2>&1; grep -E "walk" $OUT/walk.txt | head
P="benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 60 --bare --prepared --frames view"
timeout 120 python3 $P > $OUT/step.txt 2>&1; grep -E "^\|" $OUT/step.txt | grep -E "alone|short" || tail -5 $OUT/step.txt
timeout 120 python3 $P --cprofile 60 > $OUT/step-profile.txt 2>&1; tail -3 $OUT/step-profile.txt
