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
    # 1e308 was taken: it sat in the preview's delay line, and every
    # later step overflowed on it (a helper's fuzzing)
    ctrl = _stepped(sw.servo_controller(P))
    before = ctrl.state
    with pytest.raises(ValueError, match='memory is unchanged'):
        ctrl.step(1e308, -1e308)
    np.testing.assert_array_equal(ctrl.state, before)
    with pytest.raises(ValueError, match='at sample 2'):
        ctrl.run([0.5, 0.5, 1e101, 0.5], [0.0] * 4)
    np.testing.assert_array_equal(ctrl.state, before)
    fresh = _stepped(sw.servo_controller(P))
    np.testing.assert_array_equal(
        [ctrl.step(0.5, 0.0) for _ in range(3 * ctrl.preview + 3)],
        [fresh.step(0.5, 0.0) for _ in range(3 * ctrl.preview + 3)])
    # python-control's interface refuses them too, and a state not finite
    t = np.arange(5) * ctrl.dt
    with pytest.raises(ValueError, match='at most'):
        ct.input_output_response(ctrl, t, [[1e308] * 5, [0.0] * 5])
    with pytest.raises(ValueError, match='state must be finite'):
        ct.input_output_response(ctrl, t, [[1.0] * 5, [0.0] * 5],
                                 X0=np.full(ctrl.nstates, np.nan))


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

    # a reference beyond what ctrl.step takes (1e100) is refused before the
    # first sample, as a step of it would be
    with pytest.raises(ValueError, match='reference must be at most'):
        sw.closed_loop_response(Plant(), np.full(50, 1e308),
                                sw.servo_controller(P))
    assert applied == []


def test_an_input_that_overflows_in_the_loop_is_not_applied(monkeypatch):
    # the compiled step returns inf at the third sample: the loop stops
    # with a clear error before handing it to the user's plant
    from sandwichctl.design import loop
    applied, real = [], loop.servo_step

    def stepped(p, ix, s, r_ahead, y):
        return np.inf if len(applied) == 2 else real(p, ix, s, r_ahead, y)

    class Plant:
        dt = 1

        def step(self, u):
            applied.append(u)
            return 0.0

    monkeypatch.setattr(loop, 'servo_step', stepped)
    with pytest.raises(OverflowError, match='u overflowed at sample 2 '
                       r'.*not applied to the plant'):
        sw.closed_loop_response(Plant(), np.ones(10), sw.servo_controller(P))
    assert len(applied) == 2 and np.all(np.isfinite(applied))


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


@pytest.mark.parametrize('gain', [1e-20, 1e16, 1e90])
def test_the_controller_runs_as_designed_at_any_plant_gain(gain):
    # python-control's tf -> ss conversion dropped numerator coefficients
    # below 1e-14: from a plant gain of 1e15 on, the PID and feedforward
    # that ran were not the ones designed, and the loop diverged
    unit = sw.servo_controller(ct.tf([0.1], [1, -0.9], 0.01))
    ctrl = sw.servo_controller(ct.tf([0.1 * gain], [1, -0.9], 0.01))
    r = np.r_[np.zeros(5), np.ones(60)]
    u_unit = np.array([unit.step(rk, 0.0) for rk in r])
    u = np.array([ctrl.step(rk, 0.0) for rk in r])
    np.testing.assert_allclose(u * gain, u_unit, rtol=1e-9, atol=1e-12)
    plant = ct.tf([0.1 * gain], [1, -0.9], 0.01)
    y = sw.closed_loop_response(plant, r, ctrl).outputs[0]
    np.testing.assert_allclose(y[-5:], 1.0, atol=1e-3)


def test_a_sandwich_with_a_tiny_l1_gain_is_the_same_python_control_system():
    L1 = ct.tf([1e-15, 0], [1, -0.5], 0.1)
    L2 = ct.tf([0.5, 0], [1, -0.8], 0.1)
    bl = sw.Backlash(m1=1.0, m2=1.0, D1=1e-16, D2=1e-16)
    plant = sw.SandwichSystem(L1, bl, L2)
    u = np.sin(0.1 * np.arange(100))
    y = plant.simulate(u).outputs
    got = ct.input_output_response(plant, 0.1 * np.arange(100), u).outputs
    np.testing.assert_allclose(got, y, rtol=1e-12, atol=1e-30)
    assert np.max(np.abs(y)) > 0


def test_a_reference_within_the_preview_is_refused():
    # the loop reads r(k + preview): all but r[-1] were dropped silently
    ctrl = sw.servo_controller(PLANT)
    with pytest.raises(ValueError, match='more than'):
        sw.closed_loop_response(PLANT, [1.0] * ctrl.preview, ctrl)
    out = sw.closed_loop_response(PLANT, [0.0] * (ctrl.preview + 1), ctrl)
    assert out.outputs.shape == (2, ctrl.preview + 1)


