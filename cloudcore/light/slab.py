"""Reflectance and transmittance of a plane-parallel slab of a scattering medium, by adding-doubling: the reference
the shading models are checked against where the answer is known (docs/shading.md, "Optical properties").

The slab is homogeneous, of optical thickness `tau` (vertically), single-scattering albedo `albedo` and phase
function isotropic or Rayleigh (normalised to mean 1 over the sphere, as `cloudcore.light.phase`).  Only the
azimuthal mean of the light matters for fluxes, so the directions are the nodes of a Gauss-Legendre rule in the
cosine mu on each hemisphere ("double Gauss") and the phase function is its azimuthal mean.  The layer's operators
act on fluxes: column j is what a unit of flux arriving along node j (through a horizontal plane) becomes, row i
the flux leaving along node i.  A layer thin enough (tau / 2^DOUBLINGS) has its operators to first order in its
depth, which conserve light exactly where the albedo is 1; a layer twice as thick is two of them, light going back
and forth between them summed as a geometric series (I - R R)^-1 (van de Hulst 1980, "Multiple light
scattering", chapter 5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: the starting layer is tau / 2^DOUBLINGS thick, its operators exact to first order in that depth
DOUBLINGS = 30
#: Gauss nodes per hemisphere: fluxes to 1e-5 (tests/unit/light/test_slab.py)
STREAMS = 16
SLAB_PHASES = ("isotropic", "rayleigh")


@dataclass(frozen=True)
class Slab:
    """A slab's flux operators (STREAMS x STREAMS, one hemisphere's nodes `mu` with weights `weights`, summing
    to 1 over (0, 1)): `reflection` sends flux arriving at the top back up, `transmission` on through it, the
    light that crossed unscattered included.  The slab is symmetric: the same from below."""

    mu: np.ndarray
    weights: np.ndarray
    reflection: np.ndarray
    transmission: np.ndarray

    def plane_albedo(self) -> np.ndarray:
        """(STREAMS,): the share of a beam arriving along each node that the slab sends back."""
        return self.reflection.sum(axis=0)

    def plane_transmittance(self) -> np.ndarray:
        """(STREAMS,): the share of a beam arriving along each node that leaves below, scattered or not."""
        return self.transmission.sum(axis=0)

    def diffuse_flux(self) -> np.ndarray:
        """(STREAMS,): what uniform incident radiance brings in along each node, per unit of its whole flux."""
        return 2.0 * self.weights * self.mu

    def spherical_albedo(self) -> float:
        """The share of uniform (diffuse) incident light sent back."""
        return float(self.plane_albedo() @ self.diffuse_flux())

    def spherical_transmittance(self) -> float:
        """The share of uniform (diffuse) incident light that leaves below."""
        return float(self.plane_transmittance() @ self.diffuse_flux())

    def reflected_radiance(self, beam_node: int) -> np.ndarray:
        """(STREAMS,): the radiance leaving the top along each node per unit irradiance of a beam arriving along
        node `beam_node` (irradiance on a plane across the beam, as a light's)."""
        flux = self.reflection[:, beam_node] * self.mu[beam_node]
        return flux / (2.0 * np.pi * self.weights * self.mu)


def slab(tau: float, albedo: float, phase: str = "isotropic", streams: int = STREAMS) -> Slab:
    """The slab of optical thickness `tau`, single-scattering albedo `albedo` and `phase`."""
    if phase not in SLAB_PHASES:
        raise ValueError(f"unknown slab phase function {phase!r}; valid: {', '.join(SLAB_PHASES)}")
    if not (tau >= 0.0 and np.isfinite(tau)):
        raise ValueError(f"optical thickness must be finite and >= 0, got {tau}")
    if not 0.0 <= albedo <= 1.0:
        raise ValueError(f"albedo must be within [0, 1], got {albedo}")
    nodes, weights = np.polynomial.legendre.leggauss(streams)
    mu, weights = 0.5 * (nodes + 1.0), 0.5 * weights
    reflection, transmission = _thin_layer(tau / 2.0**DOUBLINGS, albedo, mu, weights, phase)
    for _ in range(DOUBLINGS):
        bounced = np.linalg.solve(np.eye(streams) - reflection @ reflection, transmission)
        reflection, transmission = reflection + transmission @ reflection @ bounced, transmission @ bounced
    return Slab(mu, weights, reflection, transmission)


def _azimuthal_phase(mu_out: np.ndarray, mu_in: np.ndarray, phase: str) -> np.ndarray:
    """The phase function's mean over the azimuth between two directions of cosines `mu_out`, `mu_in` (signed:
    the same sign is the same hemisphere)."""
    if phase == "isotropic":
        return np.ones(np.broadcast_shapes(mu_out.shape, mu_in.shape))
    # Rayleigh 3/4 (1 + cos^2): the mean of cos^2 over the azimuth is mu^2 mu'^2 + (1 - mu^2)(1 - mu'^2) / 2
    return 0.75 * (1.0 + mu_out**2 * mu_in**2 + 0.5 * (1.0 - mu_out**2) * (1.0 - mu_in**2))


def _thin_layer(depth: float, albedo: float, mu: np.ndarray, weights: np.ndarray, phase: str):
    """Flux operators of a layer of optical thickness `depth` to first order in it (the infinitesimal
    generator): what it loses along node j, depth / mu_j, it scatters, a share albedo * w_i p / 2 toward node i
    (the mean of p over the sphere is 1), so at albedo 1 every column sums to 1 and doubling keeps it so."""
    out, into = mu[:, None], mu[None, :]
    scattered = albedo * depth * weights[:, None] / (2.0 * into)
    reflection = scattered * _azimuthal_phase(out, -into, phase)
    transmission = scattered * _azimuthal_phase(out, into, phase) + np.diag(1.0 - depth / mu)
    return reflection, transmission
