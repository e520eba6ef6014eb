"""Comparing renders with committed golden PNGs (tests/golden/), shared by the golden-image tests.

Tolerance: PSNR >= 40 dB and no channel off by more than 12 levels of 255, so
llvmpipe builds and GPUs may differ by rounding but not by a visible change.
On failure the numbers are printed and tests/_failures/ gets the rendered
image, the golden and an amplified diff.  Goldens are made on llvmpipe and
rewritten only on purpose:

    ./run tests tests/test_render_golden.py tests/test_render_presets.py --regenerate-goldens
"""

from pathlib import Path

import imageio.v3 as iio
import pytest

from cloudcore.imagecompare import compare, diff_image

GOLDEN = Path(__file__).parent / "golden"
FAILURES = Path(__file__).parent / "_failures"
MIN_PSNR_DB = 40.0
MAX_ABS = 12


def check_golden(image, name: str, request) -> None:
    """Fail unless `image` matches tests/golden/NAME.png (or rewrite it under --regenerate-goldens)."""
    golden_path = GOLDEN / f"{name}.png"
    if request.config.getoption("--regenerate-goldens"):
        golden_path.parent.mkdir(exist_ok=True)
        iio.imwrite(golden_path, image)
        pytest.skip(f"regenerated {golden_path}")
    assert golden_path.exists(), f"no golden {golden_path}: run with --regenerate-goldens on purpose"
    golden = iio.imread(golden_path)
    difference = compare(image, golden)
    if not difference.within(MIN_PSNR_DB, MAX_ABS):
        FAILURES.mkdir(exist_ok=True)
        iio.imwrite(FAILURES / f"{name}-actual.png", image)
        iio.imwrite(FAILURES / f"{name}-expected.png", golden)
        iio.imwrite(FAILURES / f"{name}-diff.png", diff_image(image, golden))
        pytest.fail(
            f"{name}: {difference} (limits: PSNR >= {MIN_PSNR_DB} dB, max |diff| <= {MAX_ABS}); images in {FAILURES}"
        )
    # every golden shows something: no NaN-black frame, no flat colour
    assert image.max(axis=2).min() > 0 and image.std() > 1.0
