# H200 run d (session 21): run c's one new failure, SIGTERM during `vkpbr render` ending in
# SIGSEGV: the CLI's render with a SIGTERM 1.5 s in, ahead on and off, faulthandler on.
# Carry .gl .whl.
COMPILE_BYTECODE=1 source benchmarks/gpu_env.sh
cd /tmp
for mode in 1 0 1 0 1 0; do
  rm -f r.png; VKPBR_KERNELS_AHEAD=$mode python3 -X faulthandler -m vkpbr -v render --size 16x16 --frames 1000000 --out r.png 2> err.txt &
  pid=$!; sleep 1.5; kill -TERM $pid; wait $pid; rc=$?
  echo "ahead=$mode rc=$rc"; if [ $rc != 143 ]; then head -c 6000 err.txt; fi
done
