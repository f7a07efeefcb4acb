# H200 run h (session 18): what makes this tree's many-scene job slower with a cold bake cache
# (run g: 71.8 views/s against df46ebc's 97.8): 50 scenes of the 18 models x 16 views, cold
# only, this tree, without the early scene change, with the actor's switch interval at 5 ms,
# both, and df46ebc.
# Carry .gl .whl .assets-final .before1.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
rows() { grep -E "^\|" | grep -v "^|---" | grep -v "^| run"; }
mkdir -p /tmp/before && cp -r src /tmp/before/ && cp -r .before1/src /tmp/before/
for cfg in "" "--no-switch" "--actor-switch-interval 0.005" "--no-switch --actor-switch-interval 0.005" "before"; do
  echo "== cold ${cfg:-(this tree)}"
  if [ "$cfg" = before ]; then
    PYTHONPATH=/tmp/site:/tmp/before/src timeout 60 python3 benchmarks/bench_load.py --models $A --no-load --scenes 50 --views 16 --job-runs cold 2>&1 | rows
  else
    timeout 60 python3 benchmarks/bench_load.py --models $A --no-load --scenes 50 --views 16 --job-runs cold $cfg 2>&1 | rows
  fi
done
