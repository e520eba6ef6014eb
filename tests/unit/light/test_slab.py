"""The adding-doubling slab (`cloudcore.light.slab`) against what is known of plane-parallel slabs."""

import numpy as np
import pytest

from cloudcore.light.slab import slab


@pytest.mark.parametrize("phase", ["isotropic", "rayleigh"])
@pytest.mark.parametrize("tau", [0.5, 8.0, 64.0])
def test_a_conservative_slab_sends_back_or_on_all_the_light(phase, tau):
    layer = slab(tau, 1.0, phase)
    np.testing.assert_allclose(layer.plane_albedo() + layer.plane_transmittance(), 1.0, atol=1e-6)


@pytest.mark.parametrize("tau", [16.0, 64.0, 512.0])
def test_a_thick_conservative_slab_transmits_as_van_de_hulst_says(tau):
    # van de Hulst 1980, chapter 14: the spherical transmittance of a thick conservative layer, isotropic
    # scattering, is 4 / (3 tau + 6 q0) with the extrapolation length q0 = 0.7104, up to terms exponentially small
    layer = slab(tau, 1.0, "isotropic")
    assert layer.spherical_transmittance() == pytest.approx(4.0 / (3.0 * tau + 6.0 * 0.7104), rel=1e-3)


def test_a_thin_slab_scatters_once():
    # a beam along mu0 meets tau / mu0 of extinction; isotropic scattering sends half of it back up (away from
    # grazing beams, for which the slab is not thin)
    tau = 1e-5
    layer = slab(tau, 1.0, "isotropic")
    steep = layer.mu > 0.3
    np.testing.assert_allclose(layer.plane_albedo()[steep], tau / (2.0 * layer.mu[steep]), rtol=1e-3)


def test_a_thin_slab_sends_rayleigh_light_back_as_its_phase_function_says():
    # single scattering back toward mu from a beam along mu0, its radiance per unit irradiance across the beam:
    # albedo tau p / (4 pi mu) (the view ray's path through the slab), p the azimuthal mean of 3/4 (1 + cos^2)
    tau = 1e-5
    layer = slab(tau, 1.0, "rayleigh")
    node = len(layer.mu) - 1
    mu = layer.mu[node]
    p = 0.75 * (1.0 + mu**4 + 0.5 * (1.0 - mu**2) ** 2)
    assert layer.reflected_radiance(node)[node] == pytest.approx(tau * p / (4.0 * np.pi * mu), rel=1e-3)


@pytest.mark.parametrize("albedo", [0.9, 0.99, 0.999])
def test_a_semi_infinite_absorbing_slab_reflects_near_the_two_stream_value(albedo):
    # the two-stream spherical albedo (1 - s) / (1 + s), s = sqrt(1 - a), is an approximation: within 10%,
    # and closer the nearer a is to 1, where both tend to 1 - 4 s / sqrt(3) (van de Hulst, chapter 9)
    layer = slab(4096.0, albedo, "isotropic")
    s = np.sqrt(1.0 - albedo)
    assert layer.spherical_albedo() == pytest.approx((1.0 - s) / (1.0 + s), rel=0.1)
    assert layer.spherical_albedo() < 1.0
    if albedo == 0.999:
        assert layer.spherical_albedo() == pytest.approx(1.0 - 4.0 * s / np.sqrt(3.0), abs=5e-3)


def test_absorption_darkens_a_slab():
    reflected = [slab(32.0, albedo, "rayleigh").spherical_albedo() for albedo in (1.0, 0.999, 0.99, 0.9)]
    assert np.all(np.diff(reflected) < 0)


def test_bad_slabs_are_refused():
    with pytest.raises(ValueError, match="phase"):
        slab(1.0, 1.0, "henyey-greenstein")
    with pytest.raises(ValueError, match="albedo"):
        slab(1.0, 1.5)
    with pytest.raises(ValueError, match="optical thickness"):
        slab(np.inf, 1.0)
