"""The air between the eye and what it sees, in the renderer's values: a surface's colour becomes
transmittance * colour + the in-scattered light (Hillaire 2020's aerial perspective), under the physical sky
alone (the gradient draws no air).  The world pass, the splats and the quads read the same volume on the GPU
(shaders/aerial_perspective.glsl); this is their numpy twin.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.atmosphere.aerial_perspective import AerialPerspective, aerial_perspective_from
from cloudcore.light.lighting import PHYSICAL_EXPOSURE
from cloudcore.light.sky_background import NIGHT_SKY, SkyBackground


@dataclass(frozen=True, eq=False)
class AirBetween:
    """An aerial-perspective volume (`cloudcore.atmosphere.aerial_perspective`) as the renderer draws it."""

    volume: AerialPerspective

    def in_scattered(self) -> np.ndarray:
        """(depth, height, width, 3): the light added, in the renderer's values, and the night's sky where the air
        hides what is behind it (as the sky keeps it under the model's: a far surface at night fades to it)."""
        return np.pi * PHYSICAL_EXPOSURE * self.volume.in_scattered + NIGHT_SKY * (1.0 - self.volume.transmittance)

    def transmittance(self) -> np.ndarray:
        return self.volume.transmittance

    def seen_through(self, colour, directions, distances, alpha=1.0) -> np.ndarray:
        """(..., 3): premultiplied linear `colour` (..., 3) of opacity `alpha` (...) seen along unit `directions`
        (..., 3) from `distances` (...) away: colour * transmittance + alpha * in-scattered (the air in front
        of a cloud is added where the cloud covers what is behind it)."""
        radiance, transmittance = self.volume.radiance_and_transmittance(directions, distances)
        added = np.pi * PHYSICAL_EXPOSURE * radiance + NIGHT_SKY * (1.0 - transmittance)
        return (
            np.asarray(colour, dtype=np.float64) * transmittance
            + np.asarray(alpha, dtype=np.float64)[..., None] * added
        )


def air_between(sky: SkyBackground, eye_position) -> AirBetween | None:
    """The air an eye at `eye_position` (scene metres, y up over the scene's origin) sees through, under `sky`;
    None under the gradient."""
    if not sky.physical:
        return None
    view = sky.view
    eye_altitude = view.altitude_m + float(np.asarray(eye_position, dtype=np.float64)[1])
    return AirBetween(aerial_perspective_from(view.tables, eye_altitude, view.sun_direction, view.preview))
