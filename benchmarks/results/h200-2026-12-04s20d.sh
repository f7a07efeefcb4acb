# H200 run d (session 20): the crowd's GPU ms (1,000 CesiumMan, 1080p) three times, each its
# own process, with the GPU's SM clock, power and utilisation sampled every 50 ms during it
# (session 17 found 1.28 ms in one process and 3.3-4.9 in others, every step scaled alike).
# Carry .gl .whl .assets-c.
source benchmarks/gpu_env.sh
rows() { grep -E "^\|" | grep -v "^|---"; }
for i in 1 2 3; do
  nvidia-smi --query-gpu=clocks.sm,clocks.mem,power.draw,utilization.gpu,pstate --format=csv,noheader,nounits -lms 50 > /tmp/clk$i.csv &
  smi=$!
  echo "== crowd $i"; timeout 60 python3 benchmarks/bench_living.py --assets $PWD/.assets-c/models --only crowd --crowds 1000 --shadow-steps --frames 120 2>&1 | rows | tail -2
  kill $smi; wait $smi 2>/dev/null
  python3 - /tmp/clk$i.csv <<'PY'
import sys, statistics as st
rows = [l.split(",") for l in open(sys.argv[1]) if l.strip()]
sm = [float(r[0]) for r in rows]; mem = [float(r[1]) for r in rows]; pw = [float(r[2]) for r in rows]; ut = [float(r[3]) for r in rows]
q = lambda v: f"min {min(v):.0f} median {st.median(v):.0f} max {max(v):.0f}"
print(f"   samples {len(rows)}; SM MHz {q(sm)}; mem MHz {q(mem)}; W {q(pw)}; util% {q(ut)}; pstates {sorted(set(r[4].strip() for r in rows))}")
busy = [s for s, u in zip(sm, ut) if u > 20]
if busy: print(f"   while util > 20%: SM MHz {q(busy)} ({len(busy)} samples)")
PY
done
