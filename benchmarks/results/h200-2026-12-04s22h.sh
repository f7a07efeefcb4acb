# H200 run h (session 22): where the warm start's 0.17-0.24 s of "pipeline_cache" goes (run g):
# a first render leaves the pipeline cache file, then profile_device.py twice.
# Carry .gl .whl .assets-s.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
timeout 60 python3 -m vkpbr render $S --size 320x240 --out /tmp/first.png > /dev/null 2>&1
ls -la ~/.cache/vkpbr/ | grep -i pipel
for i in 1 2; do timeout 60 python3 benchmarks/profile_device.py > $OUT/device$i.txt 2>&1; head -1 $OUT/device$i.txt | cut -c1-400; done
sed -n 2,40p $OUT/device2.txt | cut -c1-160
