# H200 run b (session 22): the streamed walk's draws by size (median, p95, max) and the
# recordings they made. Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
S=$PWD/.assets-final/models/Sponza/glTF/Sponza.gltf
timeout 150 python3 benchmarks/probe_stream.py --scene $S --frames 600 --cameras walk > $OUT/probe.txt 2>&1
grep -v "^|---" $OUT/probe.txt | head -8
