# H200 run g (session 19): how many cores the host gives CPU-bound work (N processes of a
# pure-Python loop at once: the wall clock of each N); the 100-scene job on 6 renderer
# processes with each item's CPU split into user and system time; `vkpbr batch` without Ray
# installed (its fallback to renderer processes) on a small job.
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
for n in 1 4 8 12 16; do
  s=$(date +%s.%N); for i in $(seq $n); do python3 -c "sum(i*i for i in range(6_000_000))" & done; wait
  echo "cpu loop x$n: $(python3 -c "import time; print(f'{time.time() - $s:.2f} s')")"
done
rows() { grep -E "^\||not measured|failed|item's" | grep -v "^|---"; }
timeout 100 python3 benchmarks/bench_load.py --models $A --no-load --scenes 100 --views 16 --job-runs cold,warm --no-in-process --processes 6 2>&1 | rows
mkdir -p /tmp/j && cd /tmp/j && echo '["3,1.2,2,0,0,0", "2,1,3,0,0,0", "-2,1.5,3,0,0,0", "0,2,3,0,0,0"]' > poses.json
echo "[{\"scene\": \"$A/DamagedHelmet/glTF/DamagedHelmet.gltf\", \"cameras\": \"poses.json\", \"out\": \"h\"}, {\"scene\": \"$A/CesiumMilkTruck/glTF/CesiumMilkTruck.gltf\", \"cameras\": \"poses.json\", \"out\": \"t\"}]" > job.json
timeout 60 python3 -m vkpbr -v batch job.json; echo "exit $?"; ls h t | head -12
