# H200 run i (session 17): masked big triangles shared by slices of work groups. The shadow
# GPU tests; the walk's frames by layers redrawn with the kernels timed apart; the walk
# (bench_shadows --only walk); vkpbr bench's Sponza rows (the moving one redraws the point
# light's cube every frame). Carry .gl .whl .assets-s.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
S=$VKPBR_ASSETS/Sponza/glTF/Sponza.gltf
rows() { grep -E "^\|" | grep -v "^|---"; }
timeout 100 python3 -m pytest -q -n 4 -p no:cacheprovider -rfE --tb=short tests/gpu/test_shadow_raster.py tests/gpu/test_world_shadows.py tests/gpu/test_shadow_cache.py tests/gpu/test_shadows.py 2>&1 | tail -3
timeout 80 python3 benchmarks/probe_stream.py --scene $S --frames 400 --redraws-only 2>&1 | grep -v "^|---"
timeout 100 python3 benchmarks/bench_shadows.py --scene $S --only maps,walk --frames 600 2>&1 | rows
timeout 60 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p 2>&1 | rows
