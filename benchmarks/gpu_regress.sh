#!/usr/bin/env bash
# One device-tool run that measures the must-not-regress numbers for two trees in the same
# lease: BEFORE_TREE (default .before: `git archive <commit> src benchmarks/bench_paths.py
# benchmarks/peers/common.py tests/assets_path.py`, unpacked) and AFTER_TREE (default this
# checkout). Each tree runs with its own PYTHONPATH (its src/) and its own bench_paths.py.
#
# Steps (in this order; before then after in each, so drift between rounds shows):
#   headline r1   `vkpbr bench --scenario sponza-1080p --scenario sponza-480p` (FRAMES)
#   walk r1       bench_paths.py: compute/compute, course/scene/still and pbr/sun/moving (the
#                 walking camera with the sun's cascades), 1920x1080 and 640x480 (PATHS_FRAMES)
#   others        `vkpbr bench`'s other frame scenarios (OTHER_FRAMES)
#   headline r2, walk r2 (ROUNDS=2)
#   batch         `vkpbr bench`'s batch-* scenarios but -forward (VIEWS poses, BATCH_VIEWS_PER_CALL
#                 views a render_batch call, BATCH_FRAMES views timed at least, median of the calls)
#   batchfwd      the batch-*-forward ones (the layered batch; FWD_BATCH_VIEWS_PER_CALL a call)
# then one table: scenario, metric, before, after, change % (medians of the rounds; the runs
# beside them where a tree ran more than once).
#
# Make the carry here first: `bash benchmarks/fetch_device_carry.sh` (.gl .whl .assets-peers),
# then `mkdir -p .before && git archive <commit> src benchmarks/bench_paths.py
# benchmarks/peers/common.py tests/assets_path.py | tar -x -C .before` (the batch scenarios
# read benchmarks/peers/common.py beside their src/, bench_paths.py imports the tree's own
# names). Device call (about 5 minutes on the H200; DEADLINE keeps it inside 600 s), carry
# [".gl", ".whl", ".assets-peers", ".before"] (about 46 MiB with the tree), timeout_s 600:
#   set -o pipefail; bash benchmarks/gpu_regress.sh 2>&1 | tee $OUT/regress.txt
# Here on lavapipe (no setup, .venv's Python; a few minutes):
#   QUICK=1 OUT=/tmp/regress-out bash benchmarks/gpu_regress.sh
# Only the table again, from a run's JSON lines:  TABLE=path/regress.jsonl bash benchmarks/gpu_regress.sh
#
# $OUT gets regress.jsonl (one line per result row: tree, round, step, the tool's row),
# regress.log (every tool's stdout and stderr, nvidia-smi), regress-table.md (the table).
# Environment: QUICK=1 (tiny sizes and frame counts), BEFORE_TREE, AFTER_TREE (e.g.
# AFTER_TREE=.before to test with after = before), FRAMES, OTHER_FRAMES, PATHS_FRAMES,
# PATHS_SIZES, PATHS_ROWS, PATHS_PATHS, HEADLINE, OTHERS, BATCH, BATCHFWD (scenario lists),
# VIEWS, BATCH_VIEWS_PER_CALL, BATCH_FRAMES, FWD_BATCH_VIEWS_PER_CALL, FWD_BATCH_FRAMES, ROUNDS,
# STEP_TIMEOUT, STEPS (any of headline walk others batch batchfwd), DEADLINE (seconds from the
# start after which no step starts; each step's timeout is cut to what is left), WORSE_PCT,
# DEVICE_SETUP (1: unpack .gl and the wheels through gpu_env.sh; default: 1 where nvidia-smi
# is found), PY.
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
WORK=${WORK:-/tmp/regress-work}
mkdir -p "$WORK"
TOOL=$WORK/regress_tool.py
cat > "$TOOL" <<'PY'
"""gpu_regress.sh's helper (standard library only): `add` turns one tool run's output into
JSON lines; `table` prints the before/after table from them."""
import json
import statistics
import sys
from pathlib import Path

