#!/usr/bin/env bash
# The device's one command (see bench/gpu/README.md): the form-factor engine and the room's main job on the GPU,
# headless through EGL, with llvmpipe's figures from here for comparison in the same report. Writes under $OUT.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
vendor=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json     # the driver's EGL, where glvnd misses it
[ -f "$vendor" ] && export __EGL_VENDOR_LIBRARY_FILENAMES="$vendor"
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 1
export PYTHONPATH="$PWD:/tmp/site" PYTHONUNBUFFERED=1 OUT="${OUT:-/tmp/out}"
mkdir -p "$OUT"
cs451() { python3 -c 'import sys; from cs451.cli import main; sys.argv[0] = "cs451"; sys.exit(main())' "$@"; }
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee "$OUT/device.txt"
python3 - <<'PY' | tee -a "$OUT/device.txt"
from cs451 import gl
ctx = gl.create_context()
print(gl.renderer_name(ctx), ctx.info["GL_VERSION"], "software" if gl.is_software(ctx) else "hardware")
PY
TIMEFORMAT="render room: %R s"
for k in 1 2; do { time cs451 render room -o "$OUT/room.png"; } 2>&1 | tail -3; done | tee "$OUT/main_job.txt"
timeout 420 cs451 bench formfactors -o "$OUT/bench" 2>&1 | tee "$OUT/formfactors.txt"
