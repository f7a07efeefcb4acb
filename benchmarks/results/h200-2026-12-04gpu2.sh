# H200 GPU test pass 2 (session 15): the tests with the frame-path rule (tests/conftest.py),
# and whether the layered batch renders the same views twice alike (test_batch's out= test
# failed there in pass 1): the default scene, 7 views at 48x36, three calls, shadows' reads.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-final/models
(cd tests/gpu && PYTHONPATH=$PYTHONPATH:$PWD/..:$PWD timeout 60 python3 - <<'PY'
import numpy as np
from test_batch import cameras_of
from vkpbr.render.renderer import Renderer
r = Renderer(validation=True)
cams = cameras_of(r, 7, seed=9)
for opts in ({}, {"shadows": False} if False else {"lights": []}):
    kw = {"pipeline": "forward", "ao": "off", **opts}
    a = [r.render_batch(cams, size=(48, 36), **kw) for _ in range(4)]
    for k in range(1, 4):
        d = np.abs(a[k].astype(int) - a[0].astype(int))
        print("| batch", opts, "call", k, "vs 0 | max", d.max(), "| values", int((d > 0).sum()), "|")
PY
) 2>&1 | tail -8
HYPOTHESIS_PROFILE=report timeout -s INT 400 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=line tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  |^/.*Error" $OUT/gpu-tests.log | head -40
