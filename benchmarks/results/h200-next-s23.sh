# H200, for the next session with a device (session 23 had none): scrolling cascades
# (47643fd..) and kept maps (c3446ca..) against the tree before them (141412e, carried as .old/src:
# `git archive 141412e src | tar -x -C .old`), alternating in one lease.
# Carry .gl .whl .assets-s .old. Writes $OUT/{redraws,probe,walk,moving}-{old,new}-N.txt; one pass (N,
# default 1) a call: `N=2 bash ...` for the second; `N=3` the new tree's bench rows and the
# worlds' kept map (bench.txt, kept-*.txt) (a pass is ~5 min; the old tree's moving rows run the new bench_shadows: their "one pass" rows equal its plain ones).
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
for n in $([ "${N:-1}" = 3 ] || echo ${N:-1}); do
  for tree in old new; do
    [ $tree = old ] && P="PYTHONPATH=/tmp/site:$PWD/.old/src" || P=""
    env $P timeout 60 python3 benchmarks/probe_stream.py --scene $S --frames 400 --redraws-only > $OUT/redraws-$tree-$n.txt 2>&1
    env $P timeout 60 python3 benchmarks/probe_stream.py --scene $S --frames 600 --cameras walk > $OUT/probe-$tree-$n.txt 2>&1
    env $P timeout 70 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 600 > $OUT/walk-$tree-$n.txt 2>&1
    env $P timeout 90 python3 benchmarks/bench_shadows.py --scene $S --only moving --moving 3,100 --frames 300 > $OUT/moving-$tree-$n.txt 2>&1
    echo "== $tree $n"; grep -E "^\| [0-9]" $OUT/redraws-$tree-$n.txt | cut -c1-160
    grep -E "^\| walk" $OUT/probe-$tree-$n.txt | cut -d'|' -f2-9; grep -E "^\| walk \+" $OUT/walk-$tree-$n.txt | cut -d'|' -f2-8
    grep -E "^\| sponza sun" $OUT/moving-$tree-$n.txt | cut -d'|' -f2-9
  done
done
# `vkpbr bench`'s Sponza rows (BENCHMARKS.md's), the new tree: still, 100 moving, 3 moving.
[ "${N:-1}" = 3 ] && timeout 150 python3 -m vkpbr bench --sponza $S --scenario sponza-1080p --scenario sponza-moving-1080p --scenario sponza-few-moving-1080p > $OUT/bench.txt 2>&1; tail -4 $OUT/bench.txt
# Worlds' own maps with and without the kept map (the new tree alone: keep_still alternates).
[ "${N:-1}" = 3 ] && timeout 120 python3 benchmarks/probe_world_kept.py --worlds 1024 --size 128x128 --steps 4 --rounds 2 --steps-apart > $OUT/kept-tabletop.txt 2>&1; tail -3 $OUT/kept-tabletop.txt
[ "${N:-1}" = 3 ] && timeout 120 python3 benchmarks/probe_world_kept.py --sponza $S --worlds 256 --steps 2 --rounds 2 > $OUT/kept-sponza.txt 2>&1; tail -3 $OUT/kept-sponza.txt
[ "${N:-1}" = 1 ] && timeout 120 python3 -m pytest -q -p no:cacheprovider tests/gpu/test_shadow_cache.py tests/gpu/test_shadow_raster.py > $OUT/tests.txt 2>&1; tail -3 $OUT/tests.txt
# N=4 (session 24, no device either): its new tests on the NVIDIA driver (the headlight's
# NaN fix, the caches' random sequences, the worlds' masked alpha), and the GPU test pass.
[ "${N:-1}" = 4 ] && VKPBR_ASSETS=$PWD/.assets-s/models HYPOTHESIS_PROFILE=report timeout -s INT 500 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1; tail -5 $OUT/gpu-tests.log
