# H200 run z3 (session 15): which GTAO stage makes a compute batch's tile differ from its
# view alone on the H200 (run z2: within 3 pixels of the tiles' borders): the depth MIPs, GTAO's
# raw term (ao_raw) and the first denoise pass (ao_mid) of view 7 (tile 7: column 2, row 1 of a
# 3 x 3 grid of 60 x 50) at full resolution, batch against alone.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
(cd tests/gpu && PYTHONPATH=$PYTHONPATH:$PWD/..:$PWD timeout 150 python3 - <<'PY'
import numpy as np
from test_batch import cameras_of
from vkpbr import Renderer
from vkpbr.gpu.image_io import read_level
from test_ao import corner
r = Renderer(corner()[0], msaa=1)
cams = cameras_of(r, 8, seed=3)
kw = {"pipeline": "compute", "ao_radius": 8.0, "view": "ao", "linear": True, "ao": "gtao-full"}
def grab(origin_mip, origin_work):
    r.device.wait_idle()
    ao = r.parts.ao
    out = {}
    for k in range(5):
        lv = read_level(r.device, ao.mips[0], k, dtype=np.float32, channels=1)[0, ..., 0]
        y, x = origin_mip[1] >> k, origin_mip[0] >> k
        out[f"mip{k}"] = lv[y:y + (64 >> k), x:x + (64 >> k)].astype(np.float64)
    for name, (img, *_) in zip(("raw", "mid"), ao.work):
        a = read_level(r.device, img, 0, layout="general", dtype=np.uint32, channels=1)[0, ..., 0]
        a = a[origin_work[1]:origin_work[1] + 50, origin_work[0]:origin_work[0] + 60]
        out[name + "_vis"] = (a & 0xFFFF).astype(np.float64)
        out[name + "_edges"] = (a >> 16).astype(np.float64)
    return out
r.render_batch(cams, (60, 50), **kw)
b = grab((128, 64), (120, 50))
r.render(camera=cams[7], size=(60, 50), raster="compute", **kw)
s = grab((0, 0), (0, 0))
for k in b:
    d = np.abs(b[k] - s[k])
    ys, xs = np.nonzero(d > (1e-6 * np.abs(s[k]) if "mip" in k else 0))
    print(f"| {k} | max {d.max():.4g} | n {len(ys)} | rows {np.unique(ys)[:12].tolist()} | cols {np.unique(xs)[:12].tolist()} |")
PY
) 2>&1 | tail -14