FRAME = (("fps_readback", "frames/s (NumPy)", 1), ("fps_render_only", "frames/s (render only)", 1),
         ("gpu_ms", "GPU ms/frame", -1), ("python_ms", "Python ms/frame", -1))
BATCH = (("views_per_s_readback", "views/s (NumPy)", 1), ("views_per_s_render_only", "views/s (GPU only)", 1))
WALK = (("python_ms", "Python alone ms", -1), ("cpu_ms", "draw() ms", -1), ("gpu_ms", "GPU ms (median)", -1),
        ("gpu_ms_mean", "GPU ms (mean)", -1), ("fps_readback", "frames/s (NumPy)", 1))
WALK_STILL = tuple(m for m in WALK if m[0] != "gpu_ms_mean")  # a still camera's mean is its median


def walk_key(r):
    return f"walk {r['size']} {r.get('lighting')}/{r.get('light')}/{r['camera']} {r.get('pipeline')}/{r.get('raster')}"


def summary(r):
    if "views_per_s_readback" in r:
        return f"{r['scenario']}: {r['views_per_s_readback']:,.0f} views/s, GPU {r['gpu_ms']:.2f} ms a call"
    if "scenario" in r:
        return (f"{r['scenario']}: {r['fps_readback']:.1f} frames/s, GPU {r['gpu_ms']:.3f} ms, "
                f"Python {r['python_ms']:.3f} ms")
    return (f"{walk_key(r)}: Python alone {r['python_ms']:.3f} ms, draw() {r['cpu_ms']:.3f}, "
            f"GPU {r['gpu_ms']:.3f} (mean {r['gpu_ms_mean']:.3f}) ms")


def add(jsonl, tree, rnd, step, raw, rc, secs):
    text = Path(raw).read_text() if Path(raw).exists() else ""
    rows = []
    try:
        if step == "walk":
            rows = json.loads(text)["paths"] if text.strip() else []
        elif "[" in text:
            rows, _ = json.JSONDecoder().raw_decode(text[text.index("["):])
    except (ValueError, KeyError) as exc:
        print(f"    unreadable output: {exc}")
    with open(jsonl, "a") as f:
        for r in rows:
            r = {"tree": tree, "round": int(rnd), "step": step, **r}
            if step == "walk":
                r["key"] = walk_key(r)
            f.write(json.dumps(r) + "\n")
            try:
                print("    " + summary(r))
            except (KeyError, TypeError, ValueError) as exc:
                print(f"    a row without {exc}: {sorted(r)}")
        if int(rc) or not rows:
            f.write(json.dumps({"tree": tree, "round": int(rnd), "step": step, "error": int(rc),
                                "rows": len(rows), "seconds": float(secs)}) + "\n")


