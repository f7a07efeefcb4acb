# H200 run k (session 17): the crowd's GPU ms with the GPU idle between posed frames (as
# measured so far) and kept busy (--crowd-repeat 4: each pose's frame drawn 4 times, only the
# first timed), alternating, each its own process. Carry .gl .whl .assets-c.
source benchmarks/gpu_env.sh
rows() { grep -E "^\|" | grep -v "^|---"; }
clock() { nvidia-smi --query-gpu=clocks.sm,power.draw --format=csv,noheader; }
for rep in 1 4 1 4; do
  echo "== repeat $rep ($(clock))"; timeout 60 python3 benchmarks/bench_living.py --assets $PWD/.assets-c/models --only crowd --crowds 1000 --shadow-steps --frames 90 --crowd-repeat $rep 2>&1 | rows | tail -2
done
