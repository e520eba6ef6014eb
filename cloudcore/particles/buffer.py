"""What each cloud particle sends toward the eye: linear RGB and opacity (numpy, float64).

Harris eq. 5: a particle scatters toward the eye the light that reached it
(precomputed per light by `cloudcore.light.illumination`) times its scattering
coefficient times the phase function at the angle between the light and the
view ray, plus ambient light in proportion to its opacity, all tinted by the
cloud's colour (white by default).  Yusov's eye pass (HPG 2014, section 4.4)
replaces scattering coefficient times phase by its opacity times the light
leaving his precomputed reference particle toward the eye, p(mu) single(mu) +
multiple(mu) (`cloudcore.light.precomputed`).  A cloud that forms or dissipates has
both scaled by its opacity factor (Wang section 4 multiplies it into the
sprite's alpha; the colour here is premultiplied).  `light.direction`
points from the scene toward the light, so a view ray pointing at the light
(omega = particle - eye parallel to light.direction) sees light scattered
straight on: cos_theta = +1, the forward lobe that makes silver linings.

The colour is the light the particle adds, so it is already premultiplied;
the splat shader scales colour and opacity by the kernel and the blend is
dst = src + (1 - src_alpha) dst.

`seen_from` is the reference: the splat compute shader (`cloudcore/gl/shaders/
splat_shade.comp.glsl`) evaluates the same sum per particle from the arrays
kept here, so the CPU only sorts, and tests hold the two together.  Clouds
shaded by Wang's artist model instead (`styles`) have their reference in
`cloudcore.artist.artist_shading.artist_colours`.
"""

from __future__ import annotations

import copy

import numpy as np

from cloudcore.artist.formation import core_distances, opacity_factor
from cloudcore.artist.particle_styles import ParticleStyles, particle_styles
from cloudcore.artist.sprites import CELL_PIXELS
from cloudcore.field.shadow_cells import CellShadowing
from cloudcore.light.ground_bounce import bounce_share
from cloudcore.light.illumination import IlluminationCache, cloud_optics, light_pass_method
from cloudcore.light.lighting import active_lights
from cloudcore.light.phase import phase_function
from cloudcore.light.precomputed import eye_pass_profiles
from cloudcore.light.shading import RETURNING_LIGHT_PASSES, eye_pass_coefficients
from cloudcore.light.splat_look import inner_light_depth
from cloudcore.maths.ramps import smoothstep
from cloudcore.model.scene import Lighting, Shading, Terrain

#: a particle fades out between these distances from the eye, in radii, so the
#: camera inside one never gets a screen-filling quad.
FADE_START_RADII = 0.5
FADE_END_RADII = 1.5


