#!/usr/bin/env bash
# A short diagnostic on the NVIDIA machine: which part of a texture upload stops? Each step is
# a time-boxed process; a watchdog prints the stack and exits.
source benchmarks/gpu_env.sh
for step in ${DIAG_STEPS:-blit}; do
STEP=$step timeout 30 python3 - <<'PY' 2>&1 | tee -a "$OUT/diag.txt"
import os, threading, time
import numpy as np
step = os.environ["STEP"]
t = time.perf_counter()
def say(m): print(f"[{step}] {time.perf_counter() - t:6.2f} s  {m}", flush=True)
def watchdog():
    time.sleep(12); say("HUNG"); os._exit(3)
threading.Thread(target=watchdog, daemon=True).start()
import vulkan
o13, o12, o11 = (vulkan.VkPhysicalDeviceVulkan13Features, vulkan.VkPhysicalDeviceVulkan12Features,
                 vulkan.VkPhysicalDeviceVulkan11Features)
if step in ("blit_nomaint4", "blit_neither"):
    vulkan.VkPhysicalDeviceVulkan13Features = lambda **kw: o13(**{k: v for k, v in kw.items() if k != "maintenance4"})
if step in ("blit_nochain", "blit_neither"):
    vulkan.VkPhysicalDeviceVulkan12Features = lambda pNext=None, **kw: pNext if "shaderOutputLayer" in kw else o12(pNext=pNext, **kw)
    vulkan.VkPhysicalDeviceVulkan11Features = lambda pNext=None, **kw: pNext if "shaderDrawParameters" in kw else o11(pNext=pNext, **kw)
from vkpbr.gpu import device as D
if step == "blit_nofeatures":
    q = D.Device._query_features
    def fewer(self):
        f = q(self)
        return {**f, "geometryShader": 0, "shaderStorageImageWriteWithoutFormat": 0,
                "imageCubeArray": 0, "shaderOutputLayer": 0, "shaderDrawParameters": 0}
    D.Device._query_features = fewer
d = D.Device(None)
say(f"device {d.info.name} compute_path={d.compute_path}")
from vkpbr.gpu.image import TextureUploader
up = TextureUploader(d)
up.add(np.full((64, 64, 4), 200, np.uint8), "srgb", mipmaps=step != "copy", name="t1")
up.flush(); say("uploaded")
os._exit(0)
PY
done
