# H200 run n (session 14): diagnostics, not fixes: shader variants made on the device (sed on
# the copied sources, codegen) and timed, to see what bounds the shadow kernels and the deform
# kernel. Wrong pictures by design (the variants skip work); only the timings are read.
#   store    the shadow kernels' atomicMax -> a plain store
#   nowrite  no depth written (a never-true condition keeps the loops)
#   nodraw   shadow_small/masked set up and list triangles but draw none of their own
#   joint0   deform: every influence reads the job's first joint matrix (uniform loads)
#   noprev   deform: no previous-position copy, no inverse-transpose
# Carry .gl .whl .assets-peers. About 300 s.
source benchmarks/gpu_env.sh
export PATH=$PWD/.gl/bin:$PATH
S=$PWD/.assets-peers/models/Sponza/glTF/Sponza.gltf; A=$PWD/.assets-peers/models
SH=src/vkpbr/shaders; cp -r $SH /tmp/shaders-orig
t() { timeout "$1" "${@:2}"; }
variant() {
  rm -rf $SH && cp -r /tmp/shaders-orig $SH
  case $1 in
    store) sed -i 's/            atomicMax(depths\[at\], bits);/            depths[at] = bits;/' $SH/shadow_raster.comp ;;
    nowrite) sed -i 's/            atomicMax(depths\[at\], bits);/            if (bits == 0x7fffffffu) depths[at] = bits;/' $SH/shadow_raster.comp ;;
    nodraw) sed -i 's/^            else draw_layer(t, 0u, ALL_BANDS, 0, 1, 0, 1);/            ;/' $SH/shadow_raster.comp ;;
    joint0) sed -i 's/joint_matrix(b.z + 16u \* joint)/joint_matrix(b.z)/' $SH/deform.comp ;;
    noprev) sed -i '/deform_prev\[prev/d; s/n = transpose(inverse(m3)) \* n;/n = m3 * n;/' $SH/deform.comp ;;
  esac
  git diff --no-index --stat /tmp/shaders-orig $SH 2>/dev/null | tail -1
  python3 -m vkpbr.render.codegen > /dev/null 2>&1 || echo "codegen failed for $1"
}
for v in base store nowrite nodraw joint0 noprev; do
  echo "### $v"; variant $v
  case $v in joint0|noprev) ;; *) t 60 python3 benchmarks/bench_shadows.py --scene $S --only maps --steps --frames 40 2>&1 | grep "compute" ;; esac
  t 80 python3 benchmarks/bench_living.py --assets $A --only crowd --crowds 1000 --frames 60 --shadow-steps 2>&1 | grep "GPU ms by step\|^| crowd"
done
