# H200 run a (session 18; session 17's last tree): where a many-scene job's time goes
# (profile_job.py, cProfile of the warm job's main thread, 256x256 x 16 views, 7 models with
# Sponza) and Sponza's file to first frame per phase (bench_load.py --profile: each child's
# cProfile), and how long a bare Vulkan instance takes here (the loader, the driver).
# Carry .gl .whl .assets-final.
source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
nvidia-smi --query-gpu=name,persistence_mode,clocks.sm,clocks.max.sm --format=csv
python3 - <<'PY'
import time; t=time.perf_counter()
import vulkan as vk; t1=time.perf_counter()
i=vk.vkCreateInstance(vk.VkInstanceCreateInfo(pApplicationInfo=vk.VkApplicationInfo(apiVersion=vk.VK_MAKE_VERSION(1,3,0))),None); t2=time.perf_counter()
d=vk.vkEnumeratePhysicalDevices(i); t3=time.perf_counter()
print(f"import vulkan {t1-t:.3f} s, vkCreateInstance {t2-t1:.3f}, vkEnumeratePhysicalDevices {t3-t2:.3f} ({len(d)} devices)")
PY
echo "== job profile"
timeout 200 python3 benchmarks/profile_job.py --models $A --names DamagedHelmet,CesiumMilkTruck,BoxAnimated,MetalRoughSpheresNoTextures,CesiumMan,2CylinderEngine,Sponza \
   --scenes 42 --views 16 --size 256x256 --profile $OUT/job.txt --top 80 2>&1 | grep -E "^\||per model"
echo "== load"
timeout 150 python3 benchmarks/bench_load.py --scene $A/Sponza/glTF/Sponza.gltf --no-job --profile $OUT/load 2>&1 | grep -E "^\|" | grep -v "^|---"
