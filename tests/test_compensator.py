"""Tests of the compensator (issue 5): backlash inverse, L1 inverse, loop."""

import warnings

import numpy as np
import control as ct
import pytest
from hypothesis import given, settings, strategies as st, HealthCheck

import sandwichctl as sw

PAPER = (1.0, 1.2, 0.5, 0.6)                  # m1, m2, D1, D2 of Section 5
BACKLASHES = [PAPER, (3.0, 3.6, 1 / 3, 0.4), (1.0, 1.0, 0.5, 0.5),
              (2.0, 2.0, 0.0, 0.0), (0.7, 2.5, 0.2, 1.1), (2.5, 0.7, 1.1, 0.0)]


def _signal_with_ties(rng, n, lo, hi):
    """Random levels with about a third of the samples repeating the last."""
    v = rng.uniform(lo, hi, n)
    ties = rng.random(n) < 0.35
    ties[0] = False
    for k in np.flatnonzero(ties):
        v[k] = v[k - 1]
    return v


def _safe_range(m1, m2, D1, D2, span=6.0):
    """A v-range on the side of the slope-line crossing where the band of
    eq. (2.2) is not empty (the inverse is exact there)."""
    if m1 == m2:
        return -span / 2, span / 2
    v_star = -(D1 + D2) / (1 / m1 - 1 / m2)      # band width 0 here
    if m1 < m2:
        lo = max(-span / 2, v_star + 1e-3)
        return lo, lo + span
    hi = min(span / 2, v_star - 1e-3)
    return hi - span, hi


def _consistent_state(rng, m1, m2, D1, D2, lo, hi):
    v0 = rng.uniform(lo, hi)
    x0 = rng.uniform(v0 / m2 - D2, v0 / m1 + D1)   # inside the band
    return x0, v0


# ----------------------------------------------------------------------
# Backlash inverse: exactness
# ----------------------------------------------------------------------
@pytest.mark.parametrize('params', BACKLASHES)
def test_inverse_then_backlash_is_identity(params, rng):
    m1, m2, D1, D2 = params
    lo, hi = _safe_range(*params)
    for _ in range(5):
        v_d = _signal_with_ties(rng, 2000, lo, hi)
        x0, v0 = _consistent_state(rng, *params, lo, hi)
        x, v_hat = sw.backlash_inverse_response(v_d, *params, x0, v0,
                                                return_expected=True)
        v = sw.backlash_response(x, *params, x_prev=x0, v_prev=v0)
        np.testing.assert_allclose(v, v_d, rtol=0, atol=1e-12)
        np.testing.assert_allclose(v_hat, v_d, rtol=0, atol=1e-12)


def test_inverse_and_backlash_in_python_control(rng):
    bl = sw.Backlash(*PAPER, dt=1)
    inv = sw.backlash_inverse(bl)
    both = ct.series(inv, bl)
    v_d = _signal_with_ties(rng, 150, -2, 2)
    x0, v0 = 0.7, 0.4                    # band at v0: [-0.267, 0.9]
    resp = ct.input_output_response(both, np.arange(v_d.size), v_d,
                                    initial_state=[x0, v0, x0, v0])
    np.testing.assert_allclose(resp.outputs, v_d, rtol=0, atol=1e-12)
    # and the I/O system agrees with the compiled map
    x = ct.input_output_response(inv, np.arange(v_d.size), v_d,
                                 initial_state=[x0, v0]).outputs
    np.testing.assert_allclose(x, sw.backlash_inverse_response(
        v_d, *PAPER, x0, v0), rtol=0, atol=1e-15)


