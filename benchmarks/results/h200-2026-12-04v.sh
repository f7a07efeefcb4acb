# H200 run v (session 15): run u's two GPU test checks (test_shadow_cache; the compute batch's
# GTAO views against views alone), then where GTAO's ao_prefilter time goes: the depth copy
# before it (compute_path raster_steps' "depth_copy", untimed, so its time lands in the
# prefilter's interval) timed apart by sed on the device.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
timeout -s INT 40 python3 -m pytest -q -p no:cacheprovider --tb=line tests/gpu/test_shadow_cache.py 2>&1 | grep -E "^E |passed|failed" | head -5
(cd tests/gpu && timeout 60 python3 - <<'PY'
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
    print("tile", i, "max", float(d.max()) * 65535, "n>2/65535", int((d > 2 / 65535).sum()), "of", d.size)
PY
)
S=$VKPBR_ASSETS/Sponza/glTF/Sponza.gltf
timeout 100 python3 benchmarks/bench_ao.py --scene $S --profile --modes off,gtao,gtao-full --sizes 1920x1080 --frames 200 --views 0 | grep "^|"
sed -i 's/("depth", "transfer_dst")), timed=False))/("depth", "transfer_dst"))))/' src/vkpbr/render/compute_path.py
grep -n '"depth_copy"' -A2 src/vkpbr/render/compute_path.py | head -3
timeout 100 python3 - <<PY
import statistics
from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene
with Renderer(load_scene("$S")) as r:
    r.parts.ao.profile = True
    for ao in ("off", "gtao", "gtao-full"):
        acc = {}
        cams = [r.default_camera()] * 220
        for i, _ in enumerate(r.render_many(cams, size=(1920, 1080), readback=False, pipeline="compute", raster="compute", ao=ao)):
            if i >= 20:
                for k, v in r.last_stats.pass_ms.items():
                    acc.setdefault(k, []).append(v)
                acc.setdefault("GPU", []).append(r.last_stats.gpu_ms)
        print("|", ao, "|", " ".join(f"{k}={statistics.median(v):.3f}" for k, v in acc.items()), "|")
PY
