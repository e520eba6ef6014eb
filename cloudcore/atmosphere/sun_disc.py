"""The sun as a disc: its size, its limb darkening, and how much of it stands above the horizon."""

from __future__ import annotations

import numpy as np

#: the sun's angular radius, radians (its mean apparent diameter, 0.533 degrees)
SUN_ANGULAR_RADIUS = np.radians(0.533 / 2.0)
#: the linear limb-darkening coefficient in the visible: the rim is 1 - u as bright as the centre
LIMB_DARKENING = 0.6


def visible_fraction(sun_cosine, horizon_cosine) -> np.ndarray:
    """The share of the disc above the horizon: 1 when its centre is a radius above, 0 a radius below, between
    them the area of the circle above a chord."""
    elevation = np.arcsin(np.clip(sun_cosine, -1.0, 1.0))
    horizon_elevation = np.arcsin(np.clip(horizon_cosine, -1.0, 1.0))
    h = np.clip((elevation - horizon_elevation) / SUN_ANGULAR_RADIUS, -1.0, 1.0)
    return 1.0 - (np.arccos(h) - h * np.sqrt(1.0 - h * h)) / np.pi


def disc_radiance(angle_from_centre, pixel_angle: float) -> np.ndarray:
    """The disc's radiance per unit of its irradiance (1 / sr) at `angle_from_centre` (radians): limb darkened,
    its mean over the disc 1 / (its solid angle), and its rim spread over `pixel_angle` so a pixel partly on
    the disc shows that part."""
    angle = np.asarray(angle_from_centre, dtype=np.float64)
    radius_share = np.minimum(angle / SUN_ANGULAR_RADIUS, 1.0)
    limb = 1.0 - LIMB_DARKENING * (1.0 - np.sqrt(1.0 - radius_share * radius_share))
    mean_limb = 1.0 - LIMB_DARKENING / 3.0
    solid_angle = 2.0 * np.pi * (1.0 - np.cos(SUN_ANGULAR_RADIUS))
    coverage = np.clip((SUN_ANGULAR_RADIUS - angle) / max(pixel_angle, 1e-9) + 0.5, 0.0, 1.0)
    return coverage * limb / (mean_limb * solid_angle)