def test_inverse_hand_values_and_ties():
    # rise, hold (tie), fall, tiny rise after a fall (strictness of (2.2)),
    # return to an earlier value exactly
    m1, m2, D1, D2 = PAPER
    v_d = np.array([0.0, 1.0, 1.0, 0.5, 0.5 + 1e-9, 0.5 + 1e-9, 1.0, -1.0])
    x = sw.backlash_inverse_response(v_d, *PAPER)
    expected = [0.0,                       # tie with v(-1) = 0: hold x(-1)
                1.0 / m1 + D1,             # rise: increase line
                1.0 / m1 + D1,             # tie: hold
                0.5 / m2 - D2,             # fall: decrease line
                (0.5 + 1e-9) / m1 + D1,    # rise by 1e-9: jump the band
                (0.5 + 1e-9) / m1 + D1,
                1.0 / m1 + D1,
                -1.0 / m2 - D2]
    np.testing.assert_allclose(x, expected, rtol=0, atol=1e-15)
    v, zones = sw.backlash_response(x, *PAPER, return_zones=True)
    np.testing.assert_allclose(v, v_d, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(zones, [0, 1, 0, -1, 1, 0, 1, -1])


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(m1=st.floats(0.2, 5), m2=st.floats(0.2, 5), D1=st.floats(0, 2),
       D2=st.floats(0, 2), seed=st.integers(0, 2**31))
def test_inverse_is_exact_property(m1, m2, D1, D2, seed):
    rng = np.random.default_rng(seed)
    lo, hi = _safe_range(m1, m2, D1, D2)
    v_d = _signal_with_ties(rng, 300, lo, hi)
    x0, v0 = _consistent_state(rng, m1, m2, D1, D2, lo, hi)
    x = sw.backlash_inverse_response(v_d, m1, m2, D1, D2, x0, v0)
    v = sw.backlash_response(x, m1, m2, D1, D2, x_prev=x0, v_prev=v0)
    np.testing.assert_allclose(v, v_d, rtol=0, atol=1e-12 * max(1, hi))


def test_inverse_beyond_the_crossing_holds_until_reachable():
    # m1 < m2: the lines cross at x* = (m1 D1 + m2 D2)/(m1 - m2) = -6.1.
    # Far below it, after a fall onto the decrease line, a small rise is
    # unreachable by a monotone step (the increase line is above): the
    # inverse holds x; a larger rise is reached exactly.
    m1, m2, D1, D2 = PAPER
    x0 = -10.0
    v0 = m2 * (x0 + D2)                                   # -11.28
    x = sw.backlash_inverse_response([v0 + 0.1, v0 + 1.0], *PAPER, x0, v0)
    assert x[0] == x0                                     # hold
    v = sw.backlash_response(x, *PAPER, x_prev=x0, v_prev=v0)
    assert v[0] == v0
    # v0 + 1 = m1 (x - D1) needs x = v0 + 1.5 = -9.78 > x0: reachable
    np.testing.assert_allclose(x[1], (v0 + 1.0) / m1 + D1, atol=1e-15)
    np.testing.assert_allclose(v[1], v0 + 1.0, atol=1e-14)


# ----------------------------------------------------------------------
# Smoothing
# ----------------------------------------------------------------------
def test_smoothing_is_exact_for_large_changes(rng):
    delta = 0.2
    steps = rng.uniform(0.2, 1.0, 500) * rng.choice([-1, 1], 500)
    v_d = np.cumsum(steps)
    x = sw.backlash_inverse_response(v_d, *PAPER, smoothing=delta)
    np.testing.assert_allclose(sw.backlash_response(x, *PAPER), v_d,
                               rtol=0, atol=1e-12)


def test_smoothing_makes_the_inverse_continuous_and_monotone():
    inv = sw.BacklashInverse(*PAPER, smoothing=0.3, dt=1)
    state = [0.9, 0.4]              # on the increase edge: 0.4/1 + 0.5
    grid = 0.4 + np.linspace(-0.5, 0.5, 20001)
    x = np.array([inv.output(0, state, [v])[0] for v in grid])
    assert np.all(np.diff(x) >= 0)
    assert np.max(np.abs(np.diff(x))) < 1e-3        # no jump at v_d = 0.4
    exact = sw.BacklashInverse(*PAPER, dt=1)
    x_exact = np.array([exact.output(0, state, [v])[0] for v in grid])
    jump = np.max(np.abs(np.diff(x_exact)))
    np.testing.assert_allclose(jump, 0.9 - (0.4 / 1.2 - 0.6), atol=1e-3)


def test_smoothing_reaches_a_held_value_without_overshoot():
    # reversal after rising: v_d falls by 0.05 < smoothing and is held
    v_d = np.concatenate([np.linspace(0, 1, 11), np.full(40, 0.95)])
    x, v_hat = sw.backlash_inverse_response(v_d, *PAPER, smoothing=0.5,
                                            return_expected=True)
    v = sw.backlash_response(x, *PAPER)
    np.testing.assert_allclose(v, v_hat, rtol=0, atol=1e-15)
    tail = v[10:]
    assert np.all(tail >= 0.95 - 1e-12)              # never below target
    assert np.all(np.diff(tail) <= 1e-15)            # monotone approach
    np.testing.assert_allclose(v[-1], 0.95, atol=1e-12)


def test_smoothing_reduces_chattering(rng):
    v_d = 0.5 + 0.01 * rng.standard_normal(3000)
    tv = {}
    for delta in (0.0, 0.2):
        x = sw.backlash_inverse_response(v_d, *PAPER, smoothing=delta)
        tv[delta] = np.sum(np.abs(np.diff(x)))
    assert tv[0.2] < 0.05 * tv[0.0]


# ----------------------------------------------------------------------
# Wrong parameters: closed-form degradation
# ----------------------------------------------------------------------
@pytest.mark.parametrize('eps', [-0.3, -0.1, 0.1, 0.3])
def test_threshold_error_gives_a_constant_offset_on_a_rise(eps):
    m1, m2, D1, D2 = PAPER
    D1_hat = D1 * (1 + eps)
    v_d = np.linspace(1.0, 3.0, 40)
    # both on their increase line at v = 0.5
    x = sw.backlash_inverse_response(v_d, m1, m2, D1_hat, D2,
                                     x_prev=0.5 / m1 + D1_hat, v_prev=0.5)
    v = sw.backlash_response(x, *PAPER, x_prev=0.5 / m1 + D1, v_prev=0.5)
    np.testing.assert_allclose(v - v_d, m1 * eps * D1, rtol=0, atol=1e-12)


@pytest.mark.parametrize('eps', [-0.3, -0.1, 0.1, 0.3])
def test_slope_error_scales_a_rise(eps):
    m1, m2, D1, D2 = PAPER
    m1_hat = m1 * (1 + eps)
    v_d = np.linspace(0.5, 3.0, 50)
    x0 = 0.5 / m1_hat + D1
    x = sw.backlash_inverse_response(v_d, m1_hat, m2, D1, D2, x_prev=x0,
                                     v_prev=0.5)
    v = sw.backlash_response(x, *PAPER, x_prev=x0, v_prev=m1 * (x0 - D1))
    np.testing.assert_allclose(v, v_d / (1 + eps), rtol=1e-12)


@pytest.mark.parametrize('name', ['m1', 'm2', 'D1', 'D2'])
def test_degradation_grows_with_the_parameter_error(name, rng):
    v_d = np.convolve(rng.standard_normal(4000), np.ones(20), 'same')
    v_d = np.clip(v_d / v_d.std(), -3, 3)     # slope lines cross at -6.6
    bl = sw.Backlash(*PAPER)
    errors = []
    for eps in (0.0, 0.1, 0.3):
        wrong = bl.copy_with(**{name: getattr(bl, name) * (1 + eps)})
        x = sw.backlash_inverse(wrong).response(v_d)
        errors.append(np.sqrt(np.mean((bl.response(x) - v_d) ** 2)))
    assert errors[0] < 1e-12
    assert 0.01 < errors[1] < errors[2]


# ----------------------------------------------------------------------
# Inverse of L1
# ----------------------------------------------------------------------
@pytest.mark.parametrize('q', [0, 1, 3])
def test_causal_inverse_is_a_pure_delay(q):
    den = np.poly([0.8, -0.6, 0.1 + 0.5j, 0.1 - 0.5j]).real
    num = 1.7 * np.poly([0.5, -0.3 + 0.4j, -0.3 - 0.4j, 0.9][:4 - q]).real
    G = ct.tf(num, den, 1)                         # relative degree q
    Ginv = sw.causal_inverse(G)
    z = np.exp(1j * np.linspace(0.01, np.pi, 50))
    np.testing.assert_allclose(G(z) * Ginv(z), z ** -q, rtol=1e-10)
    assert np.all(np.abs(Ginv.poles()) < 1)


def test_causal_inverse_of_the_paper_l1():
    Linv = sw.causal_inverse(sw.examples.paper_plant().L1)
    np.testing.assert_allclose(Linv.num[0][0], [1, 0.1, 0.2])
    np.testing.assert_allclose(Linv.den[0][0], [1.5, 0, 0])


def test_non_minimum_phase_l1_raises_unless_approximate():
    L1 = ct.tf([1.0, -1.6], [1, -0.5, 0.06], 1)      # zero at 1.6
    with pytest.raises(ValueError, match=r"non-minimum-phase.*1\.6.*"
                                         r"approximate=True"):
        sw.causal_inverse(L1)
    Linv = sw.causal_inverse(L1, approximate=True)
    assert np.all(np.abs(Linv.poles()) < 1)
    z = np.exp(1j * np.linspace(0.0, np.pi, 50))
    loop = L1(z) * Linv(z)
    np.testing.assert_allclose(np.abs(loop), 1.0, rtol=1e-12)   # all-pass
    np.testing.assert_allclose(loop[0], 1.0, rtol=1e-12)        # DC gain 1
    with pytest.raises(ValueError, match="unit circle"):
        sw.causal_inverse(ct.tf([1.0, 1.0], [1, 0.5, 0], 1))    # zero at -1


# ----------------------------------------------------------------------
# Whole-sandwich compensator
# ----------------------------------------------------------------------
def _other_plant(q1):
    # slope lines cross at v = 3.57, above the signals used
    return sw.SandwichSystem.from_coefficients(
        a=[-0.5, 0.06], b=[0.8, 0.3], c=[-0.9, 0.2], d=[1.2, 0.4],
        m1=1.3, m2=1.1, D1=0.3, D2=0.2, q1=q1, q2=1, dt=0.1)


@pytest.mark.parametrize('which', ['paper', 'normalised', 'q1=0', 'q1=2'])
def test_compensated_plant_is_linear(which, rng):
    if which in ('paper', 'normalised'):
        plant = sw.examples.paper_plant()
        model = plant if which == 'paper' else plant.normalized()
    else:
        plant = model = _other_plant(int(which[-1]))
    comp = sw.sandwich_compensator(model)
    assert comp.is_exact and comp.delay == plant.orders['q1']
    v_d = 1.5 * np.sin(0.05 * np.arange(400)) + rng.uniform(-0.5, 0.5, 400)
    ties = np.arange(1, v_d.size, 7)
    v_d[ties] = v_d[ties - 1]
    t = np.arange(v_d.size) * (1.0 if plant.dt is True else plant.dt)
    u = ct.input_output_response(comp, t, v_d).outputs
    y_lin = ct.forced_response(comp.design_plant, t, v_d).outputs
    y = plant.simulate(u).outputs
    np.testing.assert_allclose(y, y_lin, rtol=0,
                               atol=1e-10 * np.abs(y_lin).max())
    if which == 'paper':
        v = plant.simulate(u, internal=True).outputs[2]
        np.testing.assert_allclose(v[1:], v_d[:-1], rtol=0, atol=1e-12)


def test_compensator_is_ready_for_interconnect():
    plant = sw.examples.paper_plant()
    comp = sw.sandwich_compensator(plant, name='comp')
    series = ct.interconnect([comp, plant], inplist=['v_d'], outlist=['y'])
    v_d = np.sin(0.2 * np.arange(60))
    y = ct.input_output_response(series, np.arange(60), v_d).outputs
    y_lin = ct.forced_response(comp.design_plant, np.arange(60),
                               v_d).outputs
    np.testing.assert_allclose(y, y_lin, rtol=0, atol=1e-10)
    assert comp.input_labels == ['v_d'] and comp.output_labels == ['u']
    assert comp.state_labels[:2] == ['backlash_inverse_x_prev',
                                     'backlash_inverse_v_prev'] or \
        comp.nstates == 2 + comp.L1_inverse.nstates


def test_compensator_for_non_minimum_phase_l1():
    model = sw.SandwichSystem(ct.tf([1.0, -1.6, 0], [1, -0.5, 0.06, 0], 1),
                              sw.Backlash(1, 1, 0.2, 0.2),
                              ct.tf([1.0], [1, -0.5], 1))
    with pytest.raises(ValueError, match="approximate=True"):
        sw.sandwich_compensator(model)
    comp = sw.sandwich_compensator(model, approximate=True)
    assert not comp.is_exact
    assert np.all(np.abs(comp.L1_inverse.poles()) < 1)


@pytest.mark.parametrize('bad, error, match', [
    (dict(model='paper'), TypeError, 'SandwichSystem'),
    (dict(smoothing=-0.1), ValueError, 'smoothing'),
])
def test_compensator_bad_input(bad, error, match):
    kwargs = dict(model=sw.examples.paper_plant())
    kwargs.update(bad)
    with pytest.raises(error, match=match):
        sw.sandwich_compensator(**kwargs)


@pytest.mark.parametrize('args, error, match', [
    ((0.0, 1.2, 0.5, 0.6), ValueError, 'm1 must be a finite number > 0'),
    ((1.0, -1.0, 0.5, 0.6), ValueError, 'm2 must be a finite number > 0'),
    ((1.0, 1.2, -0.5, 0.6), ValueError, 'D1 must be a finite number >= 0'),
])
def test_inverse_rejects_bad_parameters(args, error, match):
    with pytest.raises(error, match=match):
        sw.BacklashInverse(*args)
    with pytest.raises(error, match=match):
        sw.backlash_inverse_response([0.0, 1.0], *args)


def test_inverse_rejects_mismatched_dt_and_wrong_type():
    bl = sw.Backlash(*PAPER, dt=0.1)
    assert sw.backlash_inverse(bl).dt == 0.1
    assert sw.backlash_inverse(sw.Backlash(*PAPER), dt=0.5).dt == 0.5
    with pytest.raises(ValueError, match="same sampling time"):
        sw.backlash_inverse(bl, dt=0.2)
    with pytest.raises(ValueError, match="dt must be"):
        sw.BacklashInverse(*PAPER, dt=0)
    with pytest.raises(TypeError, match="sandwich_compensator"):
        sw.backlash_inverse(sw.examples.paper_plant())


# ----------------------------------------------------------------------
# Closed loop
# ----------------------------------------------------------------------
@pytest.mark.parametrize('compensate', [True, False])
@pytest.mark.parametrize('feedforward', [True, False])
def test_fast_closed_loop_matches_python_control(compensate, feedforward):
    plant = sw.examples.paper_plant()
    model = sw.SandwichSystem.from_theta(
        plant.theta * 1.03, **plant.orders, dt=plant.dt)   # a wrong model
    comp = sw.sandwich_compensator(model) if compensate else None
    P = comp.design_plant if compensate else sw.linearized_plant(model)
    ctrl = sw.tracking_controller(P, feedforward=feedforward)
    r = sw.steps_and_sines(80, levels=(0, 1.0, -0.5), periods=(13, 7))
    fast = sw.closed_loop_response(plant, r, ctrl, comp)
    loop = sw.closed_loop_system(plant, ctrl, comp)
    d = ctrl.preview
    r_ahead = np.concatenate([r[d:], np.full(d, r[-1])])
    slow = ct.input_output_response(loop, np.arange(r.size), r_ahead)
    np.testing.assert_allclose(fast.outputs[:2], slow.outputs, rtol=0,
                               atol=1e-10)


def test_demo_with_the_true_model_is_exact():
    plant = sw.examples.paper_plant()
    demo = sw.closed_loop_demo(plant, plant)
    assert demo.rms_with < 1e-12
    assert 0.1 < demo.rms_without < 0.2
    # and the uncompensated loop is the one the linear design promised
    # only up to the backlash: its error is mostly at reversals
    assert demo.ratio < 1e-10


def test_demo_with_a_realistic_identification_error():
    # 2 % relative error on every parameter of eq. (2.5), seeded; D2 is
    # 2.7 % too large, so the exact inverse over-compensates and u chatters
    plant = sw.examples.paper_plant()
    rng = np.random.default_rng(7)
    model = sw.SandwichSystem.from_theta(
        plant.theta * (1 + 0.02 * rng.standard_normal(plant.theta.size)),
        **plant.orders, dt=plant.dt)
    exact = sw.closed_loop_demo(plant, model)
    robust = sw.closed_loop_demo(plant, model, smoothing=0.02,
                                 band_fraction=0.95)
    assert exact.ratio <= 0.3 and robust.ratio <= 0.3
    assert exact.activity_ratio > 3            # chattering input
    assert robust.activity_ratio < 1.5         # no more active than without
    assert not robust.compensator.is_exact


def test_band_fraction_is_validated():
    plant = sw.examples.paper_plant()
    for bad in (0.0, 1.5):
        with pytest.raises(ValueError, match="band_fraction"):
            sw.sandwich_compensator(plant, band_fraction=bad)
    comp = sw.sandwich_compensator(plant, band_fraction=0.9)
    assert comp.backlash_inverse.D1 == pytest.approx(0.45)
    assert comp.backlash_inverse.D2 == pytest.approx(0.54)


@pytest.mark.parametrize('name', ['a1', 'a2', 'm1', 'm2', 'D1', 'D2'])
@pytest.mark.parametrize('factor', [0.9, 1.1])
def test_demo_with_parameters_off_by_ten_percent(name, factor):
    plant = sw.examples.paper_plant()
    theta = plant.theta.copy()
    theta[plant.theta_labels.index(name)] *= factor
    model = sw.SandwichSystem.from_theta(theta, **plant.orders, dt=plant.dt)
    demo = sw.closed_loop_demo(plant, model)
    assert demo.ratio < 0.8          # compensation still clearly helps
    if name in ('D1', 'D2') and factor < 1:
        assert demo.ratio < 0.1      # an under-estimated band is benign


def test_demo_rejects_mismatched_dt():
    with pytest.raises(ValueError, match="same sampling time"):
        sw.closed_loop_demo(sw.examples.paper_plant(dt=1),
                            sw.examples.paper_plant(dt=0.5))
    ctrl = sw.TrackingController.from_feedback(ct.tf([0.1, 0], [1, -1], 2))
    with pytest.raises(ValueError, match="same sampling time"):
        sw.closed_loop_response(sw.examples.paper_plant(dt=1), [0.0, 1.0],
                                ctrl)
    comp = sw.sandwich_compensator(sw.examples.paper_plant(dt=2))
    with pytest.raises(ValueError, match="same sampling time"):
        sw.closed_loop_response(sw.examples.paper_plant(dt=1), [0.0, 1.0],
                                sw.TrackingController.from_feedback(
                                    ct.tf([0.1, 0], [1, -1], 1)), comp)


def test_tracking_controller_bad_input():
    with pytest.raises(ValueError, match="stable"):
        sw.tracking_controller(ct.tf([1.0], [1, -1.5], 1))
    with pytest.raises(ValueError, match="modulus_margin"):
        sw.tracking_controller(ct.tf([1.0], [1, -0.5], 1), modulus_margin=1)
    with pytest.raises(TypeError, match="TrackingController"):
        sw.closed_loop_response(sw.examples.paper_plant(), [0.0, 1.0],
                                ct.tf([1.0], [1.0], 1))


def test_demo_plot_returns_three_axes():
    plant = sw.examples.paper_plant()
    demo = sw.closed_loop_demo(plant, plant, reference=sw.steps_and_sines(200))
    axs = demo.plot()
    assert len(axs) == 3
    assert 'RMS ratio' in axs[0].get_title()


# ----------------------------------------------------------------------
# The compensator simulates like the plant does
# ----------------------------------------------------------------------
@pytest.mark.parametrize('smoothing, band_fraction', [(0.0, 1.0),
                                                      (0.1, 0.9)])
def test_compensator_simulate_agrees_with_python_control(smoothing,
                                                         band_fraction, rng):
    plant = sw.examples.paper_plant()
    comp = sw.sandwich_compensator(plant, smoothing=smoothing,
                                   band_fraction=band_fraction)
    # stay clear of the slope-line crossing at x = -6.1, where no inverse
    # is exact
    r = np.clip(np.cumsum(0.3 * rng.standard_normal(200)), -3, 3)
    x0 = np.array([0.4, 0.1, 0.2, -0.1])
    fast = comp.simulate(r, initial_state=x0, internal=True)
    slow = ct.input_output_response(comp, np.arange(200), r,
                                    initial_state=x0)
    np.testing.assert_allclose(fast.outputs[0], slow.outputs, rtol=0,
                               atol=1e-12)
    assert fast.output_labels == ['u', 'x_d', 'v_hat']
    # x_d drives the plant's backlash to v_d one delay later
    v = plant.simulate(comp.simulate(r).outputs, internal=True).outputs[2]
    if smoothing == 0 and band_fraction == 1:
        np.testing.assert_allclose(v[1:], r[:-1], atol=1e-12)


def test_compensator_simulate_continues_from_final_state(rng):
    comp = sw.sandwich_compensator(sw.examples.paper_plant(), smoothing=0.05)
    r = rng.standard_normal(100)
    whole = comp.simulate(r).outputs
    first = comp.simulate(r[:40])
    second = comp.simulate(r[40:], initial_state=first.final_state)
    np.testing.assert_array_equal(np.concatenate([first.outputs,
                                                  second.outputs]), whole)


def test_compensator_simulate_labels_and_time():
    plant = sw.SandwichSystem(ct.tf([1.5, 0], [1, 0.1, 0.2], 0.1),
                              sw.Backlash(1, 1.2, 0.5, 0.6),
                              ct.tf([2, -0.1], [1, 1.2, 0.32], 0.1))
    comp = sw.sandwich_compensator(plant, name='comp', inputs='r',
                                   outputs='u_cmd')
    resp = comp.simulate(np.ones(5), timepts=1 + 0.1 * np.arange(5))
    assert resp.output_labels == ['u_cmd'] and resp.input_labels == ['r']
    np.testing.assert_allclose(resp.time, 1 + 0.1 * np.arange(5))
    with pytest.raises(ValueError, match='timepts has spacing 1'):
        comp.simulate(np.ones(5), timepts=np.arange(5))
    step = sw.step_response(comp, amplitude=0.5)
    np.testing.assert_array_equal(
        step.outputs, comp.simulate(np.full(step.time.size, 0.5)).outputs)


@pytest.mark.parametrize('block', ['L1', 'L2'])
def test_integrating_plant_is_compensated(block):
    """A speed command in, a position out: the pole at z = 1 sits in L1
    (the nut integrates the speed before the play) or in L2. The exact
    compensator cancels the play: plant after compensator equals its
    linear design plant (integrator included). With the integrator in
    L1, the design plant is stable and the tracking loop closes."""
    integ, other = [-1.6, 0.6], [-0.5]
    a, c = (integ, other) if block == 'L1' else (other, integ)
    plant = sw.SandwichSystem.from_coefficients(
        a=a, b=[1.0], c=c, d=[1.0, 0.3], m1=1.0, m2=1.1, D1=0.05, D2=0.08,
        dt=0.01)
    poles = np.concatenate([plant.L1.poles(), plant.L2.poles()])
    assert np.min(np.abs(poles - 1)) < 1e-12
    comp = sw.sandwich_compensator(plant)
    v = sw.steps_and_sines(300, levels=(0, 1.0, -0.5), periods=(60, 30))
    y = plant.simulate(comp.simulate(v).outputs).outputs
    y_design = ct.forced_response(comp.design_plant, np.arange(v.size) * 0.01,
                                  v).outputs
    np.testing.assert_allclose(y, y_design, atol=1e-9 * np.max(np.abs(y)))
    if block == 'L1':
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')     # margins of the loop
            demo = sw.closed_loop_demo(plant, plant, reference=v)
        assert np.all(np.isfinite(demo.with_compensation.outputs))
        assert demo.ratio < 0.05


@pytest.mark.parametrize('scale', [1e200, 1e-200])
def test_the_demo_compares_loops_at_any_reference_scale(scale):
    # the RMS errors overflowed to inf (ratio nan) at 1e200 and underflowed
    # to 0 (ratio nan) at 1e-200
    plant = sw.examples.paper_plant()
    demo = sw.closed_loop_demo(plant, plant, scale * sw.steps_and_sines())
    assert np.isfinite(demo.rms_with) and demo.rms_with > 0
    assert np.isfinite(demo.rms_without) and demo.rms_without > 0
    assert np.isfinite(demo.ratio)
