"""The hunting guard of ServoController (servo_controller's `hunting`):
reversals of y in a hold, or of the error in a move, scale the feedback's
gains down."""

import pickle
import types
import warnings

import numpy as np
import control as ct
import pytest

import sandwichctl as sw
from sandwichctl.design import _servo_guard as sg
from sandwichctl.design._servo_kernel import EARLY, MOTION_TURNS
from sandwichctl.tools.residuals import noise_level

PLANT = ct.tf([0.02, 0.01], np.polymul([1, -0.95], [1, -0.6]), 1e-3)


def _guarded(deadband=0.1, **kw):
    return sw.servo_controller(PLANT, hunting=deadband, **kw)


def _hold_then_swing(ctrl, amplitude, swings, period=10, start=None):
    """(r_ahead, y): a hold at 0 where y swings between +-amplitude
    `swings` times, each `period` samples, from `start` samples in (by
    default the guard's settle)."""
    start = int(ctrl.hunting['settle']) + 5 if start is None else start
    n = start + period * (swings + 2)
    y = np.zeros(n)
    for j in range(swings + 1):
        y[start + j * period:] = amplitude * (-1) ** j
    return np.zeros(n), y


def _marks(times, n):
    """A hold at 0 where y steps between +-0.2 at the given samples."""
    y = np.zeros(n)
    for j, t in enumerate(times):
        y[t:] = 0.2 * (-1) ** j
    return np.zeros(n), y