def table(jsonl, out_md, worse_pct):
    rows = [json.loads(line) for line in Path(jsonl).read_text().splitlines() if line.strip()]
    cells, order = {}, []
    for r in rows:
        if "error" in r:
            continue
        if r["step"] == "walk":
            key, metrics = r["key"], WALK if r.get("camera") == "moving" else WALK_STILL
        elif "views_per_s_readback" in r:
            key, metrics = f"{r['scenario']} (B={r['batch']})", BATCH
        else:
            key = r["scenario"]
            metrics = FRAME if r["step"] == "headline" else tuple(m for m in FRAME if m[0] != "fps_render_only")
        for field, label, sign in metrics:
            if field not in r:
                continue
            if (key, label) not in cells:
                order.append((key, label))
                cells[key, label] = {"sign": sign, "before": [], "after": []}
            cells[key, label][r["tree"]].append(float(r[field]))
    fmt = lambda v: f"{v:,.1f}" if abs(v) >= 100 else f"{v:.3f}"  # noqa: E731
    runs = lambda v: " / ".join(fmt(x) for x in v) if len(v) > 1 else ""  # noqa: E731
    lines = ["| scenario | metric | before | after | change % | | before runs | after runs |",
             "|---|---|---:|---:|---:|---|---|---|"]
    marks = []
    for key, label in order:
        c = cells[key, label]
        b, a = c["before"], c["after"]
        mb = statistics.median(b) if b else None
        ma = statistics.median(a) if a else None
        change, mark = "", ""
        if mb and ma is not None:
            pct = 100.0 * (ma - mb) / mb
            change = f"{pct:+.1f}"
            # WORSE / better: beyond WORSE_PCT, two runs or more a tree, and every after run
            # on that side of every before run; with "?": beyond it, but one run a tree or the
            # runs overlap
            good = pct * c["sign"]
            if abs(good) > worse_pct:
                sure = len(a) >= 2 and len(b) >= 2 and (max(a) < min(b) or min(a) > max(b))
                mark = ("better" if good > 0 else "WORSE") + ("" if sure else "?")
        marks.append(mark)
        lines.append(f"| {key} | {label} | {fmt(mb) if mb is not None else '-'} | "
                     f"{fmt(ma) if ma is not None else '-'} | {change} | {mark} | {runs(b)} | {runs(a)} |")
    errors = [r for r in rows if "error" in r]
    lines.append("")
    lines.append(f"{len(order)} rows (medians of the runs); WORSE: over {worse_pct:g}% in the bad "
                 f"direction, 2+ runs a tree, no overlap; WORSE?: one run a tree or overlapping runs. "
                 f"{marks.count('WORSE')} WORSE, {marks.count('WORSE?')} WORSE?")
    for e in errors:
        what = ("skipped: past DEADLINE" if e["error"] == -1 else
                f"rc {e['error']}{' (timeout)' if e['error'] in (124, 137) else ''}, {e['rows']} rows, "
                f"{e['seconds']:.0f} s (regress.log has its output)")
        lines.append(f"NOT MEASURED: {e['tree']} round {e['round']} {e['step']}: {what}")
    text = "\n".join(lines)
    print(text)
    if out_md:
        Path(out_md).write_text(text + "\n")


if __name__ == "__main__":
    if sys.argv[1] == "add":
        add(*sys.argv[2:9])
    else:
        table(sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else "", float(sys.argv[4]) if len(sys.argv) > 4 else 3.0)
PY

if [ -n "${TABLE:-}" ]; then
  python3 "$TOOL" table "$TABLE" "" "${WORSE_PCT:-3}"
  exit
fi

: "${OUT:?set OUT to the folder for the results}"
mkdir -p "$OUT"
JSONL=$OUT/regress.jsonl LOG=$OUT/regress.log
: > "$JSONL"; : > "$LOG"
if [ -z "${DEVICE_SETUP:-}" ]; then
  if command -v nvidia-smi >/dev/null; then DEVICE_SETUP=1; else DEVICE_SETUP=0; fi
fi
if [ "$DEVICE_SETUP" = 1 ]; then
  source benchmarks/gpu_env.sh  # .gl -> /, .whl -> /tmp/site, the NVIDIA ICD when needed
  SITE=/tmp/site:
  PY=${PY:-python3}
else
  SITE=
  export PYTHONDONTWRITEBYTECODE=1  # keep .before free of this machine's .pyc (it is carried)
  PY=${PY:-$( [ -x .venv/bin/python ] && echo "$ROOT/.venv/bin/python" || echo python3 )}
fi
export PYTHONUNBUFFERED=1 VKPBR_ASSETS=$ROOT/.assets-peers/models
unset PYTHONPATH
SPONZA=$VKPBR_ASSETS/Sponza/glTF/Sponza.gltf
[ -f "$SPONZA" ] || { echo "no $SPONZA: carry .assets-peers (benchmarks/fetch_device_carry.sh)"; exit 1; }

