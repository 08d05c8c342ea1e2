import matplotlib
import numpy as np
import pytest

matplotlib.use('Agg')


@pytest.fixture
def rng():
    """A seeded generator; tests never touch the global numpy seed."""
    return np.random.default_rng(20261121)
