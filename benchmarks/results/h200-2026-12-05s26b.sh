# H200 run b (session 26, for the next lease: none was lent in session 26): the GPU test pass
# at this tree (render_many's two collectors), validation on, imagecodecs carried this time
# (tests/gpu/test_ibl.py's bad-environment test needs it). The carry fits one call: the tree
# 13.6 MB + .gl 7.3 + .whl 3.1 + .whl-extra 27.7 + .assets-tests 13.9 = 65.5 MB of 67.1.
# Carry .gl .whl .whl-extra .assets-tests (the sample models the GPU tests read; Sponza's and
# the animated models' tests skip here and run on lavapipe).
source benchmarks/gpu_env.sh
export VKPBR_ASSETS=$PWD/.assets-tests/models
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
HYPOTHESIS_PROFILE=report timeout -s INT 420 python3 -m pytest -q -n 8 -p no:cacheprovider -rfE --tb=short tests/gpu tests/unit tests/test_import_graph.py > $OUT/gpu-tests.log 2>&1
grep -E "^(FAILED|ERROR)|passed|failed|^E  " $OUT/gpu-tests.log | cut -c1-300 | head -40
