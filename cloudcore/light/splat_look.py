"""How a splat is shaded across its pixels: one colour a particle (Harris), or each pixel by the view ray's chord
through the particle's sphere (Yusov 2014, section 5.4), and the 3D noise that varies its optical depth below a
particle (Yusov's small details).  The numpy reference of what `splat.frag.glsl` does per pixel.

Per particle, a splat is the colour the eye pass gave its particle, its opacity that colour's times the kernel
K(d) of `cloudcore.maths.splat_kernel` at the pixel's distance d from its centre.

Per pixel, the particle is what the path-traced truth has (`cloudcore.measure.truth`): a sphere of extinction
c K(|x - p| / r).  The pixel's view ray crosses it along a chord; its optical depth there is c r times
`kernel_chord_integral(b^2)`, b the chord's distance from the centre.  The particle's own optical depth across
its diameter, tau = -ln(1 - alpha) from the opacity alpha it has per particle, fixes c r; so the pixel's opacity is
1 - (1 - alpha)^(chord / diameter), alpha itself on a ray through the centre (`chord_opacity`).

The light that the light pass gave the particle, the sun's part of it, is varied by the depth into the particle
toward the sun from the chord's middle m (its point nearest the centre, where the kernel is largest): times
exp(-tau' (D(m) - D(0)) / diameter), D the kernel's integral from m to the sphere's surface along the sun
(`kernel_ray_integral`), 1 at the centre (`sun_light_factor`): a ray through the centre sees the particle's colour
per particle, a chord nearer the sun's side more light, one on the far side less (and near the rim, where the light
crosses little of the particle, more on either side).  tau' is not tau but tau sqrt(3 (1 - a)), a the albedo
(`inner_light_depth`): in a thick particle the sun's light is scattered many times, and the diffusion
approximation's light falls by that exponent; by tau itself, the default scene's opaque particles (tau 8) were 55
times brighter on their lit rims than at their centres.  The rest of the colour (the ambient light, the other
lights, the light a lit face sent back from every direction) has no direction: it follows the opacity.  Yusov
reads the light inside the particle from his 4D tables of the reference particle; this project keeps only their
eye-pass profiles per particle (`cloudcore.light.precomputed`), so the depth toward the sun stands in.

The detail noise multiplies a pixel's optical depth by 1 + a (2 n - 1), n in [0, 1] two octaves of value noise
at the chord's middle in the particle's own frame (metres from its centre over the noise's scale, offset by the
particle's index): it stays on the particle, and so on its cloud, as the eye moves and impostors are made again.
The noise is hashed from its lattice points in the fragment shader (an integer hash, the same on every GL): on
llvmpipe a tiled 3D texture of lattice values, read with the GL's trilinear filter, cost more (docs/performance.md,
"Per-pixel shading and detail noise").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.maths.splat_kernel import KERNEL_DIAMETER_INTEGRAL, kernel_chord_integral, kernel_ray_integral
from cloudcore.model.settings import RenderSettings

#: the opacity a pixel's optical depth is taken from at most: an opaque particle's tau would be infinite
MAX_OPACITY = 1.0 - 1e-6
#: the settings that make the look (`SplatLook.of`): what `cloudview truth` takes for its models
LOOK_SETTINGS = ("particle_shading", "detail_noise", "detail_noise_scale_m")


@dataclass(frozen=True)
class SplatLook:
    """What the splats' raster does per pixel (`RenderSettings.particle_shading`, `detail_noise`,
    `detail_noise_scale_m`)."""

    per_pixel: bool = False
    detail_noise: float = 0.0
    detail_noise_scale_m: float = 20.0

    @classmethod
    def of(cls, settings: RenderSettings) -> SplatLook:
        return cls(settings.particle_shading == "per_pixel", settings.detail_noise, settings.detail_noise_scale_m)

    @property
    def plain(self) -> bool:
        """Whether splats are one colour times the kernel, as ever: the picture of before, and what a compute
        pass can composite."""
        return not self.per_pixel and self.detail_noise == 0.0

    @property
    def key(self) -> tuple:
        """What a cloud's impostor and ring panels go stale by: () for the plain look, as before."""
        return () if self.plain else (self.per_pixel, self.detail_noise, self.detail_noise_scale_m)


def inner_light_depth(optical_depth, albedo) -> np.ndarray:
    """The optical depth across a particle's diameter by which the sun's light falls inside it: its own times
    sqrt(3 (1 - albedo)), the diffusion approximation's attenuation of light scattered many times."""
    albedo = np.clip(np.asarray(albedo, dtype=np.float64), 0.0, 1.0)
    return np.asarray(optical_depth, dtype=np.float64) * np.sqrt(3.0 * (1.0 - albedo))


def own_optical_depth(opacity) -> np.ndarray:
    """A particle's optical depth across its diameter from its opacity per particle."""
    return -np.log1p(-np.minimum(np.asarray(opacity, dtype=np.float64), MAX_OPACITY))


def chord_opacity(opacity, b2) -> np.ndarray:
    """A pixel's opacity per pixel, its view ray at squared distance `b2` (radii squared) from the centre of a
    particle of `opacity` on a ray through its centre."""
    share = kernel_chord_integral(b2) / KERNEL_DIAMETER_INTEGRAL
    return -np.expm1(-share * own_optical_depth(opacity))


def sun_light_factor(middle, toward_sun, light_depth) -> np.ndarray:
    """What multiplies the sun's part of a particle's colour at a pixel whose chord's middle is `middle` (..., 3),
    in radii from the centre: the light's attenuation inside the particle (`light_depth` across its diameter,
    `inner_light_depth`) from its surface toward the sun to there, over that to the centre."""
    depth = kernel_ray_integral(middle, toward_sun) - kernel_ray_integral(np.zeros(3), toward_sun)
    return np.exp(-np.asarray(light_depth, dtype=np.float64) * depth / KERNEL_DIAMETER_INTEGRAL)
