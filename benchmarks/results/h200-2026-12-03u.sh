# H200 run u (session 14): the two GPU test failures of run t. test_shadow_cache with its
# steps' raster units named (auto picks the kernels on GPUs), and how far a compute batch's
# GTAO views are from the views rendered alone on the H200 (test_ao_paths' batch-tiles test).
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
timeout -s INT 30 python3 -m pytest -q -p no:cacheprovider --tb=line tests/gpu/test_shadow_cache.py 2>&1 | grep -E "^E |passed|failed" | head -5
cd tests/gpu && timeout 60 python3 - <<'PY'
import numpy as np
from test_batch import cameras_of
from vkpbr import Renderer
from test_ao import corner
r = Renderer(corner()[0], msaa=1)
cams = cameras_of(r, 8, seed=3)
kw = {"pipeline": "compute", "ao_radius": 8.0, "view": "ao", "linear": True}
batch = r.render_batch(cams, (60, 50), **kw)
for i, cam in enumerate(cams):
    one = r.render(camera=cam, size=(60, 50), raster="compute", **kw)
    d = np.abs(batch[i] - one)
    print(i, "max", float(d.max()) * 65535, "n>2/65535", int((d > 2 / 65535).sum()), "of", d.size)
PY
