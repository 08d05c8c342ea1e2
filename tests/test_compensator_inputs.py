"""Compensation blocks met by a review of bad inputs: two inverses in one
python-control interconnection keep their own parameters, a compensator
whose simulation overflows says so, a NaN through python-control is
named instead of sticking in a backlash's memory or passing for an
algebraic loop, and an L1 too small to invert is refused."""

import warnings

import numpy as np
import control as ct
import pytest

import sandwichctl as sw

PLANT = sw.examples.paper_plant()


def test_two_inverses_in_one_interconnection_keep_their_parameters():
    i1 = sw.BacklashInverse(1, 1, .5, .5, dt=1, name='i1', outputs='x1')
    i2 = sw.BacklashInverse(3, 3, .1, .1, dt=1, name='i2', outputs='x2')
    both = ct.interconnect([i1, i2], inplist=[['i1.v_d', 'i2.v_d']],
                           outlist=['i1.x1', 'i2.x2'], inputs='v_d',
                           outputs=['x1', 'x2'])
    v_d = [0, 1, 2, 1.5]
    out = ct.input_output_response(both, np.arange(4), v_d).outputs
    for row, inv in zip(out, (i1, i2)):
        np.testing.assert_allclose(row, inv.response(v_d), atol=1e-12)
    assert not np.allclose(out[0], out[1])
    # two compensators side by side: each its own model's
    comps = [sw.sandwich_compensator(p, name=n) for p, n in
             ((PLANT, 'c1'), (PLANT.copy_with(D1=0.05, D2=0.05), 'c2'))]
    r = np.r_[0, np.sin(np.arange(1, 30) / 4)]
    alone = [c.simulate(r).outputs for c in comps]
    pair = ct.interconnect(comps, inplist=[['c1.v_d', 'c2.v_d']],
                           outlist=['c1.u', 'c2.u'], inputs='v_d',
                           outputs=['u1', 'u2'])
    both = ct.input_output_response(pair, np.arange(r.size), r).outputs
    np.testing.assert_allclose(both, alone, atol=1e-9)


def test_a_compensator_that_overflows_says_so():
    m = sw.SandwichSystem.from_coefficients([.1], [1], [.2], [1], 1e-300,
                                            1e-300, .1, .1)
    with pytest.warns(sw.SimulationWarning, match='diverged'):
        sw.sandwich_compensator(m).simulate([0, 1e10, 2])


@pytest.mark.parametrize('system', [sw.Backlash(1, 1, .5, .5, dt=1),
                                    PLANT, sw.backlash_inverse(
                                        sw.Backlash(1, 1, .5, .5, dt=1))])
def test_nan_through_python_control_is_named(system):
    with pytest.raises(ValueError, match='not finite'):
        ct.input_output_response(system, np.arange(4), [0, np.nan, 2, 3])
    # and a finite run after it is what it was
    out = ct.input_output_response(system, np.arange(4), [0, 1, 2, 3])
    assert np.all(np.isfinite(out.outputs))


def test_the_describing_function_of_a_huge_swing_raises_instead_of_hanging():
    F = sw.backlash_nonlinearity(sw.Backlash(1, 1.2, 0.5, 0.6))
    for A in (5e307, 1e308):
        with pytest.raises(ValueError, match='too large'):
            F.describing_function(A)
    wide = sw.backlash_nonlinearity(sw.Backlash(1e200, 2e200, .5, .6))
    with pytest.raises(ValueError, match='too large'):
        wide.describing_function(1e120)
    assert np.isfinite(F.describing_function(3.0))


def test_an_l1_too_small_to_invert_is_refused():
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')     # scipy's, building the model
        tiny = sw.SandwichSystem.from_coefficients(
            [.1], [1e-310], [.2], [1], 1, 1, .1, .1)
    with pytest.raises(ValueError, match='too small to invert'):
        sw.sandwich_compensator(tiny)
