"""Overdraw: how many splat fragments land on each pixel, measured and estimated (numpy).

The GL side counts blended fragments per pixel (`FrameRenderer.measure_overdraw`);
this module turns those counts into the reported numbers and a heat map, and
gives the analytic estimate Harris and Wang reason with: the summed screen area
of the splats over the screen area.  The estimate clips each disc to the
screen by its bounding square but ignores terrain in front, so it exceeds the
measured mean where hills hide clouds.
"""

from __future__ import annotations

import numpy as np

#: colour stops of the heat map, from no fragment (black) to the maximum (white)
_HEAT_STOPS = np.array([[0, 0, 0], [0, 0, 160], [190, 0, 120], [255, 110, 0], [255, 230, 60], [255, 255, 255]],
                       dtype=np.float64)


def overdraw_statistics(counts: np.ndarray) -> dict:
    """Mean over the screen, mean over covered pixels, and maximum of a per-pixel fragment count."""
    covered = counts > 0
    return {"overdraw_mean": float(counts.mean()) if counts.size else 0.0,
            "overdraw_mean_covered": float(counts[covered].mean()) if covered.any() else 0.0,
            "overdraw_max": float(counts.max()) if counts.size else 0.0}


def heat_map(counts: np.ndarray, scale_max: float | None = None) -> np.ndarray:
    """8-bit RGB: fragment counts mapped through the heat stops, 0 black, `scale_max` (default the max) white."""
    top = float(counts.max()) if scale_max is None and counts.size else float(scale_max or 0.0)
    level = np.clip(counts / top, 0.0, 1.0) if top > 0 else np.zeros_like(counts, dtype=np.float64)
    positions = np.linspace(0.0, 1.0, len(_HEAT_STOPS))
    rgb = np.stack([np.interp(level, positions, _HEAT_STOPS[:, c]) for c in range(3)], axis=-1)
    return np.round(rgb).astype(np.uint8)


def analytic_overdraw(centres: np.ndarray, radii: np.ndarray, view: np.ndarray, projection: np.ndarray,
                      near: float) -> float:
    """Sum of the splats' on-screen disc areas over the screen area (both in normalised device units).

    A splat is a disc of radius r parallel to the image plane at eye depth z, so
    its image is an ellipse of semi-axes r P[0,0] / z and r P[1,1] / z in NDC
    (x and y units differ by the aspect ratio); the screen is 2 x 2 NDC units.
    The part on screen is taken as the part of the disc's bounding box inside
    [-1, 1]^2.  Splats nearer than the near plane are not drawn.
    """
    eye_space = centres @ view[:3, :3].T + view[:3, 3]
    depth = -eye_space[:, 2]
    drawn = depth > near
    centre_ndc = np.column_stack([projection[0, 0] * eye_space[drawn, 0],
                                  projection[1, 1] * eye_space[drawn, 1]]) / depth[drawn, None]
    semi_axes = radii[drawn, None] * np.array([projection[0, 0], projection[1, 1]]) / depth[drawn, None]
    inside = np.clip(centre_ndc + semi_axes, -1.0, 1.0) - np.clip(centre_ndc - semi_axes, -1.0, 1.0)
    on_screen = np.prod(inside / (2.0 * semi_axes), axis=1)
    return float(np.sum(np.pi * np.prod(semi_axes, axis=1) * on_screen) / 4.0)
