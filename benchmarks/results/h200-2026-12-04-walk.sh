# H200 run (session 16, branch s16-walk, issue 31): the sun's walk through render() against the
# point light's, before (main 4220a20) and after (this branch). The row is bench_shadows
# "walk + sun" fps_render (356 before; the target >= 392, within 10% of "walk + point" 436).
# Then each frame's Python alone (profile_walk.py --python: still/walk with the sun, the walk
# with Sponza's point light, both shadow_raster modes).
# Make the before tree next to this one first:
#   rm -rf .before-walk && mkdir .before-walk && git archive 4220a20 src | tar -x -C .before-walk
# Carry .gl .whl .assets-final .before-walk. About 4 min.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models; S=$A/Sponza/glTF/Sponza.gltf
t() { timeout "$1" "${@:2}"; }
rows() { grep -E "^\|" | grep -v "^|---"; }
B="env PYTHONPATH=/tmp/site:$PWD/.before-walk/src"
for tree in before after; do
  run=""; [ $tree = before ] && run=$B
  echo "== bench_shadows --only walk ($tree)"
  t 150 $run python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 300 2>&1 | rows
  echo "== Python alone per frame ($tree)"
  t 120 $run python3 benchmarks/profile_walk.py --scene $S --python --frames 300 2>&1 | rows
done
