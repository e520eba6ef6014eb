"""A model's picture against the path-traced truth (`cloudcore.measure.truth`), region by region: the regions
(sky, silhouette, the body lit and shadowed) read from the truth alone, and per region the PSNR and the error in
luminance (numpy; `cloudview truth` reports them).
"""

from __future__ import annotations

import numpy as np

from cloudcore.maths.colour import srgb_decode
from cloudcore.measure.benchmark import PSNR_CAP_DB
from cloudcore.measure.imagecompare import compare

#: Rec. 709 weights of linear RGB in relative luminance
LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722])
#: a pixel is cloud where the truth's alpha is at least the first, the cloud's body (no longer its
#: silhouette) from the second: a view-ray optical depth of 2.3
CLOUD_ALPHA, BODY_ALPHA = 0.02, 0.9
REGIONS = ("image", "sky", "silhouette", "lit", "shadowed")


def truth_regions(alpha: np.ndarray, sun_depth: np.ndarray) -> dict[str, np.ndarray]:
    """Boolean masks (height, width) of the regions errors are split into, from the truth alone.

    sky: alpha < CLOUD_ALPHA; silhouette: CLOUD_ALPHA <= alpha < BODY_ALPHA; the body splits into lit,
    where the sun reaches the point the eye sees (where the view ray's optical depth reaches 1) through
    an optical depth below 1, and shadowed, the rest (everything, without a sun).
    """
    cloud = alpha >= CLOUD_ALPHA
    body = alpha >= BODY_ALPHA
    lit = body & (sun_depth < 1.0)
    return {
        "image": np.ones(alpha.shape, dtype=bool),
        "sky": ~cloud,
        "silhouette": cloud & ~body,
        "lit": lit,
        "shadowed": body & ~lit,
    }


def luminance(srgb8: np.ndarray) -> np.ndarray:
    """Relative luminance (linear) of 8-bit sRGB pixels (..., 3)."""
    return srgb_decode(np.asarray(srgb8, dtype=np.float64) / 255.0) @ LUMINANCE_WEIGHTS


def region_errors(truth8: np.ndarray, model8: np.ndarray, regions: dict[str, np.ndarray]) -> dict[str, dict]:
    """Per region: pixels, PSNR of the 8-bit images (capped at PSNR_CAP_DB), the truth's mean luminance,
    mean luminance error (model - truth, linear: negative is too dark) and mean absolute luminance error."""
    truth_luminance = luminance(truth8)
    difference = luminance(model8) - truth_luminance
    errors = {}
    for name, mask in regions.items():
        pixels = int(mask.sum())
        if pixels == 0:
            errors[name] = {"pixels": 0}
            continue
        errors[name] = {
            "pixels": pixels,
            "psnr_db": min(compare(truth8[mask], model8[mask]).psnr_db, PSNR_CAP_DB),
            "truth_luminance": float(truth_luminance[mask].mean()),
            "mean_luminance_error": float(difference[mask].mean()),
            "mean_abs_luminance_error": float(np.abs(difference[mask]).mean()),
        }
    return errors