if [ "${QUICK:-0}" = 1 ]; then  # lavapipe: end to end in minutes, numbers meaningless
  : "${FRAMES:=2}" "${OTHER_FRAMES:=2}" "${PATHS_FRAMES:=2}" "${PATHS_SIZES:=160x120}"
  : "${HEADLINE:=sponza-480p}" "${OTHERS:=spheres-100}" "${BATCH:=batch-helmet-128 batch-sponza-128}"
  : "${BATCHFWD:=batch-helmet-128-forward}" "${VIEWS:=4}" "${BATCH_VIEWS_PER_CALL:=4}" "${BATCH_FRAMES:=4}"
  : "${FWD_BATCH_VIEWS_PER_CALL:=4}" "${FWD_BATCH_FRAMES:=4}" "${PATHS_PATHS:=forward/hardware,compute/compute}"
  : "${DEADLINE:=3000}" "${STEP_TIMEOUT:=900}"
fi
FRAMES=${FRAMES:-1000}
OTHER_FRAMES=${OTHER_FRAMES:-300}
PATHS_FRAMES=${PATHS_FRAMES:-300}
PATHS_SIZES=${PATHS_SIZES:-1920x1080,640x480}
PATHS_ROWS=${PATHS_ROWS:-course/scene/still,pbr/sun/moving}
PATHS_PATHS=${PATHS_PATHS:-compute/compute}
HEADLINE=${HEADLINE:-sponza-1080p sponza-480p}
OTHERS=${OTHERS:-default-1080p spheres-100 spheres-5k sponza-1080p-forward sponza-1080p-compute sponza-1080p-compute-raster sponza-480p-forward sponza-480p-compute sponza-480p-compute-raster}
BATCH=${BATCH:-batch-sponza-128 batch-sponza-512 batch-helmet-128 batch-helmet-512 batch-sponza-128-compute batch-sponza-512-compute batch-helmet-128-compute batch-helmet-512-compute}
BATCHFWD=${BATCHFWD:-batch-sponza-128-forward batch-sponza-512-forward batch-helmet-128-forward batch-helmet-512-forward}
VIEWS=${VIEWS:-256}
BATCH_VIEWS_PER_CALL=${BATCH_VIEWS_PER_CALL:-1024}
BATCH_FRAMES=${BATCH_FRAMES:-5120}  # calls timed: max(3, ceil(BATCH_FRAMES / views a call)), after 4 warm-ups
FWD_BATCH_VIEWS_PER_CALL=${FWD_BATCH_VIEWS_PER_CALL:-512}
FWD_BATCH_FRAMES=${FWD_BATCH_FRAMES:-2560}
ROUNDS=${ROUNDS:-2}
STEPS=${STEPS:-headline walk others batch batchfwd}
DEADLINE=${DEADLINE:-530}
STEP_TIMEOUT=${STEP_TIMEOUT:-180}
WORSE_PCT=${WORSE_PCT:-3}

tree_dir() { local d; [ "$1" = before ] && d=${BEFORE_TREE:-.before} || d=${AFTER_TREE:-.}; (cd "$d" && pwd); }
BEFORE=$(tree_dir before) || exit 1
AFTER=$(tree_dir after) || exit 1
digest() { (cd "$1" && find src -type f \( -name '*.py' -o -name '*.spv' \) | LC_ALL=C sort | xargs cat | sha1sum | cut -c1-12); }
gpu_state() { command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=clocks.sm,clocks.mem,temperature.gpu,power.draw,pstate --format=csv,noheader | sed "s/^/  GPU now ($1): /"; }

if command -v nvidia-smi >/dev/null; then
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
  nvidia-smi >> "$LOG" 2>&1
fi
for t in before after; do
  d=$(tree_dir $t)
  [ -f "$d/benchmarks/bench_paths.py" ] || echo "warning: $d/benchmarks/bench_paths.py missing (walk steps of $t fail)"
  echo "$t: $d (src sha1 $(digest "$d")): $(PYTHONPATH=$SITE$d/src "$PY" -c 'import vkpbr, sys; print(vkpbr.__file__, "Python", sys.version.split()[0])' 2>&1 | tail -1)"
done
[ "$(digest "$BEFORE")" = "$(digest "$AFTER")" ] && echo "note: before and after have the same src"
PYTHONPATH=$SITE$AFTER/src "$PY" -m vkpbr info 2>&1 | head -1
gpu_state start
echo "frames: headline $FRAMES, others $OTHER_FRAMES, walk $PATHS_FRAMES; batch $VIEWS poses, $BATCH_VIEWS_PER_CALL a call ($FWD_BATCH_VIEWS_PER_CALL forward); deadline ${DEADLINE}s"

