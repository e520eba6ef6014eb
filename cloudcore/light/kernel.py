"""The Gaussian splat kernel K shared by shading (light plane) and rendering (screen).

Harris renders each particle as a billboard of side 2r textured with a Gaussian.
We offset and rescale the Gaussian so that K is exactly 1 at the centre and
exactly 0 at the billboard's inscribed circle, with no step at the edge.
The GLSL side reads SPLAT_SHARPNESS so both agree.
"""

from __future__ import annotations

import numpy as np

#: exp(-SPLAT_SHARPNESS * d^2) with d = distance / radius; 4 puts the 1/e point at d = 0.5.
SPLAT_SHARPNESS = 4.0
_FLOOR = np.exp(-SPLAT_SHARPNESS)
#: a billboard of side 2r reaches r sqrt(2) from its centre at the corners, however it faces: the radius
#: of the sphere that bounds what a splat can cover
SPLAT_REACH = float(np.sqrt(2.0))


def splat_kernel(d) -> np.ndarray:
    """K(d) for d = distance from the centre / radius: 1 at d = 0, 0 for d >= 1."""
    d = np.asarray(d, dtype=np.float64)
    k = (np.exp(-SPLAT_SHARPNESS * d * d) - _FLOOR) / (1.0 - _FLOOR)
    return np.where(d < 1.0, np.maximum(k, 0.0), 0.0)
