#!/usr/bin/env bash
# Issue 23's Must show, on a GPU machine in one `device` call (after scripts/device/fetch.sh here):
#   command: bash scripts/device/must_show.sh      carry: [".whl", ".gl"]      timeout_s: 560
# Every step is bounded by what is left of BUDGET_S (default 480 s) so the call ends inside its limit with
# whatever finished; a step that fails is logged and the next one runs.  STEPS names the steps to run (default
# "flythroughs renders editor tests field"; also "lod", "compositing", "sort", "compute" and "waits").  Writes to $OUT (8 files come back):
#   log.txt          every command's output: the GPU, frame means per mode and order, the GPU tests
#   flythroughs: fly_640.json, fly_1600.json   the default flythrough at 640x480 (181 frames) and 1600x1200
#                    (91): full 3D and auto, each with the CPU's and the GPU's splat order (the reference: full
#                    3D, "auto" order, the way the trial keeps); per frame: frame, CPU and GPU time per pass
#   renders: default_full.png, default_auto.png, default_auto_gpu.png   the default view at 640x480, to compare
#                    here with llvmpipe's (`cloudview render ... --mode full|auto [--splat-order gpu]`)
#   editor: editor_1280.json   the editor's viewport size (1280x720), auto, orbiting 0.2 degrees a frame
#   tests:           the tests of the GPU's ways and of the LOD's pictures, in log.txt
#   field: field.json          the 1.2M-particle field, auto against full 3D (`cloudview bench --suite lod --cases field`)
#   lod: lod.json              `cloudview bench --suite lod --cases still,flythrough`: auto against impostor mode and full 3D
#   compositing: compositing.json   full 3D at 640x480 blended by the raster (plain) or by the tiled compute
#                    pass (volume), 61 frames of the flythrough
#   sort: sort.json            the GPU's radix sort against numpy's (`bench_gpu_sort.py`), 10k to 1M keys
#   compute: compute_640.json, compute_1600.json   the flythrough (91 and 61 frames), full 3D and auto with the
#                    GPU's order, their splats blended by the raster or composited by compute (`compositing`);
#                    and the compute compositor's tests, in log.txt
#   waits: waits.json          a frame waited for once against a wait after each pass, side by side
#                    (`bench_pass_waits.py`): the flythrough (181 frames) and the still view, each mode
# LOCAL=1 runs it here on llvmpipe with a few frames and no setup: a check of the script, not numbers.
set -uo pipefail
OUT=${OUT:-out/must_show}
BUDGET_S=${BUDGET_S:-480}
STEPS=" ${STEPS:-flythroughs renders editor tests field} "
mkdir -p "$OUT"
exec > >(tee "$OUT/log.txt") 2>&1
if [ "${LOCAL:-}" = 1 ]; then
  python=.venv/bin/python fly_640=3 fly_1600=2 orbit=3 frames=3 quick=--quick plugin=()
else
  for f in .gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
  if [ ! -e /usr/share/glvnd/egl_vendor.d/10_nvidia.json ]; then
    export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
  fi
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl ||
    exit 1
  export PYTHONPATH=/tmp/site:$PWD
  python=python3 fly_640=181 fly_1600=91 orbit=60 frames=61 quick=
  plugin=(-p cloudcore.pytest_plugin) # registered by the install here, not there
  nvidia-smi -L
