#!/usr/bin/env bash
# Device-tool run for the speed issues: `vkpbr bench --peers` (vkpbr beside pyrender and pygfx
# in one run) and the Sponza breakdown. Carry .gl-peers, .whl, .whl-peers, .assets.
# .assets/models/Sponza/glTF is Sponza/glTF with its JPEGs re-encoded at quality 85 (same resolution) to
# fit the transfer limit; every renderer loads the same files.
set -uo pipefail
FRAMES=${FRAMES:-200}
python3 -m pip install -q --no-index --no-deps --no-compile --upgrade --target /tmp/site .whl/*.whl 2>/dev/null || exit 1
source benchmarks/peers_env.sh  # .gl-peers, .whl-peers -> /tmp/peers; PYTHONPATH, EGL
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
python3 -m vkpbr bench --frames "$FRAMES" --sponza .assets/models/Sponza/glTF/Sponza.gltf --peers --json > "$OUT/bench.json" 2> "$OUT/bench.err"
python3 - "$OUT/bench.json" <<'PY'
import json, sys
text = open(sys.argv[1]).read()
rows = json.loads(text[: text.index("]") + 1]) if text.strip().startswith("[") else []
from vkpbr.app.bench_cmd import print_table
print_table(rows)
print(text[text.index("]") + 1:])
PY
tail -3 "$OUT/bench.err"
python3 benchmarks/bench_sponza.py --frames 50 --json "$OUT/sponza.json" 2>&1 | tail -20
