# H200 run z2 (session 15): test_ao_paths' batch tiles on the H200: does the difference
# follow the view or the tile (cameras reversed), the radius (far samples, MIP levels), the
# resolution (gtao-full: no upsample)? The difference images into $OUT.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
(cd tests/gpu && PYTHONPATH=$PYTHONPATH:$PWD/..:$PWD timeout 150 python3 - <<'PY'
import os
import numpy as np
from test_batch import cameras_of
from vkpbr import Renderer
from test_ao import corner
r = Renderer(corner()[0], msaa=1)
cams = cameras_of(r, 8, seed=3)
out = os.environ["OUT"]
def run(tag, cams, **extra):
    kw = {"pipeline": "compute", "ao_radius": 8.0, "view": "ao", "linear": True, **extra}
    b = r.render_batch(cams, (60, 50), **kw)
    row = []
    for i, c in enumerate(cams):
        s = r.render(camera=c, size=(60, 50), raster="compute", **kw)
        d = np.abs(np.asarray(b[i], np.float64) - np.asarray(s, np.float64))[..., 0] * 65535
        row.append(f"{d.max():.0f}/{int((d > 2).sum())}")
        if d.max() > 2:
            np.save(f"{out}/{tag}_{i}.npy", np.stack([np.asarray(b[i])[..., 0], np.asarray(s)[..., 0]]))
    print(f"| {tag} |", " | ".join(row), "|")
run("base", cams)
run("reversed", cams[::-1])
run("radius1", cams, ao_radius=1.0)
run("full", cams, ao="gtao-full")
run("low", cams, ao="gtao-low")
PY
) 2>&1 | tail -8
ls $OUT | head -40
