"""A ServoController that refuses an input is left as it was: a failed
reset or step changes nothing, and the next call gives what it would have
on an untouched controller; options are taken as they were meant (numpy's
bools as bools, no int for a bool); the names given to its signals
survive a pickle; a drive too coarse to integrate is refused before it
runs."""

import pickle
import warnings

import numpy as np
import control as ct
import pytest

import sandwichctl as sw

PLANT = sw.examples.paper_plant()
P = ct.tf([0.5, 0.2], [1, -1.1, 0.3], 1)


def _stepped(ctrl, n=20):
    for k in range(n):
        ctrl.step(np.sin(k / 3), 0.1 * k)
    return ctrl


@pytest.mark.parametrize('kwargs', [dict(y=5.0, u=np.nan),
                                    dict(y=np.nan), dict(u='a'),
                                    dict(y=True)])
def test_a_failed_reset_changes_nothing(kwargs):
    ctrl = _stepped(sw.servo_controller(P, operating_point=(2.0, 10.0)))
    twin = _stepped(sw.servo_controller(P, operating_point=(2.0, 10.0)))
    with pytest.raises((TypeError, ValueError)):
        ctrl.reset(**kwargs)
    assert ctrl.operating_point == (2.0, 10.0)
    np.testing.assert_array_equal(ctrl.state, twin.state)
    assert ctrl.step(10.0, 10.0) == twin.step(10.0, 10.0)


def test_an_overflowing_step_or_run_leaves_the_memory_as_it_was():
    ctrl = _stepped(sw.servo_controller(P))
    before = ctrl.state
    with pytest.raises(OverflowError, match='memory is unchanged'):
        for _ in range(4):
            ctrl.step(1e308, -1e308)
    np.testing.assert_array_equal(ctrl.state, before)
    with pytest.raises(OverflowError, match='sample'):
        ctrl.run([1e308] * 4, [-1e308] * 4)
    np.testing.assert_array_equal(ctrl.state, before)
    assert np.isfinite(ctrl.step(0.5, 0.0))


def test_numpy_bools_are_bools_and_ints_are_not():
    off = sw.servo_controller(PLANT, adapt=np.False_, hunting=np.False_)
    assert off.adapts is False and off.hunting is None
    assert off.kp == sw.servo_controller(PLANT, adapt=False).kp
    for value in (0, 1, 1.0):
        with pytest.raises(ValueError, match='adapt'):
            sw.servo_controller(PLANT, adapt=value)
    # a deadband may be any real number, a numpy 0-d array too
    guard = sw.servo_controller(PLANT, hunting=np.array(0.5))
    assert guard.hunting['deadband'] == 0.5


def test_pickling_keeps_the_names_of_the_signals():
    ctrl = _stepped(sw.servo_controller(P, name='axis'))
    ctrl.set_inputs(['ra', 'yy'])
    ctrl.set_outputs(['uu'])
    back = pickle.loads(pickle.dumps(ctrl))
    assert back.input_labels == ['ra', 'yy'] and back.output_labels == ['uu']
    assert back.name == 'axis'
    np.testing.assert_array_equal(back.state, ctrl.state)
    assert back.step(0.3, 1.0) == ctrl.step(0.3, 1.0)


def test_an_overflowing_controller_never_drives_the_plant():
    applied = []

    class Plant:
        dt = 1

        def step(self, u):
            applied.append(u)
            return 0.0

    with pytest.raises(OverflowError, match='not applied to the plant'):
        sw.closed_loop_response(Plant(), np.full(50, 1e308),
                                sw.servo_controller(P))
    assert all(np.isfinite(applied))


def test_a_plant_dt_of_any_numeric_kind_is_compared():
    class Plant:
        def __init__(self, dt):
            self.dt = dt

        def step(self, u):
            return 0.0

    ctrl = sw.servo_controller(P)
    r = np.zeros(5)
    for dt in (np.array(1.0), np.float32(1.0), 1, None, True):
        out = sw.closed_loop_response(Plant(dt), r, ctrl)
        assert out.outputs.shape == (2, 5)
    for dt in (np.array(2.0), [2.0], 0, np.nan):
        with pytest.raises((TypeError, ValueError), match='dt'):
            sw.closed_loop_response(Plant(dt), r, ctrl)


def test_every_random_drive_passes_the_substep_check_and_a_coarse_one_not():
    # the check is far from the family: it never refuses a random drive
    for seed in range(200):
        d = sw.data.random_drive(seed)
        sw.data.ServoDrive(d['loop'], d['play'], d['dt'], seed=0, n=10,
                           **d['params'])
    # a sub-step too coarse for the contact diverged to 1e127, then NaN
    with pytest.raises(ValueError, match='substeps=1 is too few'):
        sw.data.ServoDrive(k=5e10, substeps=1)
    fine = sw.data.ServoDrive(k=5e10, substeps=400, n=300, seed=0)
    y = [fine.step(1e-3) for _ in range(299)]
    assert np.all(np.isfinite(y)) and np.max(np.abs(y)) < 1e-2


def test_a_failed_identification_warns_when_designed_from():
    rng = np.random.default_rng(3)
    u, y = rng.standard_normal(600), rng.standard_normal(600)
    with warnings.catch_warnings():      # the identification's own
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        res = sw.identify(u, y, na=1, nb=0, nc=1, nd=0)
    assert not res.success
    with pytest.warns(sw.IdentificationWarning, match='not a success') as got:
        ctrl = sw.servo_controller(res)
    # once, though the design's checks design again
    assert sum('not a success' in str(w.message) for w in got) == 1
    assert any('not a success' in note for note in ctrl.notes)


def test_a_design_from_a_result_starts_at_rest():
    # the design's checks run the controller around the model and left
    # its memory there: the first step of a fresh design was not zero
    from conftest import paper_data
    plant, u, y = paper_data(2000, seed=5, snr=100)
    res = sw.identify(u, y, **plant.orders)
    for ctrl in (sw.servo_controller(res),
                 sw.servo_controller(res, operating_point=(0.5, 2.0))):
        assert not np.any(ctrl.state)
        u0, y0 = ctrl.operating_point
        first = ctrl.step(y0, y0)
        ctrl.reset()
        assert first == ctrl.step(y0, y0) == u0


def test_a_result_about_offsets_warns_without_an_operating_point():
    # its model is about the record's means: raw values fed to a design
    # at (0, 0) tracked at a travel of error (a review's random case)
    from conftest import paper_data
    plant, u, y = paper_data(2000, seed=6)
    res = sw.identify(u + 3.0, y + 5.0, **plant.orders, offsets='mean')
    with pytest.warns(sw.IdentificationWarning, match='operating_point'):
        sw.servo_controller(res)
    u0, y0 = res.offsets['u'][0], res.offsets['y'][0]
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        ctrl = sw.servo_controller(res, operating_point=(u0, y0))
        sw.servo_controller(sw.identify(u, y, **plant.orders))
    assert ctrl.operating_point == (u0, y0)
