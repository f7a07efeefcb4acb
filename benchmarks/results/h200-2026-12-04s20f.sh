# H200 run f (session 20): the 100-scene job, warm, on 6 renderer processes, alternating the
# tree before this session's memory and uniform changes (03c5be2: .before2's files) and this one, in the same
# lease (kept memory serving smaller requests, and 2 GiB of it kept on the H200); then this
# tree's Vulkan calls timed by name.
# Carry .gl .whl .assets-final .before2.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\||not measured|failed|item's|processes;" | grep -v "^|---"; }
# (.before2 holds only the files that differ, as they were at 03c5be2: laid over a copy)
mkdir -p /tmp/old && cp -r src /tmp/old/ && cp -r .before2/src /tmp/old/
python3 -m compileall -q -j 0 /tmp/old/src > /dev/null 2>&1
timeout 100 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs warm --no-in-process --processes 6 > /dev/null 2>&1  # (fills the caches)
for t in old new old new; do
  [ $t = old ] && P=/tmp/old/src || P=$PWD/src
  echo "== $t"; PYTHONPATH=/tmp/site:$P timeout 100 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs warm --no-in-process --processes 6 2>&1 | rows | grep -v "^| run"
done
timeout 100 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs warm --no-in-process --processes 6 --time-vk-calls /tmp/vkt 2>&1 | rows | head -8
# (Found after the run: bench_load's job made a new cache folder each run, so these "warm"
# rows, the only row of their runs, ran with empty bake and pipeline caches: cold rows.
# --cache-dir came with run g.)
