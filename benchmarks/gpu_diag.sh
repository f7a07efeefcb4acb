#!/usr/bin/env bash
# A short diagnostic on the NVIDIA machine: where does a vkpbr process stop? Each step is a
# time-boxed process; a watchdog prints the validation layer's messages and the stack, then exits.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl 2>/dev/null || exit 1
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1
if [ -z "$(python3 -m vkpbr info --json 2>/dev/null | grep -i nvidia)" ]; then
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
for step in upload shadows env renderer; do
STEP=$step timeout 40 python3 -X faulthandler - <<'PY' 2>&1 | tee -a "$OUT/diag.txt"
import faulthandler, os, sys, threading, time
import numpy as np
step = os.environ["STEP"]
t = time.perf_counter()
def say(m): print(f"[{step}] {time.perf_counter() - t:6.2f} s  {m}", flush=True)
from vkpbr.gpu.device import Device
d = Device(None, validation=True, sync_validation=True)
def watchdog():
    time.sleep(20)
    say("HUNG; validation messages:")
    for e in d.instance.errors[:8]:
        print("   ", e[:900], flush=True)
    faulthandler.dump_traceback(all_threads=False)
    os._exit(3)
threading.Thread(target=watchdog, daemon=True).start()
say(f"device {d.info.name}")
if step == "upload":
    from vkpbr.gpu.image import TextureUploader
    up = TextureUploader(d)
    up.add(np.full((64, 64, 4), 200, np.uint8), "srgb", name="t1")
    up.add(np.full((1, 1, 4), 255, np.uint8), "unorm", mipmaps=False, name="t2")
    up.flush(); say("textures uploaded")
elif step == "shadows":
    from vkpbr.gpu.layered import LayeredDepth
    LayeredDepth(d, 256, 4); say("2d array made")
    LayeredDepth(d, 128, 6, cube=True); say("cube made")
elif step == "env":
    from vkpbr.render.environment import EnvironmentBaker
    b = EnvironmentBaker(d); b.brdf_lut(); say("lut"); b.from_sky(); say("sky")
else:
    from vkpbr.render.renderer import Renderer
    d.close()
    r = Renderer(validation=True); say("renderer")
    img = r.render(size=(64, 64)); say(f"pbr forward {img.mean():.1f}")
    img = r.render(size=(64, 64), pipeline="compute"); say(f"pbr compute {img.mean():.1f}")
    d = r.device
say(f"{len(d.instance.errors)} validation messages: {[e[:300] for e in d.instance.errors[:3]]}")
os._exit(0)
PY
done
