"""The sky behind everything, in the renderer's linear values: the two-colour gradient of before, or the
atmosphere's sky (its sky-view table) with the sun's disc, limb darkened, its radiance the beam that reaches
the scene.  The world pass draws the same (gl/shaders/sky.frag.glsl, `sky`); the path-traced truth
composites this one behind its clouds.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from cloudcore.atmosphere.aerial_perspective import volume_altitude
from cloudcore.atmosphere.geometry import horizon_cosine, ray_hits_ground
from cloudcore.atmosphere.sky import SkyView, sky_seen_from
from cloudcore.atmosphere.sky_view import eye_radius
from cloudcore.atmosphere.sun_disc import disc_radiance
from cloudcore.light.lighting import (
    NIGHT_AMBIENT,
    PHYSICAL_EXPOSURE,
    physical_sky,
    physical_sun,
    sky_colors,
    sky_gradient,
)
from cloudcore.model.scene import Lighting
from cloudcore.world.sun import scene_hour

#: the brightest the sun's disc is drawn, in the renderer's linear values (its physical peak is about 4e4): the
#: 16-bit float targets' blending rounds a cloud's 1 - alpha to 2^-11, so a brighter disc would show through
#: an opaque cloud (32 * 2^-11 = 1.6% of white at most); it is still far past what 8 bits can show
SUN_DISC_PEAK = 32.0
#: how far above the ray grazing the planet the sky at and below the horizon is looked up (a cosine): a row of
#: the sky-view table above the ground's half, which filtering would otherwise blend in
HORIZON_MARGIN = 1e-3


def over_the_horizon(directions, horizon: float) -> np.ndarray:
    """Unit `directions` (..., 3) raised to just over the `horizon` (the cosine to the up of the ray grazing the
    planet), each keeping its azimuth: below the horizon of a scene without a terrain, the air at the horizon is
    drawn (sky.frag.glsl does the same); with one, the ground past it (`cloudcore.light.far_ground`)."""
    directions = np.asarray(directions, dtype=np.float64)
    up = horizon + HORIZON_MARGIN
    across = np.linalg.norm(directions[..., [0, 2]], axis=-1, keepdims=True)
    scale = np.sqrt(1.0 - up * up) / np.maximum(across, 1e-300)
    level = np.where(across > 1e-12, directions[..., [0, 2]] * scale, [np.sqrt(1.0 - up * up), 0.0])
    return np.stack([level[..., 0], np.full(directions.shape[:-1], up), level[..., 1]], axis=-1)


def sky_view_altitude(params, eye_altitude_m: float) -> float:
    """The altitude whose sky-view table an eye at `eye_altitude_m` sees: rounded as the air's volume is
    (`volume_altitude`), and over the top of the air the top's (the table clamps its eye there, `eye_radius`: one
    table, not one a step)."""
    return min(volume_altitude(eye_altitude_m), params.top_radius_m - params.bottom_radius_m)


#: the night's sky under the moon and the stars, which the atmosphere (the sun's light alone) leaves black: the
#: gradient's night zenith, as the ambient keeps its night floor (`lighting.NIGHT_AMBIENT`)
NIGHT_SKY = 0.8 * NIGHT_AMBIENT


def ground_behind_the_air(far_ground) -> np.ndarray:
    """(3,): what the far ground of colour `far_ground` adds to the sky's air in front of it per unit of the air's
    transmittance: the table holds the night's sky whole, where the air hides a surface only in part (the air's
    volume keeps the night's sky where it hides what is behind, `air_between`), so the ground takes its share off
    (the sum stays positive: the share is at most the night's sky)."""
    return np.asarray(far_ground, dtype=np.float64) - NIGHT_SKY


@dataclass(frozen=True, eq=False)
class SkyBackground:
    """The gradient's (zenith, horizon) colours, or the physical sky: its view and the sun's light."""

    zenith: np.ndarray | None = None
    horizon: np.ndarray | None = None
    view: SkyView | None = None
    #: (3,) the sun's irradiance reaching the scene, renderer values (`lighting.physical_sun`)
    sun_irradiance: np.ndarray | None = None
    #: the altitude over the sea of the scene's origin, where its y is 0 (`Air.origin_altitude_m`); `view` is the
    #: sky seen from there, or from an eye (`seen_from`)
    origin_altitude_m: float = 0.0

    @property
    def physical(self) -> bool:
        return self.view is not None

    def eye_altitude_m(self, eye_position) -> float:
        """The altitude over the sea of an eye at `eye_position` (scene metres, y up)."""
        return self.origin_altitude_m + float(np.asarray(eye_position, dtype=np.float64)[1])

    def seen_from(self, eye_position) -> SkyBackground:
        """This sky as an eye at `eye_position` sees it: the table from its altitude, rounded as the air's volume
        is (`volume_altitude`, 100 m: neighbouring steps' skies differ by less than 8 bits show), so a climbing
        eye sees the horizon sink and the zenith darken (2 km up the sky is 31 dB from the one at the ground).
        The gradient sky is the same from everywhere."""
        if not self.physical:
            return self
        view = self.view
        params = view.tables.params
        altitude = sky_view_altitude(params, self.eye_altitude_m(eye_position))
        if altitude == view.altitude_m:
            return self
        seen = sky_seen_from(params, altitude, view.sun_direction, view.preview)
        return dataclasses.replace(self, view=seen)

    def table(self) -> np.ndarray:
        """(height, width, 3): the sky-view table in the renderer's values, the night's sky under it."""
        return np.pi * PHYSICAL_EXPOSURE * self.view.table + NIGHT_SKY

    def sun_disc_scale(self) -> np.ndarray:
        """(3,): the disc's colour per unit of `disc_radiance`, lowered as a whole where its centre would pass
        SUN_DISC_PEAK."""
        scale = np.pi * self.sun_irradiance
        peak = float(scale.max()) * float(disc_radiance(0.0, 1.0))
        return scale * min(1.0, SUN_DISC_PEAK / peak) if peak > 0.0 else scale

    def lowest_up(self) -> float:
        """The cosine to the up of the lowest direction the physical sky is looked up along: one below it is drawn
        as the one at it with its azimuth (`over_the_horizon`)."""
        params = self.view.tables.params
        return float(horizon_cosine(eye_radius(params, self.view.altitude_m), params.bottom_radius_m)) + HORIZON_MARGIN

    def radiance(self, directions, pixel_angle: float, far_ground=None) -> np.ndarray:
        """(..., 3): the sky along unit `directions` (..., 3), the sun's disc with its rim spread over
        `pixel_angle` (radians, a pixel's side); below the horizon the planet's ground of the renderer's colour
        `far_ground` (3,) seen through the air (`cloudcore.light.far_ground`), or without one the air at the
        horizon (`over_the_horizon`)."""
        directions = np.asarray(directions, dtype=np.float64)
        if not self.physical:
            return sky_gradient(directions, self.zenith, self.horizon)
        params = self.view.tables.params
        r = eye_radius(params, self.view.altitude_m)
        above = ~ray_hits_ground(r, directions[..., 1], params.bottom_radius_m)
        horizon = float(horizon_cosine(r, params.bottom_radius_m))
        if far_ground is None:
            low = directions[..., 1:2] < horizon + HORIZON_MARGIN
            seen = np.where(low, over_the_horizon(directions, horizon), directions)
            sky = np.pi * PHYSICAL_EXPOSURE * self.view.radiance(seen) + NIGHT_SKY
        else:
            through = (~above)[..., None] * self.view.ground_transmittance(directions)
            sky = np.pi * PHYSICAL_EXPOSURE * self.view.radiance(directions) + NIGHT_SKY
            sky = sky + through * ground_behind_the_air(far_ground)
        # the angle from the sun's centre by its chord, exact near 0 where acos is not
        chord = np.linalg.norm(directions - self.view.sun_direction, axis=-1)
        angle = 2.0 * np.arcsin(np.clip(0.5 * chord, 0.0, 1.0))
        disc = (above * disc_radiance(angle, pixel_angle))[..., None] * self.sun_disc_scale()
        return sky + disc


def scene_sky(lighting: Lighting, preview: bool = False) -> SkyBackground:
    """The sky a scene's lighting draws; the physical one's table coarser for a `preview` (a dragged slider)."""
    hours = scene_hour(lighting)
    if lighting.air.sky == "physical":
        return SkyBackground(
            view=physical_sky(hours, lighting.air, preview),
            sun_irradiance=physical_sun(hours, lighting.air),
            origin_altitude_m=lighting.air.origin_altitude_m,
        )
    return SkyBackground(*sky_colors(hours))
