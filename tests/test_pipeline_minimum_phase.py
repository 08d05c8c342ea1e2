"""``identify(..., minimum_phase='L1')``: L1's zeros kept inside the unit
circle (`Parametrisation.minimum_phase_start` on every start, `stable` on
every step), recorded in the result, and passed on by
`select_structure`; the default search is unchanged."""

import warnings

import numpy as np
import pytest

import sandwichctl as sw
from sandwichctl.identification._options import OEOptions
from sandwichctl.identification._problem import (Parametrisation,
                                                 MINIMUM_PHASE_RADIUS)

ORDERS = dict(na=1, nb=1, nc=1, nd=0, q1=1, q2=0)


def _plant(b1):
    """L1 = (1 + b1 q^-1) q^-1 / (1 - 0.6 q^-1): a zero at -b1."""
    return sw.SandwichSystem.from_coefficients(
        a=[-0.6], b=[1.0, b1], c=[-0.5], d=[1.0], m1=1.0, m2=1.1, D1=0.15,
        D2=0.1, q1=1, q2=0)


def _identified(b1, n, seed, values):
    """Noise-free data of `_plant(b1)` and its identification with each
    of the `values` of minimum_phase: (u, y, [results])."""
    u = sw.examples.paper_input(n, seed=seed)
    y = _plant(b1).simulate(u).outputs
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        return u, y, [sw.identify(u, y, **ORDERS, minimum_phase=value)
                      for value in values]


@pytest.fixture(scope='module')
def nonminimum():
    """Data of a plant whose L1 has its zero at -1.6, outside; the
    unconstrained and the minimum-phase identification."""
    u, y, (free, minph) = _identified(1.6, 2000, 4, (None, 'L1'))
    return _plant(1.6), u, y, free, minph


def test_minimum_phase_start_reflects_and_keeps_the_magnitude():
    """A zero at -2 goes to -0.5; the slopes are doubled and the widths
    halved, so that |L1| m (the gain to v) is kept; zeros inside and the
    default structure are left alone (the same object)."""
    st = Parametrisation((1, 1, 1, 0, 1, 0), minimum_phase='L1')
    phi = np.array([-0.5, -0.6, 1.0, 1.2, 0.2, 0.3, 2.0])
    out = st.minimum_phase_start(phi)
    np.testing.assert_allclose(out, [-0.5, -0.6, 2.0, 2.4, 0.1, 0.15, 0.5])
    assert st.stable(out) and not st.stable(phi)
    inside = phi.copy()
    inside[-1] = 0.5
    assert st.minimum_phase_start(inside) is inside
    plain = Parametrisation((1, 1, 1, 0, 1, 0))
    assert plain.minimum_phase_start(phi) is phi and plain.stable(phi)
    z = np.exp(1j * np.linspace(0, np.pi, 7))         # the unit circle
    np.testing.assert_allclose(np.abs(1 + 2.0 / z),
                               2.0 * np.abs(1 + 0.5 / z))


def test_a_zero_on_the_unit_circle_is_pulled_inside():
    st = Parametrisation((1, 1, 1, 0, 1, 0), minimum_phase='L1')
    phi = np.array([-0.5, -0.6, 1.0, 1.0, 0.2, 0.2, 1.0])   # zero at -1
    out = st.minimum_phase_start(phi)
    assert st.stable(out)
    assert abs(out[-1]) < MINIMUM_PHASE_RADIUS


def test_unconstrained_fit_has_the_zero_outside_and_minimum_phase_not(
        nonminimum):
    plant, u, y, free, minph = nonminimum
    assert np.max(np.abs(free.model.L1.zeros())) > 1.2
    assert free.minimum_phase is None
    zeros = minph.model.L1.zeros()
    assert zeros.size == 1 and np.all(np.abs(zeros) < 1)
    assert minph.minimum_phase == 'L1'
    assert 'L1 kept minimum-phase' in repr(minph)
    assert 'minimum-phase' not in repr(free)
    # the data ask for the zero outside: the constrained one fits worse,
    # ends on the bound, and the message says so
    assert minph.fit < free.fit
    assert abs(zeros[0]) >= 0.99 * MINIMUM_PHASE_RADIUS
    assert 'minimum-phase bound' in minph.message
    assert 'minimum-phase bound' not in free.message


def test_default_and_false_are_the_search_of_before():
    """minimum_phase=False is None: the same model to the last bit."""
    *_, (a, b) = _identified(0.5, 1500, 2, (None, False))
    np.testing.assert_array_equal(a.theta, b.theta)
    assert a.minimum_phase is None and b.minimum_phase is None
    assert OEOptions(minimum_phase=False).minimum_phase is None


@pytest.mark.parametrize('value', [True, 'L2', 'l1', 1])
def test_bad_minimum_phase_is_refused(value):
    with pytest.raises(ValueError, match='minimum_phase'):
        OEOptions(minimum_phase=value)


def test_select_structure_ranks_minimum_phase_sandwiches(nonminimum):
    plant, u, y, *_ = nonminimum
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        table = sw.select_structure((u[:1500], y[:1500]),
                                    orders=[(1, 1, 1, 0)], delays=[(1, 0)],
                                    include_linear=False,
                                    minimum_phase='L1')
    assert table.minimum_phase == 'L1'
    assert 'L1 minimum-phase' in repr(table)
    res = table.best['result']
    assert res.minimum_phase == 'L1'
    assert np.all(np.abs(table.best_model.L1.zeros()) < 1)
