"""Image comparison for screenshot tests and `cloudview compare`: PSNR, mean and max difference, a diff image."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


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
