"""Tests of the backlash of eq. (2.2): hand values, invariants, python-control."""

import numpy as np
import control as ct
import pytest
from hypothesis import given, settings, strategies as st

import sandwichctl as sw


def test_hand_values_symmetric():
    # m = 1, D = 0.5: dead band of width 1 around v.
    x = [0.0, 1.0, 2.0, 1.5, 0.0, -1.0, -0.8, 0.3]
    v, zones = sw.backlash_response(x, 1, 1, 0.5, 0.5, return_zones=True)
    np.testing.assert_allclose(
        v, [0.0, 0.5, 1.5, 1.5, 0.5, -0.5, -0.5, -0.2], atol=1e-15)
    np.testing.assert_array_equal(zones, [0, 1, 1, 0, -1, -1, 0, 1])


def test_hand_values_asymmetric():
    # m1 = 2, m2 = 3, D1 = 0.25, D2 = 0.5 from memory (x(-1), v(-1)) = (0, 0)
    x = [1.0, 0.5, 0.0, -1.0]
    v = sw.backlash_response(x, 2, 3, 0.25, 0.5)
    # 1.0 > 0/2 + .25, rising -> 2*(1-.25) = 1.5
    # 0.5 falling, 0.5 < 1.5/3 - .5 = 0? no -> hold 1.5
    # 0.0 falling, 0.0 < 0? no -> hold 1.5
    # -1.0 falling, -1 < 0 -> 3*(-1+.5) = -1.5
    np.testing.assert_allclose(v, [1.5, 1.5, 1.5, -1.5], atol=1e-15)


def test_memory_is_initial_state():
    v = sw.backlash_response([0.2, 0.1], 1, 1, 0.5, 0.5, x_prev=0.0,
                             v_prev=0.4)
    np.testing.assert_allclose(v, [0.4, 0.4])


def test_crossing_point_and_eq22_beyond_it():
    bl = sw.Backlash(1.0, 2.0, 0.5, 0.5)
    assert bl.crossing == pytest.approx(-1.5)     # (1*.5 + 2*.5)/(1 - 2)
    assert sw.Backlash(1, 1, 0.5, 0.5).crossing is None
    # Beyond x* = -1.5 the increase line lies above the decrease line.
    # Eq. (2.2) follows the line of the direction of motion, with jumps.
    x = [-3.0, -4.0, -3.5, -3.6]
    v = bl.response(x)
    # -3 falling: 2*(-3+.5) = -5; -4 falling: -7; -3.5 rising and
    # -3.5 > -7/1 + .5: 1*(-3.5-.5) = -4; -3.6 falling, -3.6 < -4/2-.5:
    # 2*(-3.6+.5) = -6.2.
    np.testing.assert_allclose(v, [-5.0, -7.0, -4.0, -6.2], atol=1e-14)


def _clamp_form(x, m1, m2, D1, D2, v_prev=0.0):
    out = []
    for xk in x:
        v_prev = min(max(v_prev, m1 * (xk - D1)), m2 * (xk + D2))
        out.append(v_prev)
    return np.array(out)


@settings(max_examples=60, deadline=None)
@given(m1=st.floats(0.2, 5), m2=st.floats(0.2, 5), D1=st.floats(0, 2),
       D2=st.floats(0, 2), seed=st.integers(0, 2**31))
def test_band_invariant_and_clamp_form_where_lines_do_not_cross(
        m1, m2, D1, D2, seed):
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.normal(0, 0.5, 300))
    v = sw.backlash_response(x, m1, m2, D1, D2)
    lo, hi = m1 * (x - D1), m2 * (x + D2)
    ok = lo <= hi            # the band is non-empty here
    tol = 1e-9 * (1 + np.abs(v))
    # v(k) lies in the band wherever the band is non-empty, and there
    # eq. (2.2) equals the clamp form as long as no sample has left it.
    assert np.all((v >= lo - tol)[ok]) and np.all((v <= hi + tol)[ok])
    first_bad = np.argmin(ok) if not ok.all() else x.size
    np.testing.assert_allclose(v[:first_bad],
                               _clamp_form(x, m1, m2, D1, D2)[:first_bad],
                               rtol=1e-12, atol=1e-12)