def test_a_loop_that_diverges_leaves_the_controller_at_rest():
    # its memory was left inf, and every later step raised OverflowError
    ctrl = sw.servo_controller(ct.tf([0.1], [1, -0.9], 1))
    wrong = ct.tf([5.0], [1, -0.9], 1)          # 50 times the model's gain
    with pytest.warns(sw.SimulationWarning, match='diverged'):
        sw.closed_loop_response(wrong, np.ones(2000), ctrl)
    assert np.all(ctrl.state == 0.0)
    assert ctrl.step(0.0, 0.0) == 0.0



def test_servo_metrics_of_large_finite_data_are_finite():
    # the squares overflowed: rms = inf with numpy's RuntimeWarning
    r = np.r_[np.zeros(50), np.ones(400)] * 1e200
    m = sw.servo_metrics(r, 0.999 * r, np.zeros(r.size), 1e-3)
    true = 1e200 * np.sqrt(np.mean((r / 1e200 * 0.001) ** 2))
    assert m['rms'] == pytest.approx(true, rel=1e-12)
    assert np.isfinite(m['near_reversals'])


def test_a_long_preview_of_far_zeros_designs_without_scipys_warning():
    # the preview inverse's leading coefficients, 1.05 ** -1000, were
    # dropped by scipy's normalize with a BadCoefficients warning
    zeros = 1.05 * np.exp(1j * np.linspace(0.2, 2.8, 10))
    num = 0.1 * np.real(np.poly(np.r_[zeros, zeros.conj()]))
    P = ct.tf(num, np.real(np.poly(np.full(21, 0.5))), 0.01)
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        ctrl = sw.servo_controller(P, max_preview=1000)
    assert ctrl.preview > 20 and ctrl.margins['pole_radius'] < 1


@pytest.mark.parametrize('m2, D, noted, warned', [
    (1.2, 0.01, True, False),        # at 5.5 bands, as the paper plant's
    (1.2, 0.0, True, True),          # no band: they cross at zero
    (1.01, 0.01, False, False),      # at 100 bands
    (1.0, 0.01, False, False)])
def test_slope_lines_that_cross_near_zero_are_told(m2, D, noted, warned):
    # beyond the crossing no inverse reaches the outputs between the lines:
    # the exact inverse of a known model tracked there to within their gap
    # (22 % of a unit step for these slopes) without a word
    P = sw.SandwichSystem.from_coefficients(
        a=[0.1, 0.2], b=[1.5], c=[1.2, 0.32], d=[2, -0.1], m1=1, m2=m2,
        D1=D, D2=D, dt=1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        ctrl = sw.servo_controller(P, band_fraction=1.0)
    told = [w for w in caught if 'slope lines cross' in str(w.message)]
    assert len(told) == warned
    notes = [n for n in ctrl.notes if 'slope lines cross' in n]
    assert len(notes) == noted
    if noted:
        x = P.backlash.crossing + 0.0
        assert f"x = {x:.4g} (backlash output v = " in notes[0]
        assert all(issubclass(w.category, sw.SandwichWarning) for w in told)


def test_a_timedelta_is_no_number_and_the_error_names_the_argument():
    # numpy's timedelta64 is an integer type: float() of it failed with
    # "float() argument must be ... not 'datetime.timedelta'"
    ctrl = sw.servo_controller(P)
    with pytest.raises(TypeError, match='y must be a real number'):
        ctrl.step(0.0, np.timedelta64(1, 's'))
    with pytest.raises(TypeError, match='modulus_margin must be a real'):
        sw.servo_controller(P, modulus_margin=np.timedelta64(1))


def test_the_repr_of_a_design_without_a_sample_time_says_so():
    ctrl = sw.servo_controller(ct.tf([0.5, 0.2], [1, -1.1, 0.3], True))
    assert ctrl.dt is True and 'dt=True,' in repr(ctrl)
    assert 'dt=1,' in repr(sw.servo_controller(P))


@pytest.mark.parametrize('share', [None, 0.0, 0.5, 1.0])
def test_a_pd_around_a_play_before_an_integrator_tells_its_dead_zone(share):
    # the default quarter of a large band left holds 3 from the reference
    # on the model itself, and nothing said why
    P = sw.SandwichSystem.from_coefficients(
        a=[0.1, 0.2], b=[1.5], c=[-1.0], d=[2, -0.1], m1=1, m2=1.2, D1=0.5,
        D2=0.6, dt=1)
    kw = {} if share is None else dict(band_fraction=share)
    ctrl = sw.servo_controller(P, **kw)
    assert ctrl.ki == 0
    r = np.r_[np.zeros(20), np.ones(300), -np.ones(300), np.zeros(300)]
    y = sw.closed_loop_response(P, r, ctrl).outputs[0]
    stuck = max(abs(y[k] - r[k]) for k in (319, 619, 919))
    note, = [n for n in ctrl.notes if n.startswith('backlash inverse')]
    if ctrl.band_fraction == 1.0:
        assert 'may stop' not in note and stuck < 1e-9
    else:
        bound = float(note.split('may stop up to ')[1].split()[0])
        assert 0.3 * bound < stuck <= bound
