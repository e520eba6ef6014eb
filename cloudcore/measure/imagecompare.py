"""Image comparison for screenshot tests and `cloudview compare`: PSNR, mean and max difference, a diff image."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cloudcore.model.errors import SceneError


@dataclass(frozen=True)
class Difference:
    psnr_db: float  # inf for identical images
    mean_abs: float  # in 8-bit levels
    max_abs: int

    def within(self, min_psnr_db: float, max_abs: int) -> bool:
        return self.psnr_db >= min_psnr_db and self.max_abs <= max_abs

    def __str__(self) -> str:
        return f"PSNR {self.psnr_db:.2f} dB, mean |diff| {self.mean_abs:.3f}, max |diff| {self.max_abs}"


def compare(a: np.ndarray, b: np.ndarray) -> Difference:
    """Difference between two 8-bit images of the same shape."""
    if a.shape != b.shape:
        raise ValueError(f"image sizes differ: {a.shape} and {b.shape}")
    diff = np.abs(a.astype(np.int64) - b.astype(np.int64))
    mse = float(np.mean(diff.astype(np.float64) ** 2))
    psnr = float("inf") if mse == 0 else 10.0 * np.log10(255.0**2 / mse)
    return Difference(psnr, float(diff.mean()), int(diff.max()) if diff.size else 0)


def diff_image(a: np.ndarray, b: np.ndarray, gain: float = 8.0) -> np.ndarray:
    """Per-pixel largest channel difference, amplified by `gain`, as a red-on-black 8-bit RGB image."""
    largest = np.abs(a.astype(np.int64) - b.astype(np.int64)).reshape(*a.shape[:2], -1).max(axis=2)
    out = np.zeros((*a.shape[:2], 3), dtype=np.uint8)
    out[..., 0] = np.clip(largest * gain, 0, 255).astype(np.uint8)
    return out


def load_rgb8(path: Path) -> np.ndarray:
    """The image at `path` as an (H, W, 3) uint8 array; anything else is a SceneError."""
    import imageio.v3 as iio

    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise SceneError(path, "(file)", "no such file") from None
    except OSError as error:
        raise SceneError(path, "(file)", f"cannot read: {error.strerror or error}") from None
    # Decoding bytes leaves imageio no file to leak; its plugins warn (deprecations) while they
    # probe a file that is not an image, which would break the one-line error.
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            image = np.asarray(iio.imread(data, index=0))
    except Exception:  # imageio raises many kinds (OSError, ValueError, struct.error), often multi-line
        raise SceneError(path, "(file)", "not a readable image") from None
    if image.dtype == np.uint16:
        image = (image >> 8).astype(np.uint8)
    elif image.dtype != np.uint8:
        raise SceneError(path, "(pixels)", f"expected 8- or 16-bit integers, got {image.dtype}")
    if image.ndim == 2:
        image = image[..., None]
    if image.ndim != 3 or image.shape[2] not in (1, 2, 3, 4):
        raise SceneError(path, "(pixels)", f"expected grey, RGB or RGBA, got shape {image.shape}")
    # grey (+alpha) repeats its one colour channel; RGB(A) keeps its first three
    colour = image[..., :1] if image.shape[2] <= 2 else image[..., :3]
    return np.ascontiguousarray(np.broadcast_to(colour, (*image.shape[:2], 3)))
