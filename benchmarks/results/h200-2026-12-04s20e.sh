# H200 run e (session 20): the frame's uniform blocks, lights, shadow matrices, post keys and
# a batch's view records in device-local host-visible memory (the GPU had read them from the
# host's memory) against the tree before (.before2, HEAD~0 without it), in the same lease:
# the crowd (x3 each, alternating, each its own process), vkpbr bench's Sponza rows, the walk
# with the sun through render_many.
# Carry .gl .whl .assets-s .assets-c .before2.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
rows() { grep -E "^\|" | grep -v "^|---"; }
NEW=$PWD/src; OLD=$PWD/.before2/src
for i in 1 2 3; do
  for t in old new; do
    [ $t = old ] && P=$OLD || P=$NEW
    echo "== crowd $t $i"; PYTHONPATH=/tmp/site:$P timeout 60 python3 benchmarks/bench_living.py --assets $PWD/.assets-c/models --only crowd --crowds 1000 --shadow-steps --frames 120 2>&1 | rows | tail -2
  done
done
for t in old new; do
  [ $t = old ] && P=$OLD || P=$NEW
  echo "== bench $t"; PYTHONPATH=/tmp/site:$P timeout 80 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p 2>&1 | rows
  echo "== walk $t"; PYTHONPATH=/tmp/site:$P timeout 100 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 600 2>&1 | rows
done
