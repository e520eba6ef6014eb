"""Harris figure 4 written out literally, one particle at a time: the test oracle.

Slow and obviously faithful: visit particles in light order, read the light-plane
value at the centre, blend the splat into every later particle's centre value.
`stable=False` is the paper's recurrence as printed (it creates light where
sigma > alpha); `stable=True` applies the documented cap.
"""

import numpy as np

from cloudcore.light.phase import phase_function
from cloudcore.maths.splat_kernel import splat_kernel


def literal_incident_light(positions, radii, tau, albedo, light_dir, phase="rayleigh", g=0.0, stable=True):
    positions = np.asarray(positions, float)
    n = len(positions)
    radii, tau, albedo = (np.broadcast_to(np.asarray(x, float), (n,)) for x in (radii, tau, albedo))
    light = np.asarray(light_dir, float) / np.linalg.norm(light_dir)
    alpha = 1.0 - np.exp(-tau)
    sigma = albedo * tau * phase_function(1.0, phase, g) / (4 * np.pi)
    if stable:
        sigma = np.minimum(sigma, alpha)
    order = np.argsort(-(positions @ light), kind="stable")
    rank = np.empty(n, int)
    rank[order] = np.arange(n)
    in_plane = positions - np.outer(positions @ light, light)
    value = np.ones(n)
    incident = np.ones(n)
    for j in order:
        incident[j] = value[j]
        if radii[j] == 0:
            continue
        w = splat_kernel(np.linalg.norm(in_plane - in_plane[j], axis=1) / radii[j])
        w = np.where(rank > rank[j], w, 0.0)
        value = sigma[j] * incident[j] * w + (1 - alpha[j] * w) * value
    return incident
