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

    def added(self, directions, distances) -> tuple[np.ndarray, np.ndarray]:
        """(light added (..., 3), in the renderer's values as `in_scattered`'s, transmittance (..., 3)) along unit
        `directions` (..., 3) over `distances` (...) from the eye."""
        radiance, transmittance = self.volume.radiance_and_transmittance(directions, distances)
        return np.pi * PHYSICAL_EXPOSURE * radiance + NIGHT_SKY * (1.0 - transmittance), transmittance

    def seen_through(self, colour, directions, distances, alpha=1.0) -> np.ndarray:
        """(..., 3): premultiplied linear `colour` (..., 3) of opacity `alpha` (...) seen along unit `directions`
        (..., 3) from `distances` (...) away: colour * transmittance + alpha * in-scattered (the air in front
        of a cloud is added where the cloud covers what is behind it)."""
        added, transmittance = self.added(directions, distances)
        return (
            np.asarray(colour, dtype=np.float64) * transmittance
            + np.asarray(alpha, dtype=np.float64)[..., None] * added
        )


def air_between(sky: SkyBackground, eye_position, coarse: bool = False) -> AirBetween | None:
    """The air an eye at `eye_position` (scene metres, y up over the scene's origin) sees through, under `sky`;
    None under the gradient.  The preview's coarse volume where `coarse` or the sky is a preview's."""
    if not sky.physical:
        return None
    view = sky.view
    preview = coarse or view.preview
    return AirBetween(
        aerial_perspective_from(view.tables, sky.eye_altitude_m(eye_position), view.sun_direction, preview)
    )


#: the widest angle (radians) one cell of a quad seen through the air spans from the eye: the air is read at the
#: cells' corners and interpolated between them (shaders/quad.vert.glsl), which is exact only where it changes
#: linearly; chosen by the split impostor against full 3D (docs/atmosphere.md#aerial-perspective)
AIR_CELL_ANGLE = np.radians(10.0)
#: a side's cells at most: a quad around the eye is cut into this many squared
AIR_MAX_CELLS = 8


def air_cells(corners, eye) -> np.ndarray:
    """(n,) int: the cells a side each quad of `corners` (n, 4, 3: lower left, lower right, upper left, upper
    right) is cut into so that none spans more than `AIR_CELL_ANGLE` from `eye`, at most `AIR_MAX_CELLS`."""
    corners = np.asarray(corners, dtype=np.float64).reshape(-1, 4, 3)
    half_diagonal = 0.5 * np.maximum(
        np.linalg.norm(corners[:, 3] - corners[:, 0], axis=-1), np.linalg.norm(corners[:, 2] - corners[:, 1], axis=-1)
    )
    nearest = np.linalg.norm(corners.mean(axis=1) - np.asarray(eye, dtype=np.float64), axis=-1) - half_diagonal
    span = np.where(nearest > 0.0, 2.0 * np.arctan2(half_diagonal, np.maximum(nearest, 0.0)), np.pi)
    return np.clip(np.ceil(span / AIR_CELL_ANGLE), 1, AIR_MAX_CELLS).astype(np.int64)