scenario_args() { local a=() s; for s in "$@"; do a+=(--scenario "$s"); done; echo "${a[@]}"; }

run_step() {  # tree round step
  local tree=$1 rnd=$2 step=$3 d raw left to t0 rc
  d=$(tree_dir "$tree")
  left=$((DEADLINE - SECONDS))
  if ((left < 20)); then
    printf '[%4ds] %-6s r%s %-8s skipped: past the deadline\n' $SECONDS "$tree" "$rnd" "$step"
    echo "{\"tree\": \"$tree\", \"round\": $rnd, \"step\": \"$step\", \"error\": -1, \"rows\": 0, \"seconds\": 0}" >> "$JSONL"
    return
  fi
  to=$STEP_TIMEOUT; ((to > left)) && to=$left
  raw=$WORK/$tree-$rnd-$step.json; rm -f "$raw"
  t0=$SECONDS
  echo "== [$SECONDS s] $tree round $rnd: $step (timeout $to s)" >> "$LOG"
  export PYTHONPATH=$SITE$d/src VKPBR_CACHE_DIR=$WORK/cache-$tree
  case $step in
    headline|others|batch|batchfwd)
      local names=$HEADLINE frames=$FRAMES per_call=$BATCH_VIEWS_PER_CALL
      [ "$step" = others ] && { names=$OTHERS; frames=$OTHER_FRAMES; }
      [ "$step" = batch ] && { names=$BATCH; frames=$BATCH_FRAMES; }
      [ "$step" = batchfwd ] && { names=$BATCHFWD; frames=$FWD_BATCH_FRAMES; per_call=$FWD_BATCH_VIEWS_PER_CALL; }
      [ -n "$names" ] || { unset PYTHONPATH; return; }
      # shellcheck disable=SC2046
      timeout -k 5 "$to" "$PY" -m vkpbr bench --json --sponza "$SPONZA" --frames "$frames" \
        --views "$VIEWS" --batch-views "$per_call" --poses-dir "$WORK/poses" \
        $(scenario_args $names) > "$raw" 2>> "$LOG"
      rc=$? ;;
    walk)
      timeout -k 5 "$to" "$PY" "$d/benchmarks/bench_paths.py" --scene "$SPONZA" --frames "$PATHS_FRAMES" \
        --sizes "$PATHS_SIZES" --lights "" --rows "$PATHS_ROWS" --paths "$PATHS_PATHS" --json "$raw" >> "$LOG" 2>&1
      rc=$? ;;
  esac
  unset PYTHONPATH
  [ -s "$raw" ] && [ "$step" != walk ] && cat "$raw" >> "$LOG"
  printf '[%4ds] %-6s r%s %-8s %3d s, rc %d\n' $SECONDS "$tree" "$rnd" "$step" $((SECONDS - t0)) $rc
  ((rc)) && tail -n 2 "$LOG" | cut -c1-200 | sed 's/^/    | /'
  python3 "$TOOL" add "$JSONL" "$tree" "$rnd" "$step" "$raw" "$rc" $((SECONDS - t0))
}
has() { [[ " $STEPS " == *" $1 "* ]]; }

for rnd in $(seq 1 "$ROUNDS"); do
  for step in headline walk others; do
    has $step || continue
    [ "$step" = others ] && [ "$rnd" != 1 ] && continue
    for tree in before after; do run_step $tree "$rnd" $step; done
  done
  gpu_state "after round $rnd"
done
for step in batch batchfwd; do
  has $step || continue
  for tree in before after; do run_step $tree 1 $step; done
done
gpu_state end
echo "total ${SECONDS}s"
echo
echo "## before ($BEFORE, $(digest "$BEFORE")) -> after ($AFTER, $(digest "$AFTER")): medians over rounds"
python3 "$TOOL" table "$JSONL" "$OUT/regress-table.md" "$WORSE_PCT"
