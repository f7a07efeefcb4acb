# H200 run d (session 22): as run c, the collector copying alone (no copy threads: their
# hand-offs took the GIL from the drawing thread in run c); old = .old/src (3a375f5).
# Carry .gl .whl .assets-s .old.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
NEW=$PYTHONPATH; OLD=/tmp/site:$PWD/.old/src
rows() { grep -E "^\|" | grep -v "^|---"; }
export VKPBR_ASSETS=$PWD/.assets-s/models
timeout 100 python3 -m pytest -q -n 4 -p no:cacheprovider -rfE --tb=short tests/gpu/test_stream.py > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR|E )|passed|failed" $OUT/tests.txt | cut -c1-300 | head -20
for i in 1 2; do
  for tree in old new; do
    if [ $tree = old ]; then export PYTHONPATH=$OLD; else export PYTHONPATH=$NEW; fi
    L=$OUT/$tree$i.txt
    echo "## $tree ($i)" | tee $L
    timeout 100 python3 benchmarks/probe_stream.py --scene $S --frames 600 --cameras walk >> $L 2>&1
    timeout 120 python3 benchmarks/bench_shadows.py --scene $S --only walk --frames 600 >> $L 2>&1
    timeout 60 python3 -m vkpbr bench --frames 300 --sponza $S --scenario sponza-1080p >> $L 2>&1
    grep -E "^\| walk \| sun|^\| sponza" $L | cut -c1-150; grep -E "^\| walk \+" $L | cut -d'|' -f2-8
  done
done
