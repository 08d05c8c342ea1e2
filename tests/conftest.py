import matplotlib
import numpy as np
import pytest

matplotlib.use('Agg')


@pytest.fixture
def rng():
    """A seeded generator; tests never touch the global numpy seed."""
    return np.random.default_rng(20261121)


def paper_data(n, seed, snr=None, plant=None, scale=1.0):
    """(plant, u, y): the paper's plant (or `plant`) driven by the paper's
    input of n samples, with noise at `snr` (seeded)."""
    import sandwichctl as sw
    plant = plant or sw.examples.paper_plant()
    u = scale * sw.examples.paper_input(n, seed=seed)
    y = plant.simulate(u).outputs
    if snr is not None:
        y = sw.examples.add_noise(y, snr, seed=seed + 1000)
    return plant, u, y


@pytest.fixture(scope='session')
def lagged_fit():
    """(P, lin): a plant with two lags and the first-order output-error
    fit of 4,000 samples of it (dt = 1 ms, seeded): the model misses a
    lag, which the fit's residuals measure."""
    import control as ct
    import sandwichctl as sw
    rng = np.random.default_rng(0)
    P = ct.tf([0.05], [1, -0.95], 1e-3) * ct.tf([0.5], [1, -0.5], 1e-3)
    u = np.repeat(rng.standard_normal(200), 20) + 0.3 * rng.standard_normal(
        4000)
    y = ct.forced_response(P, U=u).outputs + 1e-3 * rng.standard_normal(4000)
    return P, sw.identify_linear(u, y, nb=1, nf=1, nk=1, dt=1e-3)
