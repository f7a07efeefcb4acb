# H200 run e (session 22): where a Sponza frame's recording goes now (profile_record.py,
# compute path, the sun's cascades), and test_stream with render_many closing its stream.
# Carry .gl .whl .assets-s.
source benchmarks/gpu_env.sh
S=$PWD/.assets-s/models/Sponza/glTF/Sponza.gltf
export VKPBR_ASSETS=$PWD/.assets-s/models
timeout 100 python3 -m pytest -q -n 4 -p no:cacheprovider -rfE --tb=short tests/gpu/test_stream.py > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR|E )|passed|failed" $OUT/tests.txt | cut -c1-300 | head -20
timeout 100 python3 benchmarks/profile_record.py --scene $S --times 10 --sun > $OUT/record.txt 2>&1
timeout 100 python3 benchmarks/profile_record.py --scene $S --times 10 --sun --sort cumtime > $OUT/record-cum.txt 2>&1
head -30 $OUT/record.txt | cut -c1-160
