# H200 run d (session 17): a lone redraw of every cascade for new matrices copies them (no
# catch-up 8 frames on): the shadow GPU tests, the walk (bench_shadows --only walk), the
# walk's frames by layers redrawn (probe_stream.py, aligned), vkpbr bench's Sponza rows.
# Carry .gl .whl .assets-s.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
rows() { grep -E "^\|" | grep -v "^|---"; }
timeout 100 python3 -m pytest -q -n 4 -p no:cacheprovider -rfE --tb=short tests/gpu/test_shadow_raster.py tests/gpu/test_shadow_cache.py tests/gpu/test_worlds_cuda.py tests/gpu/test_shadows.py 2>&1 | tail -3
timeout 100 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 600 2>&1 | rows
timeout 80 python3 benchmarks/probe_stream.py --scene $S --frames 400 2>&1 | grep -v "^|---"
timeout 60 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p 2>&1 | rows
