"""Multiple scattering in every direction as octaves of the light reaching each particle (Wrenninge et al., "Oz: the
great and volumetric", SIGGRAPH 2013 talk; as Frostbite and Unreal use it: Hillaire 2016, "Physically based sky,
atmosphere and cloud rendering in Frostbite").

Harris's light pass carries on only the light a particle scatters forward, along the light's own direction, and
carries it far: at albedo 0.99 an opaque particle passes on 94.5% of what reaches it (sigma_eff = a tau p(0) /
(4 pi)), so a thick cloud's far side is lit as if it were thin.  In a real cloud the light deep inside has been
scattered many times, from every direction, and fades with depth at a rate set by the albedo (seed 000, section 5:
"running many passes to evenly sample all directions").  Wrenninge's octaves stand in for that light: octave i is
the transmittance T_i toward the light through the particles ahead (Harris's light-plane frame buffer with nothing
scattered on: the product of 1 - alpha K over the splats ahead that cover the particle's centre) with their
optical depths scaled by `EXTINCTION_SCALE`^i (multiply scattered light gets further), weighted by
`SCATTERING_SCALE`^i (each order carries less).  Octave 0 is the direct light; the others count only the light
the direct beam has lost on the way, T_i - T_0:

    I = T_0 + sum_{i >= 1} b^i (T_i(a^i tau) - T_0(tau))

so a particle nothing shadows gets 1, no more than a lone particle can scatter (Frostbite's sum of b^i T_i gives
it 1 + b + b^2 ..., and a slab of sparse opaque particles then sends out more light than reaches it:
tests/unit/light/test_octaves.py),
and the multiply scattered light is dark at a cloud's lit edge, where the direct light has
not yet been scattered, and rises inside: Schneider's "powder" darkening, here from the octaves themselves.  The
scales are the published ones (a = b = 0.5, three octaves), not fitted to this project's pictures.  The third
of Wrenninge's scales, the phase function's anisotropy, is 1 here: every octave keeps the scene's phase
function, so the octaves add into the one incident value per particle and light that the eye pass (numpy and GL)
already reads; the default scenes' Rayleigh phase has no anisotropy to scale.  docs/shading.md ("Octaves")
measures them against the path-traced truth.
"""

from __future__ import annotations

import numpy as np

#: light passes summed: Harris's and its multiple-scattering octaves
OCTAVES = 3
#: a: octave i's particles have optical depth a^i tau
EXTINCTION_SCALE = 0.5
#: b: octave i's light is weighted by b^i
SCATTERING_SCALE = 0.5


def octave_optical_depths(optical_depth: np.ndarray) -> np.ndarray:
    """(N, OCTAVES): each particle's optical depth in each octave, a^i tau."""
    tau = np.asarray(optical_depth, dtype=np.float64)
    return tau[:, None] * EXTINCTION_SCALE ** np.arange(OCTAVES)


def octave_weights() -> np.ndarray:
    """(OCTAVES,): b^i, what each octave's light is weighted by."""
    return SCATTERING_SCALE ** np.arange(OCTAVES)


def octave_light(through: np.ndarray) -> np.ndarray:
    """(N,): the light reaching each particle from its octaves' transmittances `through` (N, OCTAVES), column 0
    the direct light: T_0 + sum_{i >= 1} b^i (T_i - T_0)."""
    weights = octave_weights()
    return through[:, 0] + (through[:, 1:] - through[:, :1]) @ weights[1:]


def most_light() -> float:
    """The most light the octaves give a particle: 1 unshadowed; more only where the octaves' weights after the
    first add up to more than 1 and a particle's direct light is gone but none of its octaves' is."""
    return float(max(1.0, octave_weights()[1:].sum()))
