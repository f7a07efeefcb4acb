# H200 run z (session 15): are a batch's view records those of its views alone (test_ao_paths'
# batch tiles differ in GTAO on the H200 at tiles 2, 4, 6 with equal depths, run y)?
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
(cd tests/gpu && PYTHONPATH=$PYTHONPATH:$PWD/..:$PWD timeout 90 python3 - <<'PY'
import numpy as np
from test_batch import cameras_of
from vkpbr import Renderer
from vkpbr.render import views as V
from vkpbr.scene.camera_batch import CameraBatch
from test_ao import corner
r = Renderer(corner()[0], msaa=1)
cams = cameras_of(r, 8, seed=3)
corners = [[-1, -1, -1], [1, 1, 1]]
bt = V.batch_view_terms(CameraBatch.from_cameras(cams, r.default_camera()), (60, 50), corners, 1.0)
for i, c in enumerate(cams):
    one = V.camera_view_terms(c, (60, 50), corners, 1.0)
    b1 = V.batch_view_terms(CameraBatch.from_cameras(cams[i:i + 1], r.default_camera()), (60, 50), corners, 1.0)
    diffs = {}
    for name in ("vp", "inv_vp", "eye", "intrinsics"):
        a = np.asarray([np.broadcast_to(v, 8)[i] for v in getattr(bt, name)], np.float32)
        o = np.asarray(getattr(one, name), np.float32)
        s = np.asarray([np.broadcast_to(v, 1)[0] for v in getattr(b1, name)], np.float32)
        diffs[name] = (int((a != o).sum()), int((s != o).sum()))
    print("| view", i, "| (8-batch != one, 1-batch != one) |", diffs, "|")
print(np.__version__)
PY
) 2>&1 | tail -12
timeout -s INT 200 python3 -m pytest -q -p no:cacheprovider --tb=line tests/gpu/test_ao_paths.py 2>&1 | grep -E "^E  |passed|failed|^FAILED" | head -10
