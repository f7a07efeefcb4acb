# H200 run k (session 13): before/after of "unclipped" (raster.comp, shadow_raster.comp), the
# merged helpers' rows. Carry .gl .whl .assets-peers .assets-worlds .before4 (HEAD~1 of the change).
source benchmarks/gpu_env.sh
S=.assets-peers/models/Sponza/glTF/Sponza.gltf; A=$PWD/.assets-peers/models
B="env PYTHONPATH=/tmp/site:$PWD/.before4/src"
t() { timeout "$1" "${@:2}"; }
for tree in before after; do
  run=""; [ $tree = before ] && run=$B
  cd $([ $tree = before ] && echo .before4 || echo .) >/dev/null
  t 60 $run python3 benchmarks/bench_paths.py --scene $OLDPWD/$S --frames 300 --sizes 1920x1080 --rows pbr/sun/still --paths compute/compute --lights 1 > $OUT/$tree-paths.txt 2>&1
  t 90 $run python3 benchmarks/bench_world_batches.py --assets $A --rows helmet-64 --worlds 8192 --steps 10 > $OUT/$tree-helmet.txt 2>&1
  t 60 $run python3 benchmarks/bench_shadows.py --scene $OLDPWD/$S --only maps --steps --frames 60 > $OUT/$tree-shadows.txt 2>&1
  cd - >/dev/null
done
t 40 python3 benchmarks/probe_kernels.py --scene $S > $OUT/kernels.txt 2>&1
t 90 python3 benchmarks/bench_living.py --assets $A --only crowd --crowds 1000 --frames 60 --json $OUT/living.json > $OUT/living.txt 2>&1
t 80 python3 benchmarks/bench_post.py --scene $S --only cube,batch --frames 100 > $OUT/post.txt 2>&1
export VKPBR_ASSETS=$PWD/.assets-worlds/models
t 60 python3 benchmarks/profile_worlds_step.py --variant tabletop --worlds 4096 --size 128 --torch --steps 200 > $OUT/pystep.txt 2>&1
t 60 python3 benchmarks/profile_worlds_step.py --variant tabletop --worlds 4096 --size 128 --torch --steps 200 --prepared > $OUT/pystep-prepared.txt 2>&1
t 90 python3 benchmarks/bench_worlds.py --worlds 1024,4096 --sizes 128x128 --shadows 256 > $OUT/worlds-shadows.txt 2>&1
for f in $OUT/*.txt; do echo "== $f"; grep -E "^\|" $f | tail -8; done
