"""SandwichSystem.simulate_batch: many signals / parameter sets at once."""

import numba
import numpy as np
import pytest

import sandwichctl as sw
from sandwichctl import SimulationWarning

PLANT = sw.examples.paper_plant()


def _loop(plant, U, x0=None):
    return np.stack([plant.simulate(u, initial_state=x0).outputs for u in U])


@pytest.fixture
def U():
    return np.stack([sw.examples.paper_input(300, seed=s) for s in range(5)])


def test_batch_equals_loop_of_simulate_bit_for_bit(U):
    np.testing.assert_array_equal(PLANT.simulate_batch(U), _loop(PLANT, U))


def test_batch_with_initial_state(U, rng):
    x0 = rng.normal(0, 1, PLANT.nstates)
    np.testing.assert_array_equal(PLANT.simulate_batch(U, initial_state=x0),
                                  _loop(PLANT, U, x0))


@pytest.mark.parametrize('orders', [
    dict(na=0, nb=0, nc=0, nd=0, q1=0, q2=0),
    dict(na=3, nb=1, nc=1, nd=2, q1=1, q2=0),      # small kernel (<= 4)
    dict(na=2, nb=2, nc=3, nd=1, q1=3, q2=2)])     # array loop (> 4)
def test_thetas_equal_from_theta_then_simulate(orders, rng):
    U = rng.normal(0, 1, (3, 80))
    o = {k: orders[k] for k in ('na', 'nb', 'nc', 'nd')}
    base = sw.SandwichSystem.from_coefficients(
        a=rng.uniform(-0.3, 0.3, o['na']), b=rng.uniform(0.5, 1, o['nb'] + 1),
        c=rng.uniform(-0.3, 0.3, o['nc']), d=rng.uniform(0.5, 1, o['nd'] + 1),
        m1=1, m2=1.2, D1=0.2, D2=0.3, q1=orders['q1'], q2=orders['q2'])
    thetas = base.theta * rng.uniform(0.9, 1.1, (3, base.theta.size))
    Y = base.simulate_batch(U, thetas)
    for th, u, y in zip(thetas, U, Y):
        ref = sw.SandwichSystem.from_theta(th, **base.orders, dt=base.dt)
        np.testing.assert_allclose(y, ref.simulate(u).outputs, rtol=0,
                                   atol=1e-12)


def test_negative_gain_theta_uses_the_gain_sign(rng):
    plant = sw.SandwichSystem.from_coefficients(
        a=[0.1], b=[-1.5], c=[0.2], d=[2.0], m1=1, m2=1, D1=0.2, D2=0.2)
    u = rng.normal(0, 1, 60)
    y = plant.simulate_batch(u, plant.theta)[0]
    np.testing.assert_allclose(y, plant.simulate(u).outputs, atol=1e-12)


def test_shapes_and_broadcasting(U):
    assert PLANT.simulate_batch(U[0]).shape == (1, 300)
    thetas = np.stack([PLANT.theta] * 4)
    assert PLANT.simulate_batch(U[0], thetas).shape == (4, 300)
    assert PLANT.simulate_batch(U[:4], thetas).shape == (4, 300)
    assert PLANT.simulate_batch(U, PLANT.theta).shape == (5, 300)
    np.testing.assert_allclose(PLANT.simulate_batch(U, PLANT.theta),
                               _loop(PLANT, U), atol=1e-12)


def test_one_thread_gives_identical_results(U):
    big = np.tile(U, (4, 1))
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = PLANT.simulate_batch(big)
    finally:
        numba.set_num_threads(threads)
    np.testing.assert_array_equal(one, PLANT.simulate_batch(big))


@pytest.mark.parametrize('call, exc, match', [
    (lambda: PLANT.simulate_batch('u'), TypeError, 'inputs'),
    (lambda: PLANT.simulate_batch([[1.0, np.nan]]), ValueError,
     r'inputs\[0\]'),
    (lambda: PLANT.simulate_batch(np.ones((2, 2, 2))), ValueError, 'inputs'),
    (lambda: PLANT.simulate_batch([[1.0, 2.0], [1.0]]), ValueError,
     'inputs'),
    (lambda: PLANT.simulate_batch(np.ones((0, 3))), ValueError, 'inputs'),
    (lambda: PLANT.simulate_batch(np.ones(3), np.ones((2, 4))), ValueError,
     r'thetas\[0\]'),
    (lambda: PLANT.simulate_batch(np.ones(3), [['a'] * 9]), TypeError,
     'thetas'),
    (lambda: PLANT.simulate_batch(np.ones(3), -PLANT.theta), ValueError,
     r'thetas\[0\] \(m1\)'),
    (lambda: PLANT.simulate_batch(np.ones((3, 5)), [PLANT.theta] * 2),
     ValueError, 'inputs has 3 signals but thetas 2'),
    (lambda: PLANT.simulate_batch(np.ones(3), PLANT.theta,
                                  initial_state=np.ones(6)), ValueError,
     'initial_state'),
    (lambda: PLANT.simulate_batch(np.ones(3), initial_state=np.ones(2)),
     ValueError, 'initial_state'),
])
def test_bad_input(call, exc, match):
    with pytest.raises(exc, match=match):
        call()


def test_divergence_warns():
    unstable = sw.SandwichSystem.from_coefficients(
        a=[-3.0], b=[1.0], c=[], d=[1.0], m1=1, m2=1, D1=0, D2=0)
    with pytest.warns(SimulationWarning, match=r'rows \[1\]'):
        unstable.simulate_batch(np.stack([np.zeros(900), np.ones(900)]))
