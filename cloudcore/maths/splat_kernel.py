"""The Gaussian splat kernel K shared by shading (light plane) and rendering (screen).

Harris renders each particle as a billboard of side 2r textured with a Gaussian.
We offset and rescale the Gaussian so that K is exactly 1 at the centre and
exactly 0 at the billboard's inscribed circle, with no step at the edge.
The GLSL side reads SPLAT_SHARPNESS so both agree.
"""

from __future__ import annotations

import math

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


def _erf(x) -> np.ndarray:
    return np.vectorize(math.erf, otypes=[np.float64])(x)


def kernel_ray_integral(start, direction) -> np.ndarray:
    """The integral of K(|start + u direction|) over u from 0 to where the ray leaves the unit sphere, for `start`
    (..., 3) inside it (in radii) and unit `direction` (..., 3): the optical depth, in units of c r, of a blob of
    extinction c K(|x - p| / r) from a point inside it to its surface.  Closed form: with q the ray's closest
    approach to the centre and t its parameter there, K's Gaussian part integrates to erf differences; its floor
    e^-s, constant, to the length.  The per-pixel eye pass's light toward the sun (`cloudcore.light.splat_look`)."""
    start, direction = np.asarray(start, dtype=np.float64), np.asarray(direction, dtype=np.float64)
    along = np.sum(start * direction, axis=-1)  # the closest approach is at u = -along
    q2 = np.clip(np.sum(start * start, axis=-1) - along * along, 0.0, 1.0)
    half_chord = np.sqrt(1.0 - q2)  # the exit is at u = half_chord - along
    root = math.sqrt(SPLAT_SHARPNESS)
    gaussian = 0.5 * math.sqrt(math.pi) / root * np.exp(-SPLAT_SHARPNESS * q2)
    gaussian = gaussian * (_erf(root * half_chord) - _erf(root * along))
    return np.maximum((gaussian - (half_chord - along) * _FLOOR) / (1.0 - _FLOOR), 0.0)


def kernel_chord_integral(b2) -> np.ndarray:
    """The integral of K along the whole chord of the unit sphere at squared distance `b2` from its centre (in
    radii squared): a blob's optical depth along a view ray, in units of c r; `KERNEL_DIAMETER_INTEGRAL` at 0, 0 at
    1 and beyond."""
    b2 = np.clip(np.asarray(b2, dtype=np.float64), 0.0, 1.0)
    entry = np.stack([np.sqrt(b2), np.zeros_like(b2), -np.sqrt(1.0 - b2)], axis=-1)
    return kernel_ray_integral(entry, np.array([0.0, 0.0, 1.0]))
