import numpy as np
import pytest

from cloudcore.light.phase import PHASE_NAMES, phase_function
from cloudcore.maths.splat_kernel import splat_kernel


@pytest.mark.parametrize("phase", PHASE_NAMES)
@pytest.mark.parametrize("g", [0.0, 0.5, -0.7, 0.9])
def test_phase_functions_average_to_one_over_the_sphere(phase, g):
    # integrate p(mu) dOmega / 4 pi = 1/2 int p(mu) dmu with many samples
    mu = np.linspace(-1, 1, 400_001)
    mean = 0.5 * np.trapezoid(phase_function(mu, phase, g), mu)
    assert mean == pytest.approx(1.0, rel=1e-6)


def test_harris_forward_values():
    assert phase_function(1.0, "rayleigh") == pytest.approx(1.5)
    assert phase_function(1.0, "henyey-greenstein", 0.9) == pytest.approx(1.9 / 0.01)
    assert phase_function(1.0, "henyey-greenstein", 0.0) == pytest.approx(1.0)


@pytest.mark.parametrize("phase, g", [("mie", 0.0), ("rayleigh", 1.0), ("henyey-greenstein", float("nan"))])
def test_bad_phase_is_refused_with_the_valid_names(phase, g):
    with pytest.raises(ValueError, match="rayleigh|g must"):
        phase_function(0.0, phase, g)


def test_splat_kernel_is_one_at_centre_zero_at_edge_and_decreasing():
    d = np.linspace(0, 1.5, 3001)
    k = splat_kernel(d)
    assert k[0] == 1.0
    assert np.all(k[d >= 1] == 0.0)
    assert np.all(np.diff(k) <= 0)
    assert splat_kernel(0.999999) == pytest.approx(0.0, abs=1e-5)  # no step at the edge
