"""Tests of SandwichSystem: eqs. (2.1)-(2.5), the fast kernel, python-control."""

import copy

import numpy as np
import control as ct
import pytest
from hypothesis import given, settings, strategies as st, HealthCheck

import sandwichctl as sw


def _reference(u, a, b, q1, c, d, q2, m1, m2, D1, D2):
    """Eqs. (2.1)-(2.2) transcribed literally, as a test oracle."""
    n = len(u)
    x, v, y = np.zeros(n), np.zeros(n), np.zeros(n)
    past = lambda s, k: s[k] if k >= 0 else 0.0
    for k in range(n):
        x[k] = (-sum(ai * past(x, k - i) for i, ai in enumerate(a, 1))
                + sum(bj * past(u, k - q1 - j) for j, bj in enumerate(b)))
        xp, vp = past(x, k - 1), past(v, k - 1)
        if x[k] > vp / m1 + D1 and x[k] > xp:
            v[k] = m1 * (x[k] - D1)
        elif x[k] < vp / m2 - D2 and x[k] < xp:
            v[k] = m2 * (x[k] + D2)
        else:
            v[k] = vp
        y[k] = (-sum(ci * past(y, k - i) for i, ci in enumerate(c, 1))
                + sum(dj * past(v, k - q2 - j) for j, dj in enumerate(d)))
    return y, x, v


def test_paper_example_hand_values():
    plant = sw.examples.paper_plant()
    resp = plant.simulate([1.0, 1.0, 1.0, 1.0, 1.0, -1.0, -1.0],
                          internal=True)
    y, x, v = resp.outputs
    # x(k) = -0.1x(k-1) - 0.2x(k-2) + 1.5u(k-1), by hand:
    np.testing.assert_allclose(
        x, [0, 1.5, 1.35, 1.065, 1.1235, 1.17465, -1.842165], atol=1e-12)
    # backlash m1=1, m2=1.2, D1=.5, D2=.6: rises to 1.5-.5 = 1, then holds
    # until x falls below 1/1.2 - .6; at k=6, v = 1.2*(x + .6).
    np.testing.assert_allclose(
        v, [0, 1, 1, 1, 1, 1, 1.2 * (-1.842165 + 0.6)], atol=1e-12)
    # y(k) = -1.2y(k-1) - 0.32y(k-2) + 2v(k-1) - 0.1v(k-2)
    np.testing.assert_allclose(
        y[:5], [0, 0, 2.0, -0.5, 1.86], atol=1e-12)
    y_ref, x_ref, v_ref = _reference([1.0] * 5 + [-1.0] * 2, [0.1, 0.2], [1.5], 1,
                                     [1.2, 0.32], [2, -0.1], 1,
                                     1, 1.2, 0.5, 0.6)
    np.testing.assert_allclose(y, y_ref, atol=1e-12)


def test_paper_example_matches_python_control(rng):
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(1500, seed=3)
    fast = plant.simulate(u)
    slow = ct.input_output_response(plant, np.arange(u.size), u)
    np.testing.assert_allclose(fast.outputs, slow.outputs, rtol=0,
                               atol=1e-10)


def _stable_poly(rng, n, radius=0.95):
    roots = []
    while len(roots) < n:
        if n - len(roots) >= 2 and rng.random() < 0.5:
            r, phi = radius * rng.random(), np.pi * rng.random()
            roots += [r * np.exp(1j * phi), r * np.exp(-1j * phi)]
        else:
            roots.append(radius * rng.uniform(-1, 1))
    return np.atleast_1d(np.real(np.poly(roots)))


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(na=st.integers(0, 3), nb=st.integers(0, 2), nc=st.integers(0, 3),
       nd=st.integers(0, 2), q1=st.integers(0, 3), q2=st.integers(0, 2),
       seed=st.integers(0, 2**31), random_state=st.booleans())
