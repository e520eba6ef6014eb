#!/usr/bin/env bash
# Issue 23's Must show, on a GPU machine in one `device` call (after scripts/device/fetch.sh here):
#   command: bash scripts/device/must_show.sh      carry: [".whl", ".gl"]      timeout_s: 540
# Writes to $OUT (at most 8 files come back):
#   log.txt          every command's output: the GPU, frame means, each mode's PSNR
#   fly_640.json     the default flythrough at 640x480, 91 frames: full 3D and auto, each with the CPU's and
#                    the GPU's splat order; per frame: frame, CPU and GPU time per pass (`cloudview bench`)
#   fly_1600.json    the same at 1600x1200, 61 frames
#   field.json       the 1.2M-particle field, auto against full 3D (`bench_lod.py --cases field`), if time allows
#   default_full.png, default_auto.png   the default view at 640x480, to compare here with llvmpipe's
#                    (`cloudview render ... --mode full|auto` then `cloudview compare`)
set -uo pipefail
OUT=${OUT:-out/must_show}
mkdir -p "$OUT"
exec > >(tee "$OUT/log.txt") 2>&1
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
if [ ! -e /usr/share/glvnd/egl_vendor.d/10_nvidia.json ]; then
  export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
fi
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl ||
  exit 1
export PYTHONPATH=/tmp/site:$PWD PYOPENGL_PLATFORM=egl PYGLET_HEADLESS=1 PYTHONUNBUFFERED=1
nvidia-smi -L
cloudview() { python3 -m cloudcore.cli "$@"; }
scene=cloudcore/resources/scenes/valley.toml
sweep=(--sweep mode=full,auto --sweep splat_order=cpu,gpu --no-shading)
started=$SECONDS
for mode in full auto; do
  cloudview render "$scene" --mode "$mode" --width 640 --height 480 --out "$OUT/default_$mode.png" || exit 1
done
cloudview bench "$scene" --camera-path flythrough --frames 91 "${sweep[@]}" --json "$OUT/fly_640.json"
cloudview bench "$scene" --camera-path flythrough --frames 61 --width 1600 --height 1200 "${sweep[@]}" \
  --json "$OUT/fly_1600.json"
echo "flythroughs done in $((SECONDS - started)) s"
# what is left of a 540 s call, less a minute for the machine's start and the files' way back
timeout $((420 - SECONDS)) python3 scripts/bench_lod.py --cases field --json "$OUT/field.json" ||
  echo "field: not finished within the call"
