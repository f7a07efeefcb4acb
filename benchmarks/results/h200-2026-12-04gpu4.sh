# H200 GPU pass 4 (session 15): shadows' image-mode PCF from gathers with the by-hand weights
# (a frame after a redraw, read by hand, against the cached frames after it: equal now?), the
# shadow, batch and frames-folder tests, and the still/moving Sponza frame's cost of it.
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-s/models
timeout 60 python3 - <<'PY'
import numpy as np
from vkpbr.render.renderer import Renderer
with Renderer() as r:
    f = [r.render(size=(160, 120)).astype(int) for _ in range(4)]
    for k in range(1, 4):
        d = np.abs(f[k] - f[0])[..., :3]
        print("| default scene frame", k, "vs 0 | max", d.max(), "| values", int((d > 0).sum()), "|")
PY
HYPOTHESIS_PROFILE=report timeout -s INT 300 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=line tests/gpu/test_batch.py tests/gpu/test_frames_folder.py tests/gpu/test_shadow_cache.py tests/gpu/test_shadow_raster.py tests/gpu/test_shadows.py tests/gpu/test_world_shadows.py tests/gpu/test_compute_raster.py tests/gpu/test_leaks.py tests/gpu/test_instances.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  |^/.*Error" $OUT/gpu-tests.log | cut -c1-300 | head -20
S=$VKPBR_ASSETS/Sponza/glTF/Sponza.gltf
for tree in .before1 .; do echo "## $tree"; PYTHONPATH=/tmp/site:$PWD/$tree/src timeout 100 python3 benchmarks/bench_shadows.py --scene $S --steps --frames 150 2>&1 | grep "^|" | head -12; done