def test_io_system_matches_pure_function(rng):
    x = rng.normal(0, 1, 200)
    bl = sw.Backlash(1.3, 0.8, 0.2, 0.4, dt=0.5, name='bl')
    assert bl.nstates == 2 and bl.dt == 0.5
    resp = ct.input_output_response(bl, 0.5 * np.arange(x.size), x,
                                    initial_state=[0.1, 0.05])
    np.testing.assert_allclose(
        resp.outputs, bl.response(x, x_prev=0.1, v_prev=0.05), atol=1e-15)


def test_two_backlashes_in_one_interconnect_keep_their_parameters(rng):
    # python-control merges the params of interconnected blocks; the
    # backlash parameters must not be shared through them
    x = rng.normal(0, 1, 100)
    a = sw.Backlash(1.0, 1.0, 0.1, 0.1, dt=1, name='a', inputs='x',
                    outputs='va')
    b = sw.Backlash(2.0, 3.0, 0.5, 0.2, dt=1, name='b', inputs='x',
                    outputs='vb')
    both = ct.interconnect([a, b], inplist=['x'], outlist=['va', 'vb'])
    resp = ct.input_output_response(both, np.arange(x.size), x)
    np.testing.assert_allclose(resp.outputs[0], a.response(x), atol=1e-15)
    np.testing.assert_allclose(resp.outputs[1], b.response(x), atol=1e-15)


def test_output_function_is_pure():
    bl = sw.Backlash(1, 1, 0.5, 0.5, dt=1)
    state = np.array([0.0, 0.0])
    first = bl._out(0, state, [2.0])
    for _ in range(5):
        np.testing.assert_array_equal(bl._out(0, state, [2.0]), first)
    np.testing.assert_array_equal(state, [0.0, 0.0])


def test_copy_with_and_repr():
    bl = sw.Backlash(1, 2, 0.1, 0.2)
    bl2 = bl.copy_with(m1=3.0)
    assert (bl2.m1, bl2.m2, bl2.D1, bl2.D2) == (3.0, 2.0, 0.1, 0.2)
    assert 'm1=1' in repr(bl) and 'eq. 2.2' in str(bl)
    with pytest.raises(TypeError, match='unknown backlash parameter'):
        bl.copy_with(m3=1)


@pytest.mark.parametrize('kwargs, match', [
    (dict(m1=0), 'm1 must be a finite number > 0; got 0.0'),
    (dict(m2=-1), 'm2 must be a finite number > 0'),
    (dict(m1=np.inf), 'm1 must be a finite number > 0; got inf'),
    (dict(m2=np.nan), 'm2 must be a finite number > 0'),
    (dict(D1=-0.1), 'D1 must be a finite number >= 0; got -0.1'),
    (dict(D2=np.inf), 'D2 must be a finite number >= 0'),
])
def test_bad_parameters(kwargs, match):
    args = dict(m1=1.0, m2=1.0, D1=0.5, D2=0.5) | kwargs
    with pytest.raises(ValueError, match=match):
        sw.Backlash(**args)
    with pytest.raises(ValueError, match=match):
        sw.backlash_response([0.0, 1.0], **args)


def test_bad_types_and_inputs():
    with pytest.raises(TypeError, match='m1 must be a real number'):
        sw.Backlash('1', 1, 0.5, 0.5)
    with pytest.raises(ValueError, match='dt must be a positive sampling'):
        sw.Backlash(1, 1, 0.5, 0.5, dt=0)
    with pytest.raises(ValueError, match='x must be finite; sample 1 is nan'):
        sw.backlash_response([0.0, np.nan], 1, 1, 0.5, 0.5)
    with pytest.raises(ValueError, match=r'x must be a 1-D array.*\(2, 2\)'):
        sw.backlash_response(np.zeros((2, 2)), 1, 1, 0.5, 0.5)
