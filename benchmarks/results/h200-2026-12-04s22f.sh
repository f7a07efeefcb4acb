# H200 run f (session 22, the final code): Python a CUDA worlds step with the poses copied and
# written in place (batch_step.worlds_input), Sponza's cold file to first frame, then the GPU
# test pass (tests/gpu, tests/unit, tests/distributed; validation on).
# Carry .gl .whl .assets-final.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
A=$PWD/.assets-final/models
export VKPBR_ASSETS=$A
P="benchmarks/profile_worlds_step.py --torch --variant tabletop --worlds 4096 --size 128 --steps 60 --bare --prepared --frames view"
for i in 1 2; do
  timeout 90 python3 $P > $OUT/step-copy$i.txt 2>&1; echo "copy $i"; grep -E "alone|short way" $OUT/step-copy$i.txt | cut -c1-140
  timeout 90 python3 $P --in-place > $OUT/step-inplace$i.txt 2>&1; echo "in place $i"; grep -E "alone|short way" $OUT/step-inplace$i.txt | cut -c1-140
done
timeout 120 python3 benchmarks/bench_load.py --scene $A/Sponza/glTF/Sponza.gltf --no-job --fresh-driver-cache --rows cold,cold,cold,"warm bake + pipelines" > $OUT/load.txt 2>&1
grep -E "^\| (cold|warm)" $OUT/load.txt | cut -c1-200 | head -8
timeout -s INT 330 python3 -m pytest -q -n 12 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/distributed > $OUT/tests.txt 2>&1
grep -E "^(FAILED|ERROR)|passed|failed" $OUT/tests.txt | cut -c1-200 | head -20
