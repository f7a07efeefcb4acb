# H200 run a (session 17): where the sun walk's time goes (bench_paths: per step GPU ms,
# layers a frame, frames/s; still / walk with the sun / walk with the point light), the crowd's
# steps, the CUDA worlds tests (the short way made after a replay: session 16 left it unrun).
# Carry .gl .whl .assets-s .assets-c.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
rows() { grep -E "^\|" | grep -v "^|---"; }
timeout 90 python3 -m pytest -q -p no:cacheprovider -rfE --tb=short tests/gpu/test_worlds_cuda.py 2>&1 | tail -5
timeout 150 python3 benchmarks/bench_paths.py --scene $S --sizes 1920x1080 --rows pbr/sun/still,pbr/sun/moving,pbr/scene/moving --paths compute/compute --lights "" --frames 600 2>&1 | rows
timeout 60 python3 benchmarks/bench_living.py --assets $PWD/.assets-c/models --only crowd --crowds 1000 --shadow-steps --frames 60 2>&1 | rows | tail -3