def test_every_three_reversals_in_a_hold_scale_the_gains():
    ctrl = _guarded()
    gap = ctrl.hunting['gap']
    assert ctrl.hunting == dict(deadband=0.1, settle=ctrl.hunting['settle'],
                                beta=sg.BETA, floor=sg.FLOOR, gap=gap)
    assert gap > 10
    # the first move sets a direction; each later swing is a reversal
    for swings, gain in ((2, 1.0), (3, 0.6), (6, 0.36), (9, 0.25),
                         (30, 0.25)):
        ctrl.reset()
        ctrl.run(*_hold_then_swing(ctrl, 0.2, swings))
        assert ctrl.feedback_gain == pytest.approx(gain)
    ctrl.reset()
    assert ctrl.feedback_gain == 1.0
    # swings inside the deadband, or before the early window (the step's
    # overshoot), are not hunting
    ctrl.run(*_hold_then_swing(ctrl, 0.04, 30))
    ctrl.reset()
    ctrl.run(*_hold_then_swing(ctrl, 0.2, 8, period=3, start=0))
    assert EARLY * ctrl.hunting['settle'] > 8 * 3 + 1
    assert ctrl.feedback_gain == 1.0
    # while the reference moves, it takes MOTION_TURNS reversals of the
    # error in a row (a tracking loop's error turns with the reference)
    for swings, gain in ((MOTION_TURNS - 1, 1.0), (MOTION_TURNS, 0.6),
                         (2 * MOTION_TURNS, 0.36)):
        ctrl.reset()
        r, y = _hold_then_swing(ctrl, 0.2, swings)
        ctrl.run(np.arange(r.size) * 1e-3, y)
        assert ctrl.feedback_gain == pytest.approx(gain)
    # the count restarts where r turns: a reference that jitters turns
    # the error at every sample, and that is not the loop hunting
    ctrl.reset()
    k = np.arange(4000)
    ctrl.run(1e-3 * k + 0.2 * (-1) ** k, np.zeros(k.size))
    assert ctrl.feedback_gain == 1.0
    # nor are reversals slower than `gap` samples apart (a load that
    # friction holds, broken free by the integrator), however many
    ctrl.reset()
    ctrl.run(*_hold_then_swing(ctrl, 0.2, 30, period=int(gap) + 1))
    assert ctrl.feedback_gain == 1.0
    ctrl.reset()
    ctrl.run(*_hold_then_swing(ctrl, 0.2, 3, period=int(gap)))
    assert ctrl.feedback_gain == pytest.approx(0.6)
    # once the gains are scaled by c the loop is slower, and reversals
    # within gap / c samples count
    slower = int(gap / sg.BETA) - 1
    assert slower > gap
    for period, gain in ((slower + 3, 0.6), (slower, 0.36)):
        r, y = _hold_then_swing(ctrl, 0.2, 3, period=10)
        y = np.r_[y, y[-1] * (-1) ** (np.arange(4 * period) // period + 1)]
        ctrl.reset()
        ctrl.run(np.zeros(y.size), y)
        assert ctrl.feedback_gain == pytest.approx(gain)
    # a slow reversal restarts the count: two fast ones, a slow one, two
    # fast ones leave the gains; a third fast one scales them
    start = int(ctrl.hunting['settle']) + 5
    gaps = [10, 10, int(gap) + 5, 10, 10]
    times = start + np.cumsum([0] + gaps)
    for extra, gain in ((0, 1.0), (1, 0.6)):
        marks = np.r_[times, times[-1] + 10] if extra else times
        ctrl.reset()
        ctrl.run(*_marks(marks, marks[-1] + 20))
        assert ctrl.feedback_gain == pytest.approx(gain)


def test_an_early_window_catches_a_hunt_that_starts_with_the_hold():
    # random drive 72's linear design hunts from a hold's start; from EARLY
    # settle samples in, 3 reversals in a row scale the gains before the
    # settle, and that window's count is dropped at the settle
    ctrl = _guarded()
    settle = int(ctrl.hunting['settle'])
    early = int(np.ceil(EARLY * settle))     # sample k is t = k + 1 in
    n = settle + 60
    fast = [early, early + 6, early + 12]
    later = [settle + 4, settle + 10, settle + 16, settle + 22]
    assert early + 18 < settle - 2
    assert settle + 4 - (early + 12) <= ctrl.hunting['gap']
    for times, gain in ((fast + [early + 18], 0.6),     # 3 in the window
                        ([t - 6 for t in fast], 1.0),   # 2 of them in it
                        (fast + later[:2], 1.0),        # dropped: 2, then 1
                        (fast + later, 0.6)):           # 3 after the settle
        ctrl.reset()
        ctrl.run(*_marks(times, n))
        assert ctrl.feedback_gain == pytest.approx(gain), times


def test_the_guard_scales_the_error_so_the_input_does_not_jump():
    # feedback only: u = C(z) [c(k) e(k)], with c dropping to 0.6 at the
    # third reversal; the PID's states carry over, so u does not jump
    ctrl = _guarded(feedforward=None)
    r, y = _hold_then_swing(ctrl, 0.2, 3)
    y += 0.5                    # a standing error the integrator holds
    u = ctrl.run(r, y)
    plain = sw.servo_controller(PLANT, hunting=False, feedforward=None)
    fired = np.flatnonzero(u != plain.run(r, y))[0]
    assert ctrl.feedback_gain == pytest.approx(0.6)
    c = np.where(np.arange(r.size) < fired, 1.0, 0.6)
    expected = ct.forced_response(ctrl.pid, U=c * (r - y)).outputs
    np.testing.assert_allclose(u, expected, rtol=1e-9, atol=1e-9)


def test_the_guard_stops_a_heavy_drive_that_coasts_from_hunting():
    # random drive 53 of bench_servo.py: 49 kg, little Coulomb friction and
    # 211 um of play; the linear design hunts in every hold without the
    # guard (8 reversals, 40.6 um) and not with it (21.5 um)
    d = sw.data.random_drive(53)
    loop, play, dt, params = d['loop'], d['play'], d['dt'], d['params']
    u = sw.data.drive_reference(int(round(5.0 / dt)), loop, rng=153, dt=dt)
    y = sw.data.servo_drive(u, loop, play, dt, seed=1153, **params)
    lin = sw.identify_linear(u, y, nb=3, nf=4, nk=1, dt=dt)
    r = sw.servo_reference(dt, 1e-3)
    got = {}
    for hunting in (False, None):
        ctrl = sw.servo_controller(lin, hunting=hunting)
        drive = sw.data.ServoDrive(loop, play, dt, seed=653, n=r.size,
                                   **params)
        out = sw.closed_loop_response(drive, r, ctrl)
        got[hunting] = (sw.servo_metrics(r, *out.outputs, dt,
                                         deadband=1.5 * params['resolution']),
                        ctrl.feedback_gain)
    (m_off, c_off), (m_on, c_on) = got[False], got[None]
    assert c_off == 1.0 and m_off['hunting'] >= 3
    assert c_on < 1.0 and m_on['hunting'] < 3
    assert m_on['rms'] < 0.75 * m_off['rms']
    deadband = sg.DEADBAND * noise_level(lin.residuals)
    assert sw.servo_controller(lin).hunting['deadband'] == deadband


def test_the_guard_keeps_quiet_where_the_loop_does_not_hunt():
    # a play-free drive: the design with the guard is the one without it
    case = sw.data.drive_case(0, 'position', 0.0, n=3000)
    lin = sw.identify_linear(case.u, case.y, nb=3, nf=4, nk=1, dt=case.dt)
    r = sw.servo_reference(case.dt, 1e-3)[:4000]
    outs = []
    for hunting in (None, False):
        ctrl = sw.servo_controller(lin, hunting=hunting)
        drive = sw.data.ServoDrive('position', 0.0, seed=1, n=r.size)
        outs.append(sw.closed_loop_response(drive, r, ctrl).outputs)
    assert ctrl.hunting is None
    np.testing.assert_array_equal(outs[0], outs[1])


def test_which_models_get_the_guard():
    # a model without a record has no noise level: no guard, and a note
    ctrl = sw.servo_controller(PLANT)
    assert ctrl.hunting is None and ctrl.feedback_gain == 1.0
    assert any('no hunting guard' in n for n in ctrl.notes)
    # an identification result's record gives the deadband
    result = types.SimpleNamespace(model=PLANT, success=True,
                                   linear=dict(model=PLANT, noise=1e-3))
    ctrl = sw.servo_controller(result)
    assert ctrl.hunting['deadband'] == pytest.approx(sg.DEADBAND * 1e-3)
    assert any('hunting guard: in a hold' in n for n in ctrl.notes)
    assert sw.servo_controller(result, hunting=False).hunting is None
    # the settle is SETTLE time constants of the crossover
    num, den = PLANT.num[0][0], PLANT.den[0][0]
    wc = sw.design._servo_design.crossover(num, den, ctrl.pid)
    assert ctrl.hunting['settle'] == np.ceil(sg.SETTLE / wc)


@pytest.mark.parametrize('hunting, error, match', [
    ('loud', TypeError, 'hunting must be'),
    (np.array([0.1]), TypeError, 'hunting must be'),
    (-0.1, ValueError, 'hunting'),
    (0.0, ValueError, 'hunting'),
    (np.nan, ValueError, 'hunting'),
    (np.inf, ValueError, 'hunting'),
    (True, ValueError, 'needs an identification result'),
])
def test_bad_hunting(hunting, error, match):
    with pytest.raises(error, match=match):
        sw.servo_controller(PLANT, hunting=hunting)


def test_the_guard_pickles_with_its_scale_and_reset_restores_it():
    ctrl = _guarded()
    ctrl.run(*_hold_then_swing(ctrl, 0.2, 3))
    back = pickle.loads(pickle.dumps(ctrl))
    assert back.feedback_gain == ctrl.feedback_gain == pytest.approx(0.6)
    assert back.hunting == ctrl.hunting
    r, y = np.zeros(50), np.linspace(0, 0.1, 50)
    np.testing.assert_array_equal(back.run(r, y), ctrl.run(r, y))
    back.reset()
    assert back.feedback_gain == 1.0


def test_the_floor_is_where_the_loop_still_holds(monkeypatch):
    # a plant whose loop is conditionally stable: lower gains destabilise
    # it, so the guard stops above them (or is off)
    calls = []

    def radius(num, den, C):
        gain = float(np.real(C.num[0][0][0] / ctrl0.pid.num[0][0][0]))
        calls.append(gain)
        return 0.9 if gain > 0.5 else 1.1
    ctrl0 = _guarded()
    monkeypatch.setattr(sg, 'loop_radius', radius)
    ctrl = _guarded()
    assert ctrl.hunting['floor'] == pytest.approx(0.6)
    assert any('down to 0.6' in n for n in ctrl.notes)
    monkeypatch.setattr(sg, 'loop_radius', lambda *a: 1.5)
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        off = _guarded()
    assert off.hunting is None
    assert any('no hunting guard: the loop is unstable' in n
               for n in off.notes)
