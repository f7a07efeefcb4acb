#!/usr/bin/env bash
# A short diagnostic on the NVIDIA machine: where does a vkpbr process stop? Each step is
# time-boxed and dumps its Python stack when it hangs (faulthandler), output unbuffered.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl 2>/dev/null || exit 1
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1
if [ -z "$(python3 -m vkpbr info --json 2>/dev/null | grep -i nvidia)" ]; then
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
timeout 60 python3 -X faulthandler - <<'PY' 2>&1 | tee "$OUT/diag.txt"
import faulthandler, time
faulthandler.dump_traceback_later(45, exit=True)
t = time.perf_counter()
def say(m): print(f"{time.perf_counter() - t:7.2f} s  {m}", flush=True)
from vkpbr.gpu.device import Device
d = Device(None); say(f"device {d.info.name} compute_path={d.compute_path}"); d.close()
from vkpbr.render.renderer import Renderer
r = Renderer(); say("renderer")
img = r.render(size=(64, 64), lighting="course"); say(f"course forward {img.mean():.1f}")
img = r.render(size=(64, 64)); say(f"pbr forward {img.mean():.1f}")
img = r.render(size=(64, 64), pipeline="compute"); say(f"pbr compute {img.mean():.1f}")
r.close(); say("closed")
PY
