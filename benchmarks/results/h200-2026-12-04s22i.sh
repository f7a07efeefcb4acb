# H200 run i (session 22, the final code: kept kernel threads, the collector's 24 MiB rule):
# the streamed walk once more (probe_stream's walk rows, bench_shadows' walk rows).
# Carry .gl .whl .assets-s.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
timeout 60 python3 benchmarks/probe_stream.py --scene $S --frames 600 --cameras walk > $OUT/probe.txt 2>&1; grep -E "^\| walk" $OUT/probe.txt
timeout 70 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 600 > $OUT/walk.txt 2>&1; grep -E "^\| walk \+" $OUT/walk.txt | cut -d'|' -f2-8
