"""Where the sun is: its direction at an hour of the day, and the hour a scene's lighting stands for (numpy).

The sun follows the standard solar-position formula at a fixed latitude and
declination (mid-latitude late spring), so 12:00 is due south and highest,
sunrise and sunset are near 05:15 and 18:45, and midnight is well below the
horizon.  World axes: x east, y up, z south (north is -z).  The light it
gives is `cloudcore.light.lighting`'s.
"""

from __future__ import annotations

import numpy as np

from cloudcore.model.scene import Lighting

LATITUDE_DEG = 45.0
DECLINATION_DEG = 12.0


def check_time_of_day(hours: float) -> None:
    if not np.isfinite(hours) or not 0.0 <= hours <= 24.0:
        raise ValueError(f"time of day must be within [0, 24] hours, got {hours}")


def sun_direction(hours: float) -> np.ndarray:
    """Unit vector from the scene toward the sun at `hours` (0-24)."""
    check_time_of_day(hours)
    lat, dec = np.radians(LATITUDE_DEG), np.radians(DECLINATION_DEG)
    hour_angle = np.radians(15.0 * (hours - 12.0))
    up = np.sin(lat) * np.sin(dec) + np.cos(lat) * np.cos(dec) * np.cos(hour_angle)
    east = -np.cos(dec) * np.sin(hour_angle)
    north = np.cos(lat) * np.sin(dec) - np.sin(lat) * np.cos(dec) * np.cos(hour_angle)
    return np.array([east, up, -north])


def elevation_deg(direction) -> float:
    return float(np.degrees(np.arcsin(np.clip(direction[1], -1.0, 1.0))))


def scene_hour(lighting: Lighting) -> float:
    """The hour a scene's sky (and artist-shaded clouds) follow: its time of day, or the default one
    where explicit lights replace the sun."""
    return Lighting().time_of_day if lighting.time_of_day is None else lighting.time_of_day
