# H200 run b (session 17): the CUDA worlds tests (the short-way test given the steps the
# ring's frames need to replay again), the walk with the cascades' depth range to the scene's
# far bound (bench_shadows --only walk), a streamed frame's readback copy on the GPU
# (probe_readback.py). Carry .gl .whl .assets-s.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
rows() { grep -E "^\|" | grep -v "^|---"; }
timeout 90 python3 -m pytest -q -p no:cacheprovider -rfE --tb=short tests/gpu/test_worlds_cuda.py 2>&1 | tail -3
timeout 100 python3 benchmarks/probe_readback.py --scene $S --frames 400 2>&1 | grep -v "^|---"
timeout 100 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 600 2>&1 | rows
