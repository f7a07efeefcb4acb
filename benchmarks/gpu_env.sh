# Sourced by the device-tool scripts (gpu_run.sh, gpu_diag.sh): unpack the carried Vulkan
# loader and validation layer (.gl) and wheels (.whl), point Python at them and at this
# checkout, and find the NVIDIA driver (its ICD needs the glvnd libraries carried in .gl/).
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
# .whl-extra (optional): wheels only some runs carry (imagecodecs for the test pass, 26 MiB).
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl $(ls .whl-extra/*.whl 2>/dev/null) 2>/dev/null || exit 1
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1
if [ -z "$(python3 -m vkpbr info --json 2>/dev/null | grep -i nvidia)" ]; then
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
# The device sets PYTHONDONTWRITEBYTECODE, so every process compiled the vulkan binding's 2 MB
# of source (0.23-0.35 s of each "device: binding") and vkpbr's own modules: what no pip
# install leaves a user with. COMPILE_BYTECODE=1 compiles them once first (Python still reads
# bytecode that exists), for the runs that time a fresh process's start.
if [ "${COMPILE_BYTECODE:-0}" = 1 ]; then
  python3 -m compileall -q -j 0 /tmp/site $PWD/src > /dev/null 2>&1
fi
