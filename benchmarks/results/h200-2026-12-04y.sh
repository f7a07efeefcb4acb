# H200 run y (session 15): test_ao_paths' batch tiles (tiles 4 and 6 differ from the views
# alone by up to 103/65535 on the H200, run w, with equal depths, run x): is GTAO
# deterministic there (the same batch twice, the same view twice), and does a one-view batch
# equal the view alone? Then the AO GPU tests.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
(cd tests/gpu && PYTHONPATH=$PYTHONPATH:$PWD/..:$PWD timeout 90 python3 - <<'PY'
import numpy as np
from test_batch import cameras_of
from vkpbr import Renderer
from test_ao import corner
r = Renderer(corner()[0], msaa=1)
cams = cameras_of(r, 8, seed=3)
kw = {"pipeline": "compute", "ao_radius": 8.0, "view": "ao", "linear": True}
def m(a, b):
    d = np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64))
    return f"{d.max() * 65535:.1f} ({int((d > 2 / 65535).sum())} px)"
b1 = r.render_batch(cams, (60, 50), **kw)
b2 = r.render_batch(cams, (60, 50), **kw)
for i in (2, 4, 6):
    s1 = r.render(camera=cams[i], size=(60, 50), raster="compute", **kw)
    s2 = r.render(camera=cams[i], size=(60, 50), raster="compute", **kw)
    one = r.render_batch(cams[i:i + 1], (60, 50), **kw)[0]
    print(f"| tile {i} | batch-batch {m(b1[i], b2[i])} | single-single {m(s1, s2)} | batch-single {m(b1[i], s1)} | 1-view batch - single {m(one, s1)} | 1-view batch - batch {m(one, b1[i])} |")
PY
) 2>&1 | tail -8
timeout -s INT 200 python3 -m pytest -q -p no:cacheprovider --tb=short tests/gpu/test_ao.py tests/gpu/test_ao_paths.py 2>&1 | grep -E "^E  |passed|failed|^FAILED" | head -20
