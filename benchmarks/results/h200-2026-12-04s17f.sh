# H200 run f (session 17's last code): repeats, each its own process: the crowd (twice), the
# walk (bench_shadows --only walk), Python a CUDA worlds step (frames view).
# Carry .gl .whl .assets-s .assets-c.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
rows() { grep -E "^\|" | grep -v "^|---"; }
clock() { nvidia-smi --query-gpu=clocks.sm,clocks.mem,power.draw --format=csv,noheader; }
for i in 1 2; do
  echo "== crowd $i ($(clock))"; timeout 45 python3 benchmarks/bench_living.py --assets $PWD/.assets-c/models --only crowd --crowds 1000 --shadow-steps --frames 60 2>&1 | rows | tail -2
done
echo "== walk ($(clock))"; timeout 100 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 600 2>&1 | rows
P="benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 60 --bare --prepared --frames view"
for i in 1 2; do echo "== step $i"; timeout 40 python3 $P 2>&1 | grep -E "^\|" | grep -E "alone|short"; done
