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


def _kernel_diameter_integral(points: int = 64) -> float:
    """The integral of K(|u|) over u in [-1, 1], by Gauss-Legendre on [0, 1] (K is smooth there: exact
    to rounding at 64 points; tests/unit/measure/test_truth.py checks it against the closed form with erf)."""
    nodes, weights = np.polynomial.legendre.leggauss(points)
    return float(np.sum(weights * splat_kernel(0.5 * (nodes + 1.0))))  # 2 * (1/2) * sum over [0, 1]


#: a blob of extinction c K(|x - p| / r) has optical depth c r times this along a diameter (the
#: path-traced truth's particles, `cloudcore.measure.truth`, and Yusov's reference particle,
#: `cloudcore.light.precomputed`)
KERNEL_DIAMETER_INTEGRAL = _kernel_diameter_integral()


def _kernel_volume_integral(points: int = 64) -> float:
    """The integral of K(|u|) over the unit ball, 4 pi times that of K(d) d^2 over d in [0, 1] (Gauss-Legendre
    as `_kernel_diameter_integral`)."""
    nodes, weights = np.polynomial.legendre.leggauss(points)
    d = 0.5 * (nodes + 1.0)
    return float(4.0 * np.pi * 0.5 * np.sum(weights * splat_kernel(d) * d * d))


#: a blob of extinction c K(|x - p| / r) holds c r^3 times this of extinction times volume: what a particle
#: fitted to a density grid (`cloudcore.scenes.interop.density_fit`) carries of the grid's integral
KERNEL_VOLUME_INTEGRAL = _kernel_volume_integral()
