"""The light a cloud's lit face sends back: what the medium behind a particle (away from the light) reflects up
to it, for the octaves light pass (`cloudcore.light.octaves`).

A light pass carried along the light's direction gives a particle only light coming from the light's side.  In a
thick, nearly white medium most of the light that enters the lit face comes back out of it, from every direction:
the particles near the lit face are lit from behind as well as from the front.  Here the medium behind a particle
is taken as a plane-parallel slab of the optical thickness the light pass finds behind it (the product of
1 - alpha K over the splats behind that cover its centre, as the octaves' transmittances ahead), which reflects
the share `R`, its spherical albedo (`cloudcore.light.slab`: light arriving from every direction, the direct beam
and the octaves), of the light that reaches the particle.  Sent back isotropically over the hemisphere, that flux
is a fluence of twice itself (a hemisphere of radiance L carries the flux pi L and the fluence 2 pi L), so a
particle gets

    I (1 + 2 R(tau_behind, albedo))

where I is its light from the octaves.  A particle at the far side of a cloud (nothing behind it) gets nothing
more; one on a thick cloud's lit face at most three times its light, at albedo 1.  The eye pass scatters it with
the scene's phase function, as the rest of the particle's light.  docs/shading.md ("The light a lit face sends
back") measures it against the path-traced truth.

Phase functions other than Rayleigh have their slab by the similarity relations (van de Hulst 1980, section
14.3): an isotropic medium of albedo a (1 - g) / (1 - a g) and optical thickness tau (1 - a g).
"""

from __future__ import annotations

import functools

import numpy as np

from cloudcore.light.slab import slab

#: the slabs' optical thicknesses the reflectance is tabulated at (interpolated in log(1 + tau)); beyond the
#: last, the slab is as good as semi-infinite (its spherical albedo within 1e-4 of the limit at albedo 1)
TABLE_DEPTHS = np.concatenate([[0.0], np.logspace(-3.0, 4.0, 57)])
#: the most the lit face adds to a particle's light, per unit of it: 2 R, R <= 1
MOST_RETURN = 2.0


def lit_face_return(depth_behind, albedo, phase: str = "rayleigh", g: float = 0.0) -> np.ndarray:
    """(N,): 2 R, the fluence the medium behind each particle (optical thickness `depth_behind` (N,) away from
    the light, albedo `albedo` (N,) or a scalar) sends back to it, per unit of the light reaching it."""
    depth = np.asarray(depth_behind, dtype=np.float64)
    albedo = np.broadcast_to(np.asarray(albedo, dtype=np.float64), depth.shape)
    slab_phase, asymmetry = ("rayleigh", 0.0) if phase == "rayleigh" else ("isotropic", float(g))
    reflectance = np.zeros(depth.shape)
    for value in np.unique(albedo):
        chosen = albedo == value
        # the similarity relations: 1 - value * asymmetry >= 1 - 0.999 (check_phase bounds |g|)
        shrink = 1.0 - value * asymmetry
        table = _spherical_albedos(float(value * (1.0 - asymmetry) / shrink), slab_phase)
        scaled = np.log1p(np.clip(depth[chosen] * shrink, 0.0, TABLE_DEPTHS[-1]))
        reflectance[chosen] = np.interp(scaled, np.log1p(TABLE_DEPTHS), table)
    return MOST_RETURN * reflectance


@functools.lru_cache(maxsize=64)
def _spherical_albedos(albedo: float, phase: str) -> np.ndarray:
    """The spherical albedo of the slab at each of `TABLE_DEPTHS` (made once an albedo and phase)."""
    return np.array([slab(float(depth), albedo, phase).spherical_albedo() for depth in TABLE_DEPTHS])
