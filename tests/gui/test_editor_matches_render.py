"""The editor's viewport shows what the headless renderer renders, at any window size.

The editor runs in a subprocess under Xvfb (`python -m app SCENE --window-size WxH --frames N
--screenshot OUT.png`: the viewport's own picture, at the viewport's size); the same scene,
camera and settings are then rendered headless at that size, after as many frames (the ring
built), and the two compared.  Any state the window path leaves different (GL state, viewport
or scissor, target sizes) shows here as a difference.  Skipped without a display.
"""

import os
import subprocess
import sys

import imageio.v3 as iio
import pytest

from cloudcore.measure.imagecompare import compare
from tests.conftest import VALLEY
from tests.goldens import FAILURES

pytestmark = pytest.mark.gui

#: enough frames to build the ring of impostors (8 segments) and fade it in (8 more)
FRAMES = 24
#: the picture may differ only by the sRGB encoding's rounding (on the GPU in the editor, on the CPU
#: headless); a GL-state bug (a smudge, a seam) costs far more
MIN_PSNR_DB = 40.0


#: the same view rendered headless, after as many frames, default settings: argv scene, width, height,
#: frames, output PNG
HEADLESS = """
import os, sys
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
import imageio.v3 as iio
from cloudcore.gl import FrameRenderer
from cloudcore.scenes.files import load_scene
from cloudcore.model.settings import RenderSettings
scene_path, width, height, frames, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
scene = load_scene(scene_path)
with FrameRenderer(width, height) as renderer:
    for _ in range(frames):
        image, _ = renderer.render(scene, settings=RenderSettings())
iio.imwrite(out, image)
"""


@pytest.mark.parametrize("window", ["1280x720", "1280x800", "1600x900", "1111x677"])
def test_the_viewport_equals_cloudview_render_of_the_same_view(tmp_path, window):
    if not os.environ.get("DISPLAY"):
        pytest.skip("no display: run the suite through ./run tests, which starts Xvfb")
    shot = tmp_path / "viewport.png"
    env = {k: v for k, v in os.environ.items() if k != "PYOPENGL_PLATFORM"}
    env["HOME"] = str(tmp_path)  # no layout file of the user's is read or written
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "app",
            str(VALLEY),
            "--window-size",
            window,
            "--frames",
            str(FRAMES),
            "--screenshot",
            str(shot),
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert result.returncode == 0 and shot.exists(), result.stderr[-3000:]
    shown = iio.imread(shot)
    height, width = shown.shape[:2]
    # headless in a process of its own: closing a second EGL display here would end the session's
    reference = tmp_path / "rendered.png"
    result = subprocess.run(
        [sys.executable, "-c", HEADLESS, str(VALLEY), str(width), str(height), str(FRAMES), str(reference)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    rendered = iio.imread(reference)
    difference = compare(shown, rendered)
    if difference.psnr_db < MIN_PSNR_DB:
        failures = str(FAILURES)
        os.makedirs(failures, exist_ok=True)
        iio.imwrite(os.path.join(failures, f"editor_{window}_shown.png"), shown)
        iio.imwrite(os.path.join(failures, f"editor_{window}_rendered.png"), rendered)
    assert difference.psnr_db >= MIN_PSNR_DB, f"window {window}, viewport {width}x{height}: {difference}"
