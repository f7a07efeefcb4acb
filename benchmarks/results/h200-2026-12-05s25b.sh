# H200 run b (session 25): `vkpbr bench`'s Sponza rows at this tree (still, 100 moving, 3
# moving), then h200-next-s23.sh's first A/B pass (scrolling cascades and kept maps against
# 141412e, carried as .old/src), then the worlds' kept map in Sponza. Carry .gl .whl .assets-s .old.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
timeout 150 python3 -m vkpbr bench --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p --scenario sponza-few-moving-1080p > $OUT/bench.txt 2>&1; tail -6 $OUT/bench.txt
N=2 bash benchmarks/results/h200-next-s23.sh 2>&1 | grep -v "^$" | grep -v passed
timeout 100 python3 benchmarks/probe_world_kept.py --sponza $S --worlds 256 --steps 2 --rounds 2 > $OUT/kept-sponza.txt 2>&1; tail -4 $OUT/kept-sponza.txt
