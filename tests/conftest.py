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
