"""A float export of a large controller: the balanced realization's
gramians of a block of hundreds of states (a controller with 217 samples
of preview had 675) are solved by the bilinear method, not as a
Kronecker system of n^2 unknowns, which took 24 GB."""

import tracemalloc

import numpy as np

from sandwichctl.design import _export_blocks as eb


def _block(n, seed=0):
    """A stable random SISO block of n states."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A *= 0.9 / np.max(np.abs(np.linalg.eigvals(A)))
    return eb.Block('t', 'test', n, A, rng.standard_normal(n),
                    rng.standard_normal(n), 0.1)


def test_a_large_block_is_balanced_in_little_memory():
    n = 150                          # directly: 22,500^2 doubles, 4 GB
    block = _block(n)
    tracemalloc.start()
    balanced = block._balanced()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 50e6
    assert balanced is not None and balanced.n <= n
    u = eb._probe()[:300]
    np.testing.assert_allclose(balanced._response(u, np.float64),
                               block._response(u, np.float64),
                               atol=1e-8 * np.max(np.abs(
                                   block._response(u, np.float64))))


def test_small_blocks_are_solved_as_before():
    # up to DIRECT_MOST states the gramians are solved directly, so the
    # exports of the usual controllers are unchanged
    assert eb.DIRECT_MOST >= 30
    small = _block(12, seed=1)
    assert small.for_float() is not None
