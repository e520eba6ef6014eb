"""What each cloud particle sends toward the eye: linear RGB and opacity (numpy, float64).

Harris eq. 5: a particle scatters toward the eye the light that reached it
(precomputed per light by `cloudcore.illumination`) times its scattering
coefficient times the phase function at the angle between the light and the
view ray, plus ambient light in proportion to its opacity, all tinted by the
cloud's colour (white by default).  A cloud that forms or dissipates has
both scaled by its opacity factor (Wang section 4 multiplies it into the
sprite's alpha; the colour here is premultiplied).  `light.direction`
points from the scene toward the light, so a view ray pointing at the light
(omega = particle - eye parallel to light.direction) sees light scattered
straight on: cos_theta = +1, the forward lobe that makes silver linings.

The colour is the light the particle adds, so it is already premultiplied;
the splat shader scales colour and opacity by the kernel and the blend is
dst = src + (1 - src_alpha) dst.
"""

from __future__ import annotations

import numpy as np

from cloudcore.formation import core_distances, opacity_factor
from cloudcore.illumination import IlluminationCache, cloud_optics, illuminate_clouds
from cloudcore.lighting import active_lights
from cloudcore.phase import phase_function
from cloudcore.ramps import smoothstep
from cloudcore.scene import Shading
from cloudcore.shading import scattering_coefficient

#: a particle fades out between these distances from the eye, in radii, so the
#: camera inside one never gets a screen-filling quad.
FADE_START_RADII = 0.5
FADE_END_RADII = 1.5


class ParticleShading:
    """All particles of a scene's clouds, concatenated, with their illumination precomputed."""

    def __init__(self, clouds, shading: Shading, lights, ambient, method: str = "exact",
                 cache: IlluminationCache | None = None):
        """`cache` keeps the illumination of unchanged clouds between instances (the editor)."""
        clouds = tuple(clouds)
        self._phase, self._g = shading.phase, shading.g
        lights = active_lights(lights)
        self._light_directions = np.array([l.direction for l in lights], dtype=np.float64).reshape(-1, 3)
        self._light_radiance = np.array([np.asarray(l.color) * l.intensity for l in lights],
                                        dtype=np.float64).reshape(-1, 3)
        self._ambient = np.asarray(ambient, dtype=np.float64)

        counts = np.array([len(c.particles) for c in clouds], dtype=np.int64)
        self.cloud_starts = np.concatenate([[0], np.cumsum(counts)])
        self.centres = _concatenated([c.centres for c in clouds], (0, 3))
        self.radii = _concatenated([c.radii for c in clouds], (0,))
        optics = [cloud_optics(c, shading) for c in clouds]
        tau = _concatenated([o[0] for o in optics], (0,))
        albedo = _concatenated([o[1] for o in optics], (0,))
        self._alpha = -np.expm1(-tau)
        self._scattering = scattering_coefficient(tau, albedo, shading.phase, shading.g)
        self._tint = np.repeat(np.array([c.color for c in clouds], dtype=np.float64).reshape(-1, 3), counts, axis=0)
        incident = (cache.incident(clouds, shading, lights, method) if cache is not None
                    else illuminate_clouds(clouds, shading, lights, method))
        self._incident = _concatenated(incident, (0, len(lights)))

        spheres = [c.bounding_sphere() for c in clouds]
        self.bounding_centres = np.array([s[0] for s in spheres], dtype=np.float64).reshape(-1, 3)
        self.bounding_radii = np.array([s[1] for s in spheres], dtype=np.float64)
        # only clouds that form or dissipate: (first particle, end, formation, core distances)
        self._forming = [(start, stop, c.formation, core_distances(c.centres))
                         for c, start, stop in zip(clouds, self.cloud_starts[:-1], self.cloud_starts[1:])
                         if c.formation is not None]

    def seen_from(self, eye, indices: np.ndarray, *, time_s: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(linear RGB (n, 3), opacity (n,)) of particles `indices` seen from `eye`, near fade applied.

        Given `time_s` (the scene clock), clouds that form or dissipate are
        scaled by their opacity factor at that time (`cloudcore.formation`).
        """
        offset = self.centres[indices] - np.asarray(eye, dtype=np.float64)
        distance = np.linalg.norm(offset, axis=1)
        # a particle centred on the eye is faded to nothing below, so its direction does not matter
        view = offset / np.maximum(distance, np.finfo(np.float64).tiny)[:, None]
        scattered = np.zeros((len(indices), 3))
        for light, (direction, radiance) in enumerate(zip(self._light_directions, self._light_radiance)):
            phase = phase_function(view @ direction, self._phase, self._g)
            scattered += (self._incident[indices, light] * phase)[:, None] * radiance
        alpha = self._alpha[indices]
        colour = (scattered * self._scattering[indices, None] + self._ambient * alpha[:, None]) * self._tint[indices]
        radii = self.radii[indices]
        fade = smoothstep(FADE_START_RADII * radii, FADE_END_RADII * radii, distance)
        if time_s is not None and self._forming:
            fade = fade * self._formation_factors(time_s)[indices]
        return colour * fade[:, None], alpha * fade

    def _formation_factors(self, time_s: float) -> np.ndarray:
        """Every particle's formation opacity factor at `time_s`: 1 in clouds without a formation."""
        factors = np.ones(len(self.radii))
        for start, stop, formation, distances in self._forming:
            factors[start:stop] = opacity_factor(formation, distances, time_s)
        return factors


def _concatenated(parts, empty_shape) -> np.ndarray:
    """np.concatenate that also accepts no parts (a scene without clouds)."""
    return np.concatenate(parts) if parts else np.zeros(empty_shape)
