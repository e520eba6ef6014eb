"""Rays and the planet, in the spherically symmetric terms every table uses: a point at distance `r` from
the planet's centre and a direction whose cosine with the local up is `mu` (Bruneton 2017's notation).

Square roots take max(0, .) first, so a ray grazing a sphere (a discriminant rounding below 0) gives its
tangent distance, never NaN.
"""

from __future__ import annotations

import numpy as np


def _discriminant(r, mu, radius) -> np.ndarray:
    r, mu = np.asarray(r, dtype=np.float64), np.asarray(mu, dtype=np.float64)
    return r * r * (mu * mu - 1.0) + radius * radius


def distance_to_top(r, mu, top_radius: float) -> np.ndarray:
    """How far a ray from inside the sphere of `top_radius` travels before it leaves it (0 from outside, rising)."""
    return np.maximum(-np.asarray(r) * mu + np.sqrt(np.maximum(_discriminant(r, mu, top_radius), 0.0)), 0.0)


def ray_hits_ground(r, mu, bottom_radius: float) -> np.ndarray:
    """Whether a ray from above the ground meets the sphere of `bottom_radius`: it points below the horizon."""
    return (np.asarray(mu) < 0.0) & (_discriminant(r, mu, bottom_radius) >= 0.0)


def distance_to_ground(r, mu, bottom_radius: float) -> np.ndarray:
    """How far a ray travels to the ground where it meets it (`ray_hits_ground`), else inf."""
    near = -np.asarray(r) * mu - np.sqrt(np.maximum(_discriminant(r, mu, bottom_radius), 0.0))
    return np.where(ray_hits_ground(r, mu, bottom_radius), np.maximum(near, 0.0), np.inf)


def distance_to_boundary(r, mu, bottom_radius: float, top_radius: float) -> np.ndarray:
    """How far a ray travels in the atmosphere: to the ground where it meets it, else to the top."""
    return np.minimum(distance_to_ground(r, mu, bottom_radius), distance_to_top(r, mu, top_radius))


def horizon_cosine(r, bottom_radius: float) -> np.ndarray:
    """The cosine to the local up of the ray grazing the ground from radius `r` (0 on the ground, below 0 above)."""
    r = np.maximum(np.asarray(r, dtype=np.float64), bottom_radius)
    return -np.sqrt(np.maximum(1.0 - (bottom_radius / r) ** 2, 0.0))


def radius_along(r, mu, t) -> np.ndarray:
    """The distance from the centre of the point `t` along the ray (law of cosines)."""
    r, mu, t = (np.asarray(v, dtype=np.float64) for v in (r, mu, t))
    return np.sqrt(np.maximum(t * t + 2.0 * r * mu * t + r * r, 0.0))


def sun_cosine_along(r, mu_s, nu, t, radius_there) -> np.ndarray:
    """The cosine of the sun to the up at the point `t` along a ray whose cosine with the sun is `nu`."""
    return np.clip((np.asarray(r) * mu_s + t * np.asarray(nu)) / np.maximum(radius_there, 1.0), -1.0, 1.0)
