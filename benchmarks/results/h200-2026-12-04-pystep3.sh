# H200 run (session 15, pystep3 / issue 32): the Python of one worlds step before and after
# pystep3, CUDA poses into torch (profile_worlds_step.py --torch), plain, prepared
# (batch_step) and prepared with frames="view" (no clone of the frames; after only), then
# the CUDA tests (test_worlds_cuda.py has frames='view''s test; it skips on lavapipe).
# Before the call, from the repository root (main with pystep3 merged):
#   rm -rf .before3 && mkdir -p .before3 && git archive 89ad009 src | tar -x -C .before3
# (89ad009: main's HEAD when pystep3 branched; the old .before3 is another session's tree)
# Carry .gl .whl .assets-worlds .before3 (torch is the machine's own, as in runs k and s;
# .whl-worlds, 83 MiB, does not fit the 64 MiB carry and is not needed here).
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-worlds/models
t() { timeout "$1" "${@:2}"; }
P="benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 30 --bare"
rows() { grep -E "^\|" | grep -E "Python|submit|GPU wait|replayed|last_stats"; }
for tree in before after before after; do
  run=""; [ $tree = before ] && run="env PYTHONPATH=/tmp/site:$PWD/.before3/src"
  echo "== $tree plain";    t 60 $run python3 $P 2>&1 | rows
  echo "== $tree prepared"; t 60 $run python3 $P --prepared 2>&1 | rows
done
echo "== after prepared, frames='view' (batch_step(frames='view'): no clone)"
t 60 python3 $P --prepared --frames view 2>&1 | rows
echo "== the call list of a replayed step, NumPy poses (world_expand=gpu), after"
t 60 python3 benchmarks/bench_step_calls.py --worlds 4096 --size 128 --steps 20 --top 40 2>&1 | head -30
timeout -s INT 120 python3 -m pytest -q -p no:cacheprovider tests/gpu/test_worlds_cuda.py tests/gpu/test_batch_cache.py 2>&1 | grep -E "^E |passed|failed" | head -12
