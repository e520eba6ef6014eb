"""Precomputed illumination of a scene's clouds: incident light per particle and light.

Harris shades each cloud on its own (clouds do not shadow each other) once per
light; this module maps a scene's clouds, shading defaults and lights onto
`cloudcore.shading.incident_light`.
"""

from __future__ import annotations

import numpy as np

from cloudcore.lighting import active_lights
from cloudcore.scene import Cloud, Shading
from cloudcore.shading import DEFAULT_RASTER_RESOLUTION, incident_light


def cloud_optics(cloud: Cloud, shading: Shading) -> tuple[np.ndarray, np.ndarray]:
    """Per-particle optical depth and albedo: the cloud's override or the scene default."""
    n = len(cloud.particles)
    tau = shading.optical_depth if cloud.optical_depth is None else cloud.optical_depth
    albedo = shading.albedo if cloud.albedo is None else cloud.albedo
    return np.full(n, tau), np.full(n, albedo)


def illuminate_clouds(clouds, shading: Shading, lights, method: str = "exact", *,
                      resolution: int = DEFAULT_RASTER_RESOLUTION) -> list[np.ndarray]:
    """Incident light (N_i, L) of each cloud for each light that contributes (`active_lights`).

    All clouds go through one `incident_light` call per light, each its own
    shadowing group, which lets the raster method share its slab walk.
    """
    clouds = list(clouds)
    lights = active_lights(lights)
    counts = [len(c.particles) for c in clouds]
    if not clouds or sum(counts) == 0:
        return [np.zeros((n, len(lights))) for n in counts]
    optics = [cloud_optics(c, shading) for c in clouds]
    positions = np.concatenate([c.centres for c in clouds])
    radii = np.concatenate([c.radii for c in clouds])
    tau = np.concatenate([o[0] for o in optics])
    albedo = np.concatenate([o[1] for o in optics])
    groups = np.repeat(np.arange(len(clouds)), counts)
    columns = [
        incident_light(positions, radii, tau, albedo, light.direction,
                       phase=shading.phase, g=shading.g, method=method, groups=groups,
                       resolution=resolution)
        for light in lights
    ]
    incident = np.stack(columns, axis=1) if columns else np.zeros((len(positions), 0))
    return np.split(incident, np.cumsum(counts)[:-1])