def test_kernel_agrees_with_python_control(na, nb, nc, nd, q1, q2, seed,
                                           random_state):
    rng = np.random.default_rng(seed)
    a = _stable_poly(rng, na)[1:]
    c = _stable_poly(rng, nc)[1:]
    b = rng.uniform(0.5, 2, nb + 1) * rng.choice([-1, 1], nb + 1)
    d = rng.uniform(0.5, 2, nd + 1) * rng.choice([-1, 1], nd + 1)
    m1, m2 = rng.uniform(0.3, 3, 2)
    D1, D2 = rng.uniform(0, 1, 2)
    plant = sw.SandwichSystem.from_coefficients(
        a, b, c, d, m1, m2, D1, D2, q1=q1, q2=q2, dt=0.1)
    u = rng.normal(0, 1, 120)
    x0 = rng.normal(0, 1, plant.nstates) if random_state else None
    fast = plant.simulate(u, initial_state=x0, return_states=True)
    slow = ct.input_output_response(
        plant, 0.1 * np.arange(u.size), u,
        initial_state=0 if x0 is None else x0)
    np.testing.assert_allclose(fast.outputs, slow.outputs, rtol=0,
                               atol=1e-10)
    np.testing.assert_allclose(fast.states, slow.states, rtol=0, atol=1e-10)
    # and with the literal transcription of eqs. (2.1)-(2.2)
    if x0 is None:
        y_ref, _, _ = _reference(u, a, b, q1, c, d, q2, m1, m2, D1, D2)
        np.testing.assert_allclose(fast.outputs, y_ref, rtol=1e-9,
                                   atol=1e-9)


def test_continuation_with_final_state(rng):
    plant = sw.examples.paper_plant()
    u = rng.normal(0, 0.7, 400)
    whole = plant.simulate(u).outputs
    first = plant.simulate(u[:150])
    second = plant.simulate(u[150:], initial_state=first.final_state)
    np.testing.assert_array_equal(
        np.concatenate([first.outputs, second.outputs]), whole)


def test_internal_signals_and_response_object():
    plant = sw.examples.paper_plant(dt=0.5)
    resp = plant.simulate(np.ones(6), internal=True)
    assert isinstance(resp, ct.TimeResponseData)
    assert resp.output_labels == ['y', 'x', 'v']
    np.testing.assert_allclose(resp.time, 0.5 * np.arange(6))
    assert plant.simulate(np.ones(6)).outputs.shape == (6,)


def test_parts_orders_and_repr():
    plant = sw.examples.paper_plant()
    assert isinstance(plant, ct.InterconnectedSystem)
    assert isinstance(plant.L1, ct.TransferFunction)
    assert isinstance(plant.backlash, sw.Backlash)
    np.testing.assert_allclose(plant.L1.num[0][0], [1.5, 0])
    np.testing.assert_allclose(plant.L2.den[0][0], [1, 1.2, 0.32])
    assert plant.orders == dict(na=2, nb=0, nc=2, nd=1, q1=1, q2=1)
    text = repr(plant)
    assert 'x(k) = -0.1 x(k-1) - 0.2 x(k-2) + 1.5 u(k-1)' in text
    assert 'y(k) = -1.2 y(k-1) - 0.32 y(k-2) + 2 v(k-1) - 0.1 v(k-2)' in text
    assert 'm1 = 1, m2 = 1.2, D1 = 0.5, D2 = 0.6' in text


@pytest.mark.parametrize('num, den, expected', [
    ([1.5, 0], [1, 0.1, 0.2], dict(na=2, nb=0, q1=1)),
    ([1.5], [1, 0.1, 0.2], dict(na=2, nb=0, q1=2)),
    ([1, 0.5, 0], [1, -0.3, 0, 0], dict(na=1, nb=1, q1=1)),
    ([2, 1], [1, 0.4], dict(na=1, nb=1, q1=0)),
    ([3], [1], dict(na=0, nb=0, q1=0)),
])
def test_orders_from_transfer_functions(num, den, expected):
    L1 = ct.tf(num, den, 1)
    plant = sw.SandwichSystem(L1, sw.Backlash(1, 1, 0.1, 0.1),
                              ct.tf([1, 0], [1, -0.5], 1))
    orders = plant.orders
    assert {k: orders[k] for k in expected} == expected


