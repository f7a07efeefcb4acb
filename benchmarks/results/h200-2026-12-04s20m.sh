# H200 run m (session 20): the crowd's slow processes, narrowed: four processes, each
# measuring the 1,000-CesiumMan crowd on three Renderers in turn (--crowds 1000,1000,1000:
# a new device each): is slowness the process's or the device's?
# Carry .gl .whl .assets-c.
source benchmarks/gpu_env.sh
for i in 1 2 3 4; do
  echo "== process $i"; timeout 80 python3 benchmarks/bench_living.py --assets $PWD/.assets-c/models --only crowd --crowds 1000,1000,1000 --frames 60 2>&1 | grep -E "^\| crowd" | cut -d'|' -f2-7
done