class ParticleBuffer:
    """The scene's packed particle buffer: every cloud's particles concatenated, with what the splats are
    drawn from (their incident light per light, scattering and ambient terms, styles, formation), and their
    colour seen from an eye (`seen_from`, the reference of the GL side's eye pass)."""

    def __init__(
        self,
        clouds,
        shading: Shading,
        lights,
        ambient,
        method: str = "exact",
        cache: IlluminationCache | None = None,
        styles: ParticleStyles | None = None,
        between_clouds: bool | CellShadowing = False,
        ground: Terrain | None = None,
    ):
        """`cache` keeps the illumination of unchanged clouds between instances (the editor);
        `styles` (`cloudcore.artist.particle_styles`, by default at the default hour) say which clouds
        are sprites or artist-shaded; with `between_clouds` the sun reaches each cloud through the others
        (`cloudcore.light.illumination.sun_through_others`; a `CellShadowing`: a cloud field's cells through one
        another).  With `shading.ground_bounce`, `lights` and `ambient` are `cloud_lights`' and the bounce comes
        from the `ground` (its heights; y = 0 without one) below each particle, in the clouds' shadow."""
        clouds = tuple(clouds)
        self.styles = styles if styles is not None else particle_styles(clouds, Lighting())
        self.phase, self.g = shading.phase, shading.g
        # the clouds' shadows fall in the first light's beam (the sun), whether or not the others give light
        scene_lights, lights = tuple(lights), active_lights(lights)
        self.light_directions = np.array([light.direction for light in lights], dtype=np.float64).reshape(-1, 3)
        radiance = [np.asarray(light.color) * light.intensity for light in lights]
        self.light_radiance = np.array(radiance, dtype=np.float64).reshape(-1, 3)
        self.ambient = np.asarray(ambient, dtype=np.float64)

        counts = np.array([len(c.particles) for c in clouds], dtype=np.int64)
        self.cloud_starts = np.concatenate([[0], np.cumsum(counts)])
        self.centres = _concatenated([c.centres for c in clouds], (0, 3))
        self.radii = _concatenated([c.radii for c in clouds], (0,))
        optics = [cloud_optics(c, shading) for c in clouds]
        tau = _concatenated([o[0] for o in optics], (0,))
        albedo = _concatenated([o[1] for o in optics], (0,))
        self.alpha = -np.expm1(-tau)
        #: per particle, the optical depth across it by which the sun's light falls inside it, for the eye pass
        #: per pixel (`cloudcore.light.splat_look.inner_light_depth`)
        self.inner_light_depth = inner_light_depth(tau, albedo)
        artist = np.array([c.artist is not None for c in clouds], dtype=bool)
        self._opaque = (self.alpha > 0.0) | np.repeat(artist, counts)
        self._near_faded = self.styles.near_faded
        #: per particle: what multiplies the scattered light, and the ambient light, toward the eye
        self.scattering, self.ambient_weight = eye_pass_coefficients(
            tau, albedo, shading.phase, shading.g, shading.eye_pass
        )
        #: Yusov's eye pass: the reference particle's light leaving toward the eye, per particle; None
        #: for the others, whose light is the phase function times the scattering coefficient
        self.profiles = (
            eye_pass_profiles(tau, albedo, shading.phase, shading.g) if shading.eye_pass == "yusov" else None
        )
        self.tint = np.repeat(np.array([c.color for c in clouds], dtype=np.float64).reshape(-1, 3), counts, axis=0)
        cache = IlluminationCache() if cache is None else cache
        incident, returned = cache.light_parts(clouds, shading, scene_lights, method, between_clouds=between_clouds)
        #: (n, lights): light that reached each particle, per light (Harris's light pass), all of it
        self.incident = _concatenated(incident, (0, len(lights)))
        #: (n, lights): the part of `incident` a cloud's lit face sent back (`cloudcore.light.lit_face`), which
        #: arrives from every direction; None where the light pass sends none back
        self.returned = (
            _concatenated(returned, (0, len(lights)))
            if light_pass_method(shading, method) in RETURNING_LIGHT_PASSES
            else None
        )
        if shading.ground_bounce and lights and lights[-1] is scene_lights[-1]:
            # the bounce, `cloud_lights`' last light, is the ground's straight below each particle
            share = bounce_share(self.centres, self.radii, self.alpha, scene_lights, self.ambient, ground)
            self.incident[:, -1] *= share
            if self.returned is not None:
                self.returned[:, -1] *= share

        #: (clouds,) metres: the finest detail in each cloud (0 for an empty one), which bounds how
        #: fine an impostor texture needs to be (`cloudcore.lod.impostors.detail_size_px`); each cloud's
        #: bounding sphere
        self.finest_radii, self.bounding_centres, self.bounding_radii = cloud_extents(
            clouds, self.radii, self.cloud_starts, self.styles
        )
        # only clouds that form or dissipate: (first particle, end, formation, core distances)
        self._forming = [
            (start, stop, c.formation, core_distances(c.centres))
            for c, start, stop in zip(clouds, self.cloud_starts[:-1], self.cloud_starts[1:])
            if c.formation is not None
        ]
        self._formation_memo: tuple[float, np.ndarray] | None = None
        #: per particle, the blend weights of the eye's frame (a cloud field's rings), None: all 1
        self._weights: np.ndarray | None = None
        #: changes whenever the weights do, so the GL side uploads them only then
        self.weights_serial = 0

    def carried(self, offsets: np.ndarray, cloud_shifts: np.ndarray, grown: float) -> ParticleBuffer:
        """These particles, each moved by `offsets` (n, 3) metres, with the light, styles and formation they have:
        the wind's drift and turbulence since their light was made (`cloudcore.world.wind.AirMotion.carry`).  Each
        cloud's bounding sphere moves by its `cloud_shifts` (clouds, 3) and grows by `grown` metres, the most a
        particle strays from its cloud's shift."""
        moved = copy.copy(self)
        moved.centres = self.centres + offsets
        moved.bounding_centres = self.bounding_centres + cloud_shifts
        moved.bounding_radii = np.where(self.bounding_radii > 0.0, self.bounding_radii + grown, 0.0)
        return moved

    def seen_from(self, eye, indices: np.ndarray, *, time_s: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(linear RGB (n, 3), opacity (n,)) of particles `indices` seen from `eye`, near fade applied.

        Given `time_s` (the scene clock), clouds that form or dissipate are
        scaled by their opacity factor at that time (`cloudcore.artist.formation`).
        """
        offset = self.centres[indices] - np.asarray(eye, dtype=np.float64)
        distance = np.linalg.norm(offset, axis=1)
        # a particle centred on the eye is faded to nothing below, so its direction does not matter
        view = offset / np.maximum(distance, np.finfo(np.float64).tiny)[:, None]
        scattered = np.zeros((len(indices), 3))
        for light, (direction, radiance) in enumerate(zip(self.light_directions, self.light_radiance)):
            mu = view @ direction
            # the light along the light's direction at the angle mu; what a lit face sends back, from every
            # direction behind the particle, with the phase function's mean over the sphere, 1 (Rayleigh's over
            # either hemisphere too)
            phase, around = phase_function(mu, self.phase, self.g), 1.0
            if self.profiles is not None:
                single, multiple = self.profiles.at(indices, mu)
                phase, around = phase * single + multiple, single + multiple
            back = 0.0 if self.returned is None else self.returned[indices, light]
            scattered += ((self.incident[indices, light] - back) * phase + back * around)[:, None] * radiance
        alpha = self.alpha[indices]
        ambient = self.ambient * self.ambient_weight[indices, None]
        colour = (scattered * self.scattering[indices, None] + ambient) * self.tint[indices]
        radii = self.radii[indices]
        fade = smoothstep(FADE_START_RADII * radii, FADE_END_RADII * radii, distance)
        factors = self.opacity_factors(time_s)
        if factors is not None:
            fade = fade * factors[indices]
        return colour * fade[:, None], alpha * fade

    def drawn(self, indices: np.ndarray, distances: np.ndarray, time_s: float | None = None) -> np.ndarray:
        """Which of `indices`, at `distances` from the eye, have any opacity: the rest need no draw.

        Splats vanish next to the eye (the near fade); sprites lock there instead and stay.
        Harris's opacity is the particle's own, the artist model's its colour level's.
        """
        kept = ((distances > FADE_START_RADII * self.radii[indices]) | ~self._near_faded[indices]) & self._opaque[
            indices
        ]
        factors = self.opacity_factors(time_s)
        return kept if factors is None else kept & (factors[indices] > 0.0)

    @property
    def drawn_bits(self) -> np.ndarray:
        """(n,) uint32, what `drawn` tests of each particle besides its distance and opacity factors: bit 0 its
        near fade (a splat's; sprites lock instead), bit 1 any opacity at all; for the GPU's own test
        (`cloudcore/gl/shaders/splat_select.comp.glsl`)."""
        return self._near_faded.astype(np.uint32) | self._opaque.astype(np.uint32) << 1

    def weigh(self, weights: np.ndarray | None) -> None:
        """Set every particle's blend weight in [0, 1] for the frames to come (None: all 1).

        A cloud field's rings blend by these (`cloudcore.field.grid.level_weights`); they change as the eye moves,
        the particles do not, so the buffer is kept and only its weights are replaced.
        """
        if weights is None and self._weights is None:
            return
        if weights is not None:
            weights = np.asarray(weights, dtype=np.float64)
            if weights.shape != self.radii.shape:
                raise ValueError(f"expected {len(self.radii)} weights, got shape {weights.shape}")
            if self._weights is not None and np.array_equal(weights, self._weights):
                return
        self._weights = weights
        self.weights_serial += 1

    def opacity_factors(self, time_s: float | None) -> np.ndarray | None:
        """What multiplies each particle's colour and opacity: its formation factor at `time_s` times its blend
        weight (`weigh`); None when both are 1 everywhere."""
        factors = self.formation_factors(time_s)
        if self._weights is None:
            return factors
        return self._weights if factors is None else factors * self._weights

    def formation_factors(self, time_s: float | None) -> np.ndarray | None:
        """Every particle's formation opacity factor at `time_s` (1 in clouds without a formation), or
        None when nothing forms or dissipates (or no time is given): then every factor is 1."""
        if time_s is None or not self._forming:
            return None
        if self._formation_memo is None or self._formation_memo[0] != time_s:
            factors = np.ones(len(self.radii))
            for start, stop, formation, distances in self._forming:
                factors[start:stop] = opacity_factor(formation, distances, time_s)
            self._formation_memo = (time_s, factors)
        return self._formation_memo[1]


def cloud_extents(clouds, radii: np.ndarray, cloud_starts: np.ndarray, styles: ParticleStyles) -> tuple:
    """(finest detail per cloud in metres, bounding-sphere centres, their radii) of `clouds`, whose particles'
    `radii` are concatenated at `cloud_starts`: a sprite's detail is its texture's texel, a splat's the splat
    itself (a smooth Gaussian)."""
    detail = np.where(styles.sprite_index >= 0, radii * (2.0 / CELL_PIXELS), radii)
    finest = np.array(
        [detail[start:stop].min() if stop > start else 0.0 for start, stop in zip(cloud_starts[:-1], cloud_starts[1:])]
    )
    spheres = [c.bounding_sphere() for c in clouds]
    centres = np.array([s[0] for s in spheres], dtype=np.float64).reshape(-1, 3)
    return finest, centres, np.array([s[1] for s in spheres], dtype=np.float64)


def _concatenated(parts, empty_shape) -> np.ndarray:
    """np.concatenate that also accepts no parts (a scene without clouds)."""
    return np.concatenate(parts) if parts else np.zeros(empty_shape)