def test_normalized_paper_example():
    plant = sw.examples.paper_plant()
    norm = plant.normalized()
    co = norm.coefficients
    assert norm.is_normalized and not plant.is_normalized
    np.testing.assert_allclose(
        [co['m1'], co['m2'], co['D1'], co['D2']], [3, 3.6, 1 / 3, 0.4],
        rtol=1e-15)
    np.testing.assert_allclose(co['d'], [1, -0.05], rtol=1e-15)
    np.testing.assert_allclose(co['a'], [0.1, 0.2])
    np.testing.assert_allclose(co['c'], [1.2, 0.32])
    np.testing.assert_allclose(
        plant.theta, [1.2, 0.32, 0.1, 0.2, 3, 3.6, 1 / 3, 0.4, -0.05],
        rtol=1e-15)
    u = sw.examples.paper_input(5000, seed=1)
    np.testing.assert_allclose(norm.simulate(u).outputs,
                               plant.simulate(u).outputs,
                               rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize('b0, d0', [(2.0, 0.5), (-1.5, -2.0), (0.3, 4.0)])
def test_normalized_output_identical_any_gain_sign(b0, d0, rng):
    plant = sw.SandwichSystem.from_coefficients(
        a=[-0.5], b=[b0, 0.3 * b0], c=[0.2, 0.1], d=[d0], m1=0.8, m2=1.7,
        D1=0.2, D2=0.5, q1=1, q2=0)
    u = rng.normal(0, 1, 3000)
    np.testing.assert_allclose(plant.normalized().simulate(u).outputs,
                               plant.simulate(u).outputs,
                               rtol=1e-11, atol=1e-11)


@pytest.mark.parametrize('b0, d0', [(-1.5, 2.0), (1.5, -2.0), (-0.5, -3.0)])
def test_signed_normalisation_keeps_output_and_sign(rng, b0, d0):
    """b0 = 1, d0 = sign(b0 d0): the same output from rest, any signs."""
    plant = sw.SandwichSystem.from_coefficients(
        a=[-0.5], b=[b0, 0.3], c=[0.2, 0.1], d=[d0, -0.4], m1=0.8, m2=1.3,
        D1=0.1, D2=0.3, q1=1, q2=0, dt=0.01, name='ax')
    norm = plant.normalized()
    assert norm.is_normalized and norm.name == 'ax'
    assert norm.gain_sign == plant.gain_sign == int(np.sign(b0 * d0))
    assert norm.coefficients['b'][0] == 1
    assert norm.coefficients['d'][0] == np.sign(b0 * d0)
    u = rng.standard_normal(300)
    np.testing.assert_allclose(norm.simulate(u).outputs,
                               plant.simulate(u).outputs, atol=1e-12)
    back = sw.SandwichSystem.from_theta(norm.theta, **plant.orders,
                                        dt=0.01, sign=plant.gain_sign)
    np.testing.assert_allclose(back.simulate(u).outputs,
                               plant.simulate(u).outputs, atol=1e-12)


def test_declared_orders_keep_zero_coefficients():
    """An identified coefficient that is exactly 0 does not drop an order."""
    plant = sw.SandwichSystem.from_coefficients(
        a=[0.5, 0.0], b=[1.0, 0.0], c=[0.0], d=[1.0, 0.0], m1=1, m2=1,
        D1=0.1, D2=0.1, q1=1, q2=1)
    assert plant.orders == {'na': 2, 'nb': 1, 'nc': 1, 'nd': 1, 'q1': 1,
                            'q2': 1}
    assert plant.theta.size == 1 + 2 + 4 + 1 + 1
    assert plant.normalized().orders == plant.orders
    with pytest.raises(ValueError, match='smaller'):
        sw.SandwichSystem(plant.L1, plant.backlash, plant.L2,
                          orders={'na': 0})


def test_theta_round_trip(rng):
    plant = sw.SandwichSystem.from_coefficients(
        a=[0.3, -0.1], b=[2.0, 0.4], c=[-0.5], d=[0.5, 0.2, 0.1],
        m1=1.1, m2=0.9, D1=0.3, D2=0.2, q1=2, q2=1, dt=0.01)
    theta = plant.theta
    assert plant.theta_labels == ['c1', 'a1', 'a2', 'm1', 'm2', 'D1', 'D2',
                                  'b1', 'd1', 'd2']
    back = sw.SandwichSystem.from_theta(theta, **plant.orders, dt=0.01)
    np.testing.assert_allclose(back.theta, theta, rtol=1e-15)
    assert back.orders == plant.orders and back.dt == 0.01
    u = rng.normal(0, 1, 1000)
    np.testing.assert_allclose(back.simulate(u).outputs,
                               plant.simulate(u).outputs, rtol=1e-11,
                               atol=1e-11)


def test_theta_of_a_negative_gain_rebuilds_the_same_system(rng):
    """theta has no d0; for a negative gain it carries sign = -1, so that
    from_theta(theta, **orders) needs no sign argument."""
    plant = sw.SandwichSystem.from_coefficients(
        a=[0.3], b=[-2.0, 0.4], c=[-0.5], d=[0.5, 0.2], m1=1.1, m2=0.9,
        D1=0.3, D2=0.2, dt=1)
    assert plant.gain_sign == -1 and plant.theta.sign == -1
    u = rng.normal(0, 1, 500)
    for theta in (plant.theta, plant.theta.copy(), 1.0 * plant.theta):
        back = sw.SandwichSystem.from_theta(theta, **plant.orders, dt=1)
        assert back.gain_sign == -1
        np.testing.assert_allclose(back.simulate(u).outputs,
                                   plant.simulate(u).outputs, atol=1e-12)
    # a plain array has no sign: the explicit argument gives it
    plain = np.asarray(plant.theta)
    assert type(plain) is np.ndarray
    assert sw.SandwichSystem.from_theta(plain, **plant.orders).gain_sign == 1
    assert sw.SandwichSystem.from_theta(plain, **plant.orders,
                                        sign=-1).gain_sign == -1
    # positive gains keep a plain array (the paper's theta)
    assert type(sw.examples.paper_plant().theta) is np.ndarray
    assert float(plant.theta.max()) == max(plain)


def test_identified_theta_rebuilds_the_identified_model():
    """A hidden random plant with d0 = -1 gave another model from
    from_theta(res.theta, **orders) (425 apart in output)."""
    plant = sw.examples.paper_plant()
    neg = plant.copy_with(d=-plant.coefficients['d'])
    u = sw.examples.paper_input(1000, seed=3)
    res = sw.identify(u, neg.simulate(u).outputs, **plant.orders)
    assert res.success and res.model.gain_sign == -1
    back = sw.SandwichSystem.from_theta(res.theta, **plant.orders)
    np.testing.assert_array_equal(back.simulate(u).outputs,
                                  res.model.simulate(u).outputs)


def test_copy_with_changes_parts_and_keeps_the_rest(rng):
    plant = sw.examples.paper_plant()
    u = rng.normal(0, 1, 300)
    wider = plant.copy_with(D1=0.7, name='wider')
    assert wider.coefficients['D1'] == 0.7 and wider.name == 'wider'
    assert wider.L1 is plant.L1 and wider.orders == plant.orders
    same = plant.copy_with(backlash=plant.backlash)
    np.testing.assert_array_equal(same.simulate(u).outputs,
                                  plant.simulate(u).outputs)
    longer = plant.copy_with(c=[1.2, 0.32, 0.0])
    assert longer.orders['nc'] == 3 and longer.name == plant.name
    np.testing.assert_allclose(longer.simulate(u).outputs,
                               plant.simulate(u).outputs, atol=1e-12)
    other_l2 = plant.copy_with(L2=ct.tf([1], [1, -0.5], 1))
    assert other_l2.orders['nc'] == 1 and other_l2.L1 is plant.L1


def test_states_of_a_simulation(rng):
    plant = sw.examples.paper_plant()
    u = rng.normal(0, 1, 50)
    stored = plant.simulate(u, return_states=True)
    assert stored.states.shape == (plant.nstates, 50)
    with pytest.raises(AttributeError, match='return_states=True'):
        plant.simulate(u).states


def test_feedback_and_interconnect_work_like_any_system():
    plant = sw.examples.paper_plant()
    K = 0.2
    closed = ct.feedback(plant, K)
    r = np.sin(0.05 * np.arange(300))
    resp = ct.input_output_response(closed, np.arange(r.size), r)
    # the same loop by hand, one sample at a time (q1 = 1: no algebraic
    # loop)
    state, y = None, np.zeros(r.size)
    for k in range(r.size):
        yk_resp = plant.simulate([0.0], initial_state=state)
        y[k] = yk_resp.outputs[0]      # y(k) does not depend on u(k)
        step = plant.simulate([r[k] - K * y[k]], initial_state=state)
        state = step.final_state
    np.testing.assert_allclose(resp.outputs, y, atol=1e-10)

    ctrl = ct.tf([0.3], [1], 1, inputs='e', outputs='u', name='ctrl')
    sumblk = ct.summing_junction(inputs=['r', '-y'], output='e')
    loop = ct.interconnect([plant, ctrl, sumblk], inplist='r', outlist='y')
    resp2 = ct.input_output_response(loop, np.arange(r.size), r)
    closed2 = ct.feedback(plant, 1)
    assert resp2.outputs.shape == r.shape and np.all(np.isfinite(resp2.outputs))
    assert closed2.nstates == plant.nstates


@pytest.mark.parametrize('make, exc, match', [
    (lambda: sw.SandwichSystem(ct.tf([1], [1, 1]), sw.Backlash(1, 1, 1, 1),
                               ct.tf([1], [1, 0.5], 1)),
     ValueError, 'L1 must be discrete-time'),
    (lambda: sw.SandwichSystem(ct.tf([1], [1, 0.5], 1),
                               sw.Backlash(1, 1, 1, 1),
                               ct.tf([[[1]], [[1]]], [[[1, .5]], [[1, .5]]],
                                     1)),
     ValueError, 'L2 must be SISO'),
    (lambda: sw.SandwichSystem(ct.tf([1], [1, 0.5], 1),
                               sw.Backlash(1, 1, 1, 1),
                               ct.tf([1], [1, 0.5], 0.1)),
     ValueError, 'same sampling time; got dt=1 and dt=0.1'),
    (lambda: sw.SandwichSystem(ct.tf([1], [1, 0.5], 1),
                               sw.Backlash(1, 1, 1, 1, dt=2),
                               ct.tf([1], [1, 0.5], 1)),
     ValueError, 'same sampling time'),
    (lambda: sw.SandwichSystem(ct.tf([1, 0, 0], [1, 0.5], 1),
                               sw.Backlash(1, 1, 1, 1),
                               ct.tf([1], [1, 0.5], 1)),
     ValueError, 'L1 is improper'),
    (lambda: sw.SandwichSystem(ct.tf([1], [1, 0.5], 1), (1, 1, 1, 1),
                               ct.tf([1], [1, 0.5], 1)),
     TypeError, 'backlash must be a sandwichctl.Backlash'),
    (lambda: sw.SandwichSystem(ct.ss(-0.5, 1, 1, 0, 1),
                               sw.Backlash(1, 1, 1, 1),
                               ct.tf([1], [1, 0.5], 1)),
     TypeError, 'L1 must be a control.TransferFunction'),
    (lambda: sw.SandwichSystem.from_coefficients(
        [0.1], [0, 1.5], [0.2], [1], 1, 1, 1, 1),
     ValueError, r'b\[0\] is 0.*express a delay with q1'),
    (lambda: sw.SandwichSystem.from_coefficients(
        [0.1], [1.5], [0.2], [0.0, 1.0], 1, 1, 1, 1),
     ValueError, r'd\[0\] is 0'),
    (lambda: sw.SandwichSystem.from_coefficients(
        [0.1], [1.5], [0.2], [1.0], 1, 1, 1, 1, q1=-1),
     ValueError, 'q1 must be an integer >= 0'),
    (lambda: sw.SandwichSystem.from_coefficients(
        [0.1], [1.5], [0.2], [1.0], 0, 1, 1, 1),
     ValueError, 'm1 must be a finite number > 0'),
    (lambda: sw.SandwichSystem.from_coefficients(
        [0.1], [1.5], [0.2], [1.0], 1, 1, -1, 1),
     ValueError, 'D1 must be a finite number >= 0'),
    (lambda: sw.SandwichSystem.from_theta(np.ones(8), 2, 0, 2, 1),
     ValueError, r'theta must be a 1-D array of length 9; got shape \(8,\)'),
    (lambda: sw.SandwichSystem.from_theta(np.ones(9), 2.5, 0, 2, 1),
     TypeError, 'na must be an integer'),
    (lambda: sw.examples.paper_plant().simulate([0.0, np.inf]),
     ValueError, 'inputs must be finite; sample 1 is inf'),
    (lambda: sw.examples.paper_plant().simulate(np.zeros((3, 3))),
     ValueError, r'inputs must be a 1-D array of samples; got shape \(3, 3\)'),
    (lambda: sw.examples.paper_plant().simulate([1.0], initial_state=[0, 0]),
     ValueError, 'initial_state must be a 1-D array of length 6'),
    (lambda: sw.examples.paper_plant().simulate('abc'),
     TypeError, 'inputs must be an array of numbers'),
])
def test_bad_input(make, exc, match):
    with pytest.raises(exc, match=match):
        make()


# ----------------------------------------------------------------------
# Step responses, time points, declared orders
# ----------------------------------------------------------------------
def test_step_response_depends_on_the_amplitude():
    plant = sw.examples.paper_plant()
    small = sw.step_response(plant, amplitude=0.2)
    assert np.all(small.outputs == 0)             # inside the dead band
    big = sw.step_response(plant, amplitude=2.0)
    np.testing.assert_array_equal(
        big.outputs, plant.simulate(np.full(big.time.size, 2.0)).outputs)
    assert 'amplitude 2' in big.title
    # python-control's own step_response needs time points, and agrees
    unit = sw.step_response(plant, timepts=np.arange(30))
    np.testing.assert_allclose(
        ct.step_response(plant, np.arange(30)).outputs, unit.outputs,
        atol=1e-12)


def test_step_response_time_points():
    plant = sw.SandwichSystem(ct.tf([1], [1, -0.5], 0.1),
                              sw.Backlash(1, 1, 0.1, 0.1),
                              ct.tf([1], [1, -0.9], 0.1))
    resp = sw.step_response(plant)
    # slowest pole 0.9: 7 time constants of -1/ln(0.9) samples, + delays
    assert resp.time.size == int(np.ceil(7 / -np.log(0.9))) + 2
    np.testing.assert_allclose(resp.time, 0.1 * np.arange(resp.time.size))
    assert sw.step_response(plant, timepts=2.0).time.size == 21
    integrating = sw.SandwichSystem(ct.tf([1], [1, -1], 1),
                                    sw.Backlash(1, 1, 0.1, 0.1),
                                    ct.tf([1], [1, 0], 1))
    assert sw.step_response(integrating).time.size == 102
    lin = sw.step_response(ct.tf([1], [1, -0.5], 1), amplitude=3)
    np.testing.assert_allclose(lin.outputs[-1], 6, rtol=1e-3)


def test_simulate_accepts_evenly_spaced_timepts_only():
    plant = sw.SandwichSystem(ct.tf([1], [1, -0.5], 0.1),
                              sw.Backlash(1, 1, 0.1, 0.1),
                              ct.tf([1], [1, -0.9], 0.1))
    t = 5 + 0.1 * np.arange(30)
    np.testing.assert_array_equal(plant.simulate(np.ones(30),
                                                 timepts=t).time, t)
    with pytest.raises(ValueError, match='timepts must be evenly spaced'):
        plant.simulate(np.ones(30), timepts=t + 0.01 * (np.arange(30) > 9))
    with pytest.raises(ValueError, match='timepts has spacing 1'):
        plant.simulate(np.ones(30), timepts=np.arange(30))


def test_simulate_with_timepts_returns_the_inputs_given():
    # the kernel copies u only where it also writes the time points: with
    # time points given, the response's inputs were an unfilled buffer
    plant = sw.SandwichSystem(ct.tf([1], [1, -0.5], 0.1),
                              sw.Backlash(1, 1, 0.1, 0.1),
                              ct.tf([1], [1, -0.9], 0.1))
    u = np.sin(0.3 * np.arange(30))
    t = 5 + 0.1 * np.arange(30)
    for internal in (False, True):
        resp = plant.simulate(u, timepts=t, internal=internal)
        np.testing.assert_array_equal(np.ravel(resp.inputs), u)
        np.testing.assert_array_equal(resp.time, t)
    step = sw.step_response(plant, amplitude=2.0)
    np.testing.assert_array_equal(np.ravel(step.inputs),
                                  np.full(step.time.size, 2.0))


def test_from_coefficients_keeps_orders_without_extra_states():
    plant = sw.SandwichSystem.from_coefficients(
        a=[0.1, 0.2, 0.0], b=[1.5, 0.0], c=[1.2, 0.32], d=[2, -0.1, 0.0],
        m1=1, m2=1.2, D1=0.5, D2=0.6, dt=1)
    assert plant.orders == {'na': 3, 'nb': 1, 'nc': 2, 'nd': 2, 'q1': 1,
                            'q2': 1}
    ref = sw.examples.paper_plant()
    assert plant.nstates == ref.nstates
    u = sw.examples.paper_input(200, seed=2)
    np.testing.assert_array_equal(plant.simulate(u).outputs,
                                  ref.simulate(u).outputs)


def test_simulate_paths_agree_bit_for_bit(rng):
    """Register kernel, array kernel and the generic fallback agree."""
    for a, d in (([0.1, 0.2], [2, -0.1]),                 # orders <= 2
                 ([0.1, 0.2, 0.1], [2, -0.1, 0.3]),       # orders <= 4
                 ([0.1, 0.2, 0.1, 0.05, 0.02], [2, -0.1, 0.3, 0.1, 0.2, 0.1])):
        plant = sw.SandwichSystem.from_coefficients(
            a=a, b=[1.5], c=[1.2, 0.32], d=d, m1=1, m2=1.2, D1=0.5, D2=0.6)
        u = rng.normal(0, 1, 500)
        x0 = rng.normal(0, 1, plant.nstates)
        fast = plant.simulate(u, initial_state=x0, internal=True)
        full = plant.simulate(u, initial_state=x0, internal=True,
                              return_states=True)
        np.testing.assert_array_equal(fast.outputs, full.outputs)
        np.testing.assert_array_equal(fast.final_state, full.final_state)
        generic = copy.deepcopy(plant)
        generic._companion = None         # force the matrix kernel
        slow = generic.simulate(u, initial_state=x0, internal=True,
                                return_states=True)
        np.testing.assert_allclose(slow.outputs, fast.outputs, rtol=0,
                                   atol=1e-12)
        np.testing.assert_allclose(slow.states, full.states, rtol=0,
                                   atol=1e-12)
        np.testing.assert_allclose(generic.simulate_batch(u[None], None, x0),
                                   fast.outputs[:1], rtol=0, atol=1e-12)


def test_simulate_response_owns_its_arrays():
    plant = sw.examples.paper_plant(dt=0.5)
    u = np.ones(5)
    resp = plant.simulate(u)
    u[:] = 7.0
    np.testing.assert_array_equal(resp.inputs, np.ones(5))
    np.testing.assert_array_equal(resp.time, 0.5 * np.arange(5))
    assert resp.outputs.shape == (5,)


def test_sampling_times_equal_to_rounding_are_one():
    """0.1 * 3 and 0.3 are one sampling time to python-control (its
    product of the two blocks has one); a sandwich of them too."""
    L1 = ct.tf([1.5, 0], [1, 0.1, 0.2], 0.1 * 3)
    L2 = ct.tf([1, 0], [1, -0.5], 0.3)
    assert (L1 * L2).dt == pytest.approx(0.3)
    plant = sw.SandwichSystem(L1, sw.Backlash(1, 1, 0.1, 0.1), L2)
    assert plant.dt == 0.1 * 3
    with pytest.raises(ValueError, match='same sampling time'):
        sw.SandwichSystem(L1, sw.Backlash(1, 1, 0.1, 0.1),
                          ct.tf([1, 0], [1, -0.5], 0.3003))


def test_python_control_poles_zeros_and_dcgain_of_a_sandwich():
    """ct.poles and ct.zeros give L1's and L2's; ct.dcgain refuses with
    the reason and names the linearised plant's gain instead."""
    plant = sw.examples.paper_plant()
    np.testing.assert_allclose(
        np.sort_complex(ct.poles(plant)),
        np.sort_complex(np.r_[ct.poles(plant.L1), ct.poles(plant.L2)]))
    np.testing.assert_allclose(
        np.sort_complex(ct.zeros(plant)),
        np.sort_complex(np.r_[ct.zeros(plant.L1), ct.zeros(plant.L2)]))
    with pytest.raises(TypeError, match="no single DC gain.*linearized"):
        ct.dcgain(plant)


def test_theta_labels_take_a_plants_orders_whole():
    plant = sw.examples.paper_plant()
    assert sw.theta_labels(**plant.orders) == plant.theta_labels
