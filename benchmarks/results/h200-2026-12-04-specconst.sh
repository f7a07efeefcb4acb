# H200 run (session 15, helper specconst, issue 31): the by-hand shadow reads behind
# specialisation constant 3 (shadow_sampling.glsl SHADOW_HAND_READS). Before: main's HEAD
# merged into the branch (63d2223), unpacked into .before1 first, here:
#   mkdir -p .before1 && git archive 63d2223 src | tar -x -C .before1
# Carry .gl .whl .assets-s (Sponza) .before1. About 7 minutes (the timeouts sum to 540 s).
# 1) the driver's statistics of the shading kernels built with the constant 1 (buffer-reading
#    frames) and 0 (frames that compare in hardware): registers / instructions should drop at 0;
# 2) the still and moving Sponza 1080p frames, compute shadows, before/after, twice:
#    bench_shadows.py --steps (shading_ms: the still frame's shading kernel time, 0.250 ms
#    before vs 0.235 without the by-hand code in run s) and bench_living.py's walk rows.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf; A=$PWD/.assets-s/models
t() { timeout "$1" "${@:2}"; }
t 60 python3 - "$S" <<'PY' 2>&1 | grep -E "^\||rror" | head -20
import sys
from vkpbr import Renderer
from vkpbr.scene.loader import load_scene
with Renderer(load_scene(sys.argv[1])) as r:
    kw = dict(lights=[r.automatic_sun()], size=(1920, 1080), pipeline="compute", raster="compute",
              shadow_raster="compute")
    r.render(**kw); r.render(**kw)  # a full redraw: the buffer (constant 1)
    r.shadows.forget(); r.render(**kw)
    assert r.shadows.reads_buffer
    for _ in range(10):  # SETTLE_FRAMES: the catch-up, then the images (constant 0)
        r.render(**kw)
    assert not r.shadows.reads_buffer
    for name, s in r.compute_scene().kernel_statistics().items():
        if name.startswith("shade_"):
            print(f"| {name} | " + " | ".join(f"{k}: {v}" for k, v in s.items()) + " |")
PY
for round in 1 2; do for tree in before after; do
  run=""; [ $tree = before ] && run="env PYTHONPATH=/tmp/site:$PWD/.before1/src"
  t 80 $run python3 benchmarks/bench_shadows.py --scene $S --only walk,moving --frames 150 --steps > $OUT/$tree-$round-shadows.txt 2>&1
  [ $round = 1 ] && t 60 $run python3 benchmarks/bench_living.py --assets $A --only walk --frames 150 > $OUT/$tree-living.txt 2>&1
done; done
for f in $OUT/*.txt; do echo "== $f"; grep -E "^\||rror" $f | grep -v "^|---" | tail -14; done
