"""Comparing renders with committed golden PNGs (tests/golden/), shared by the golden-image tests.

The comparison is `cloudview check`'s (`cloudcore.measure.screenshot_check`), with its
default tolerance: PSNR >= 40 dB and no channel off by more than 12 levels of
255, so llvmpipe builds and GPUs may differ by rounding but not by a visible
change.  On failure the line says why and tests/_failures/golden/ gets the
rendered image, the golden and an amplified diff.  Goldens are made on
llvmpipe and rewritten only on purpose (those whose pixels changed):

    ./run tests tests/render/test_render_golden.py tests/render/test_render_presets.py --regenerate-goldens
"""

from pathlib import Path

import pytest

from cloudcore.measure.screenshot_check import Tolerance, check_view, keep_images, update_golden

GOLDEN = Path(__file__).parent / "golden"
FAILURES = Path(__file__).parent / "_failures"
TOLERANCE = Tolerance()
MIN_PSNR_DB, MAX_ABS = TOLERANCE.min_psnr_db, TOLERANCE.max_diff
REGENERATE = "./run tests tests/render/test_render_golden.py tests/render/test_render_presets.py --regenerate-goldens"


def check_golden(image, name: str, request) -> None:
    """Fail unless `image` matches tests/golden/NAME.png (or rewrite it under --regenerate-goldens)."""
    result = check_view("golden", name, image, GOLDEN / f"{name}.png", TOLERANCE)
    if request.config.getoption("--regenerate-goldens"):
        if update_golden(result, image):
            pytest.skip(f"regenerated {result.golden}")
    elif not result.passed:
        keep_images(FAILURES, result, image)
        pytest.fail(f"{result.line(REGENERATE)}; images in {FAILURES / result.scene}", pytrace=False)
    # every golden shows something: no NaN-black frame, no flat colour
    assert image.max(axis=2).min() > 0 and image.std() > 1.0
