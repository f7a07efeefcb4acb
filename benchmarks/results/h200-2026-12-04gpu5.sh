# H200 GPU pass 5 (session 15): the compute rasteriser covering views in tile pixels (c5b794a):
# batch tiles against views alone (GTAO, run z2's table), the raster, batch and frames-folder
# tests, and Sponza's frame (the raster's cost).
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
(cd tests/gpu && PYTHONPATH=$PYTHONPATH:$PWD/..:$PWD timeout 100 python3 - <<'PY'
import numpy as np
from test_batch import cameras_of
from vkpbr import Renderer
from test_ao import corner
r = Renderer(corner()[0], msaa=1)
cams = cameras_of(r, 8, seed=3)
for tag, extra in (("gtao", {}), ("full", {"ao": "gtao-full"}), ("color", {"view": "final"})):
    kw = {"pipeline": "compute", "ao_radius": 8.0, "view": "ao", "linear": True, **extra}
    b = r.render_batch(cams, (60, 50), **kw)
    row = []
    for i, c in enumerate(cams):
        s = r.render(camera=c, size=(60, 50), raster="compute", **kw)
        d = np.abs(np.asarray(b[i], np.float64) - np.asarray(s, np.float64)) * 65535
        row.append(f"{d.max():.0f}/{int((d > 0).sum())}")
    print(f"| {tag} |", " | ".join(row), "|")
PY
) 2>&1 | tail -4
HYPOTHESIS_PROFILE=report timeout -s INT 300 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=line tests/gpu/test_batch.py tests/gpu/test_frames_folder.py tests/gpu/test_compute_raster.py tests/gpu/test_compute_batch.py tests/gpu/test_ao_paths.py tests/gpu/test_ao.py tests/gpu/test_worlds.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  |^/.*Error" $OUT/gpu-tests.log | cut -c1-300 | head -20
timeout 100 python3 benchmarks/bench_ao.py --scene $VKPBR_ASSETS/Sponza/glTF/Sponza.gltf --profile --modes off,gtao --sizes 1920x1080 --frames 200 --views 0 | grep "^|"
