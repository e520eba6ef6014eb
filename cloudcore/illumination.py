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


class IlluminationCache:
    """`illuminate_clouds` that recomputes only clouds it has not seen under the same shading and lights.

    The editor changes one cloud at a time; recomputing the other 33 clouds of
    the default scene would freeze it for seconds.  Clouds are immutable, so a
    cloud object seen before (by identity) has the same particles; entries for
    clouds no longer asked for are dropped.
    """

    def __init__(self):
        self._entries: dict[int, tuple[Cloud, object, np.ndarray]] = {}
        self.last_recomputed = 0  # clouds shaded by the last call

    def incident(self, clouds, shading: Shading, lights, method: str = "exact") -> list[np.ndarray]:
        clouds = list(clouds)
        key = (shading, tuple(active_lights(lights)), method)
        stale = [c for c in clouds if (hit := self._entries.get(id(c))) is None or hit[0] is not c or hit[1] != key]
        for cloud, incident in zip(stale, illuminate_clouds(stale, shading, lights, method)):
            self._entries[id(cloud)] = (cloud, key, incident)
        self._entries = {id(c): self._entries[id(c)] for c in clouds}
        self.last_recomputed = len(stale)
        return [self._entries[id(c)][2] for c in clouds]
