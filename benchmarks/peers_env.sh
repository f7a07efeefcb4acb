# Sourced by the device-tool peer runs (gpu_bench.sh, gpu_batch.sh) after the wheels of .whl
# are in /tmp/site: unpack .gl-peers (libGLU, glvnd EGL/GL), install the carried peer wheels
# of .whl-peers into /tmp/peers without dependencies (skipping small packages the image or
# /tmp/site already has), and point Python, PyOpenGL and glvnd at them and the NVIDIA driver.
for f in .gl-peers/*.deb; do dpkg -x "$f" /; done; ldconfig
wheels=()
for w in .whl-peers/*.whl; do
  mod=$(basename "$w"); mod=${mod%%-*}
  case $mod in six | jinja2 | markupsafe | packaging | typing_extensions | typing_inspect | mypy_extensions | cffi | pycparser | marshmallow | dataclasses_json)
    python3 -c "import $mod" 2>/dev/null && continue ;; esac
  [ -e "/tmp/site/$mod" ] && continue
  wheels+=("$w")
done
python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/peers "${wheels[@]}" 2>/dev/null || exit 1
export PYTHONPATH=/tmp/site:/tmp/peers:$PWD/src PYTHONUNBUFFERED=1 PYOPENGL_PLATFORM=egl
nv=/usr/local/nvidia/share
ls /usr/share/glvnd/egl_vendor.d/*nvidia* >/dev/null 2>&1 || export __EGL_VENDOR_LIBRARY_FILENAMES=$nv/glvnd/egl_vendor.d/10_nvidia.json
