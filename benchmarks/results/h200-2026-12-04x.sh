# H200 run x (session 15): run w's GTAO tables again (its output was cut), and whether the
# compute batch's depths equal the views' rendered alone (test_ao_paths' batch tiles: tiles 4
# and 6 differ by up to 103/65535 in GTAO on the H200, none on lavapipe).
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
S=$VKPBR_ASSETS/Sponza/glTF/Sponza.gltf
(cd tests/gpu && PYTHONPATH=$PYTHONPATH:$PWD/..:$PWD timeout 60 python3 - <<'PY'
import numpy as np
from test_batch import cameras_of
from vkpbr import Renderer
from test_ao import corner
r = Renderer(corner()[0], msaa=1)
cams = cameras_of(r, 8, seed=3)
kw = {"pipeline": "compute", "ao_radius": 8.0}
batch = r.render_batch(cams, (60, 50), outputs=("depth",), **kw)
for i, cam in enumerate(cams):
    one = r.render(camera=cam, size=(60, 50), raster="compute", outputs=("depth",), **kw)["depth"]
    b = batch["depth"][i] if isinstance(batch, dict) else batch[i]["depth"]
    fin = np.isfinite(one) & np.isfinite(b)
    d = np.abs(b - one)[fin]
    print("| depth tile", i, "| max rel", float((d / one[fin]).max()) if d.size else 0, "| n differ", int((d > 0).sum()), "| inf mismatch", int((np.isfinite(one) != np.isfinite(b)).sum()), "|")
PY
) 2>&1 | tail -12
for tree in .before1 .; do
  echo "## tree $tree"
  PYTHONPATH=/tmp/site:$PWD/$tree/src timeout 100 python3 benchmarks/bench_ao.py --scene $S --profile --modes off,gtao,gtao-low,gtao-full --sizes 1920x1080 --frames 300 --batches 5 | grep "^|"
done
