# H200 run w (session 15): GTAO with the prefilter reading the compute rasteriser's depths in
# place (no depth copy: b1433b1) against the tree before (.before1 = 18c8219) in one lease; the
# AO GPU tests; the compute batch's GTAO tiles against views alone (run u's check, the tests
# folder on the path this time); the lens resample and noise steps at 1080p.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
S=$VKPBR_ASSETS/Sponza/glTF/Sponza.gltf
for tree in .before1 .; do
  echo "## tree $tree"
  PYTHONPATH=/tmp/site:$PWD/$tree/src timeout 100 python3 benchmarks/bench_ao.py --scene $S --profile --modes off,gtao,gtao-low,gtao-full --sizes 1920x1080 --frames 300 --batches 5 | grep "^|"
done
timeout -s INT 150 python3 -m pytest -q -p no:cacheprovider --tb=short tests/gpu/test_ao.py tests/gpu/test_ao_paths.py 2>&1 | grep -E "^E |passed|failed|assert" | head -20
(cd tests/gpu && PYTHONPATH=$PYTHONPATH:$PWD/..:$PWD timeout 60 python3 - <<'PY'
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
    print("| tile", i, "| max", float(d.max()) * 65535, "| n>2/65535", int((d > 2 / 65535).sum()), "of", d.size, "|")
PY
)
timeout 120 python3 benchmarks/bench_post.py --scene $S --only lens,noise 2>&1 | grep "^|"