fi
export PYOPENGL_PLATFORM=egl PYGLET_HEADLESS=1 PYTHONUNBUFFERED=1 TQDM_DISABLE=1
left() { echo $((BUDGET_S - SECONDS)); }
wanted() { [[ $STEPS == *" $1 "* ]]; }
step() { # step NAME COMMAND...: run within what is left of the budget, say how it went
  local name=$1 started=$SECONDS
  shift
  if [ "$(left)" -le 5 ]; then
    echo "== $name: skipped, the budget is spent"
    return
  fi
  echo "== $name (at ${SECONDS} s)"
  timeout "$(left)" "$@"
  echo "== $name: rc=$? in $((SECONDS - started)) s"
}
cloudview=("$python" -m cloudcore.cli)  # an array: `timeout` runs programs, not functions
scene=cloudcore/resources/scenes/valley.toml
sweep=(--sweep mode=full,auto --sweep splat_order=cpu,gpu --no-shading)
"$python" -c "
from cloudcore.gl import FrameRenderer
from OpenGL import GL
r = FrameRenderer(64, 64); r.context.make_current()
print('GL:', GL.glGetString(GL.GL_RENDERER).decode(), '|', GL.glGetString(GL.GL_VERSION).decode()); r.close()"
if wanted flythroughs; then
  step "flythrough 640x480" "${cloudview[@]}" bench "$scene" --camera-path flythrough --frames "$fly_640" \
    "${sweep[@]}" --json "$OUT/fly_640.json"
  step "flythrough 1600x1200" "${cloudview[@]}" bench "$scene" --camera-path flythrough --frames "$fly_1600" \
    --width 1600 --height 1200 "${sweep[@]}" --json "$OUT/fly_1600.json"
fi
if wanted renders; then
  for way in full auto auto_gpu; do
    mode=${way%_gpu} order=cpu
    [ "$way" = auto_gpu ] && order=gpu
    step "render $way" "${cloudview[@]}" render "$scene" --mode "$mode" --splat-order "$order" --width 640 \
      --height 480 --out "$OUT/default_$way.png"
  done
fi
if wanted editor; then
  step "editor size 1280x720, orbit" "${cloudview[@]}" bench "$scene" --orbit 0.2 --warmup 20 --frames "$orbit" \
    --width 1280 --height 720 --sweep mode=auto --sweep splat_order=cpu,gpu --no-shading \
    --json "$OUT/editor_1280.json"
fi
if wanted tests; then
  step "GPU-path tests" "$python" -m pytest -q "${plugin[@]}" tests/render/test_gpu_order.py tests/render/test_impostor_atlas.py \
    tests/render/test_splats_shaded_ahead.py tests/render/test_render_golden.py tests/render/test_render_lod.py
fi
if wanted compositing; then
  step "compositing 640x480" "${cloudview[@]}" bench "$scene" --camera-path flythrough --frames "$frames" \
    --sweep mode=full --sweep blending=plain,volume --no-shading --json "$OUT/compositing.json"
fi
if wanted compute; then
  step "compute compositing tests" "$python" -m pytest -q "${plugin[@]}" tests/render/test_compute_compositing.py \
    tests/render/test_render_depth.py
  compute=(--sweep mode=full,auto --sweep splat_order=gpu --sweep compositing=raster,compute --no-shading)
  step "compute 640x480" "${cloudview[@]}" bench "$scene" --camera-path flythrough --frames "$frames" \
    "${compute[@]}" --json "$OUT/compute_640.json"
  step "compute 1600x1200" "${cloudview[@]}" bench "$scene" --camera-path flythrough --frames "$frames" \
    --width 1600 --height 1200 "${compute[@]}" --json "$OUT/compute_1600.json"
fi
if wanted sort; then
  step "sort" "$python" scripts/bench_gpu_sort.py --json "$OUT/sort.json"
fi
if wanted waits; then
  step "waits" "$python" scripts/bench_pass_waits.py --cases flythrough,still --frames "$fly_640" \
    --json "$OUT/waits.json"
fi
if wanted lod; then
  # shellcheck disable=SC2086
  step "lod" "${cloudview[@]}" bench --suite lod --cases still,flythrough $quick --json "$OUT/lod.json"
fi
if wanted field; then
  # shellcheck disable=SC2086
  step "field" "${cloudview[@]}" bench --suite lod --cases field $quick --json "$OUT/field.json"
fi
echo "done in $SECONDS s"
