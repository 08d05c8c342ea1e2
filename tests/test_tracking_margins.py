"""The tracking controller's gain margin is the factor on the loop gain
that makes the loop unstable: python-control's took the PI's integrator
at z = 1 for a phase crossover (1e-16 on a first-order plant)."""

import warnings

import numpy as np
import control as ct
import pytest

import sandwichctl as sw

PLANT = sw.examples.paper_plant()


@pytest.mark.parametrize('P', [ct.tf([1], [1, -0.5], 1),
                               ct.tf([0.5], [1, -0.8], 1),
                               ct.tf([0.1], [1, -1], 1),
                               PLANT.L1 * PLANT.L2])
def test_the_gain_margin_is_where_the_loop_turns_unstable(P):
    ctrl = sw.tracking_controller(P)
    gm = ctrl.margins[0]
    assert 1.5 < gm < 1e3
    loop = ctrl.feedback * P
    radius = [np.max(np.abs(ct.feedback(f * gm * loop, 1).poles()))
              for f in (0.98, 1.02)]
    assert radius[0] < 1 < radius[1]
    # the servo controller reads the same crossing at the Nyquist frequency
    servo = sw.servo_controller(P) if P is not PLANT.L1 * PLANT.L2 else None
    if servo is not None and np.isfinite(servo.margins['gain']):
        L = servo.pid * servo.design_plant
        g = servo.margins['gain']
        assert np.max(np.abs(ct.feedback(1.02 * g * L, 1).poles())) > 1


def test_a_controller_from_feedback_prints_its_margins():
    comp = sw.sandwich_compensator(PLANT)
    ctrl = sw.TrackingController.from_feedback(ct.tf([0.2, 0], [1, -1], 1),
                                               comp.design_plant)
    text = repr(ctrl)
    assert 'feedback=' in text and 'gain_margin=' in text
    assert ctrl.kp is None and np.isfinite(ctrl.margins[0])


def test_a_plant_of_too_many_poles_is_refused_with_the_remedy():
    # 200 samples of delay took 170 s in the grid search (900: 37 GiB)
    P = ct.tf([1.0], np.r_[1.0, -0.5, np.zeros(200)], 1)
    with pytest.raises(ValueError,
                       match='at most 100 poles.*servo_controller'):
        sw.tracking_controller(P)


def test_the_phase_margin_is_the_angle_to_minus_one_without_warnings():
    """Around a lightly damped resonance python-control wrapped the margin
    of a gain crossover at +128 deg to -52 deg, for a stable loop that
    meets its modulus margin; and on ordinary plants it warned of its
    'frd' fallback. The margins are read on the log grid."""
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        ctrl = sw.tracking_controller(ct.tf([1], [1, 0, 0.99], 1))
        for P in (ct.tf([0.001], [1, -0.999], 1),
                  ct.tf([1], np.poly(np.full(12, 0.5)), 1)):
            sw.tracking_controller(P)
    gm, pm, sm = ctrl.margins[:3]
    assert ctrl.pole_radius < 1 and sm >= 0.6 - 1e-3
    assert 51 < pm < 53
    L = ctrl.feedback * ct.tf([1], [1, 0, 0.99], 1)
    w = np.linspace(1e-3, np.pi, 200001)
    Lw = L(np.exp(1j * w))
    cross = np.flatnonzero(np.diff(np.sign(np.abs(Lw) - 1)) != 0)
    assert np.isclose(pm, np.min(180 - np.degrees(np.abs(np.angle(
        Lw[cross])))), atol=0.2)


def test_an_unstable_loop_has_a_negative_phase_margin():
    """The phase margin read as the angle to -1 is negated where the
    closed loop is unstable (a crossing past -180 deg): a feedback given
    to from_feedback that leaves the loop unstable is not reported with a
    healthy margin."""
    tc = sw.TrackingController.from_feedback(ct.tf([0.8, 0], [1, -1], 1),
                                             ct.tf([1], [1, -0.5, 0], 1))
    assert tc.pole_radius > 1
    assert tc.margins[1] == pytest.approx(-25.3, abs=0.1)


@pytest.mark.parametrize('change, error, match', [
    (dict(preview=-1), ValueError, 'preview must be an integer >= 0'),
    (dict(preview=2.0), TypeError, 'preview must be an integer'),
    (dict(preview='2'), TypeError, 'preview must be an integer'),
    (dict(kp='a'), TypeError, 'kp must be a real number'),
    (dict(feedforward=ct.tf([1.0], [1, 0], 0.5)), ValueError,
     'feedback and feedforward must have the same sampling time')])
def test_a_tracking_controller_built_by_hand_checks_its_parts(change, error,
                                                              match):
    # they failed later, inside closed_loop_response ("negative dimensions
    # are not allowed", "Unknown format code 'g'")
    c = sw.tracking_controller(sw.sandwich_compensator(PLANT).design_plant)
    parts = dict(feedback=c.feedback, feedforward=c.feedforward,
                 preview=c.preview, design_plant=c.design_plant, kp=c.kp,
                 ki=c.ki)
    assert sw.TrackingController(**parts).preview == c.preview
    with pytest.raises(error, match=match):
        sw.TrackingController(**dict(parts, **change))
