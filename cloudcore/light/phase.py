"""Phase functions, normalised as in Harris (2002): their mean over the sphere is 1.

So an isotropic phase function is 1 everywhere, Rayleigh is 0.75 (1 + cos^2)
with p(0) = 1.5, and a strongly forward Henyey-Greenstein lobe has p(0) in the
hundreds, (1 + g) / (1 - g)^2.  `cos_theta` is the cosine of the scattering
angle: 1 means straight on (forward), -1 back toward the light.
"""

from __future__ import annotations

import numpy as np

PHASE_NAMES = ("rayleigh", "henyey-greenstein", "cornette-shanks")

#: |g| must stay below 1: at g = +-1 Henyey-Greenstein is a Dirac delta.
MAX_ABS_G = 0.999


def check_phase(phase: str, g: float) -> None:
    """Raise ValueError naming the valid choices for an unknown phase or g out of range."""
    if phase not in PHASE_NAMES:
        raise ValueError(f"unknown phase function {phase!r}; valid: {', '.join(PHASE_NAMES)}")
    if not np.isfinite(g) or abs(g) > MAX_ABS_G:
        raise ValueError(f"phase asymmetry g must be finite and within [-{MAX_ABS_G}, {MAX_ABS_G}], got {g}")


def phase_function(cos_theta, phase: str = "rayleigh", g: float = 0.0) -> np.ndarray:
    """Evaluate the phase function (mean 1 over the sphere) at `cos_theta`, float64."""
    check_phase(phase, g)
    mu = np.clip(np.asarray(cos_theta, dtype=np.float64), -1.0, 1.0)
    if phase == "rayleigh":
        return 0.75 * (1.0 + mu * mu)
    # 1 + g^2 - 2 g mu >= (1 - |g|)^2 > 0 for |g| < 1, so the power is finite.
    lobe = (1.0 - g * g) / (1.0 + g * g - 2.0 * g * mu) ** 1.5
    if phase == "henyey-greenstein":
        return lobe
    return 1.5 * (1.0 + mu * mu) / (2.0 + g * g) * lobe  # Cornette-Shanks (1992)
