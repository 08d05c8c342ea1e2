"""Real-data forms (issue 13): python-control records, several experiments
and offsets, for identify, identify_linear and refine."""

import warnings

import numpy as np
import pytest
import control as ct

import sandwichctl as sw


@pytest.fixture(scope='module')
def two_runs():
    plant = sw.examples.paper_plant(dt=0.01)
    runs = []
    for seed in (31, 32):
        u = sw.examples.paper_input(1500, seed=seed)
        y = sw.examples.add_noise(plant.simulate(u).outputs, 200,
                                  seed=seed + 100)
        runs.append((u, y))
    return plant, runs


def _record(u, y, dt):
    return ct.TimeResponseData(dt * np.arange(u.size), y, inputs=u)


def test_record_gives_dt(two_runs):
    plant, runs = two_runs
    res = sw.identify(_record(*runs[0], 0.01), **plant.orders)
    assert res.success and res.model.dt == pytest.approx(0.01)
    ref = sw.identify(*runs[0], **plant.orders)
    assert res.fit == pytest.approx(ref.fit, abs=1e-9)


def test_several_experiments_sum_their_costs(two_runs):
    plant, runs = two_runs
    res = sw.identify([_record(u, y, 0.01) for u, y in runs], **plant.orders)
    assert res.success and res.n_experiments == 2
    assert sw.parameter_error(res.theta, plant.theta) < 0.02
    cost = sum(0.5 * np.sum((y - res.model.simulate(u).outputs) ** 2)
               for u, y in runs)
    assert res.cost == pytest.approx(cost, rel=1e-9)
    assert res.cost <= res.linear['cost'] * (1 + 1e-9)
    lin = sw.identify_linear(runs, nb=2, nf=4, nk=2)
    assert lin.success and lin.n_experiments == 2
    ref = sw.refine(res.model, runs)
    assert ref.cost <= res.cost * (1 + 1e-9)


@pytest.mark.parametrize('data, match', [
    (lambda r: [_record(*r[0], 0.01), _record(*r[1], 0.02)],
     'share the sampling time'),
    (lambda r: ct.TimeResponseData(np.r_[0, np.cumsum(np.ones(1499))
                                         * 0.01 * (1 + 0.1 * (
                                             np.arange(1499) == 7))],
                                   r[0][1], inputs=r[0][0]),
     'not evenly spaced'),
    (lambda r: [(r[0][0], r[0][1][:-1])], 'same length'),
    (lambda r: [(r[0][0], np.r_[r[0][1][:-1], np.nan])], 'finite'),
    (lambda r: [], 'empty'),
])
def test_bad_records_are_refused(two_runs, data, match):
    plant, runs = two_runs
    with pytest.raises(ValueError, match=match):
        sw.identify(data(runs), **plant.orders)


def test_continuous_time_and_positional_orders_are_refused(two_runs):
    plant, runs = two_runs
    with pytest.raises(ValueError, match='continuous-time'):
        sw.identify(*runs[0], **plant.orders, dt=0)
    with pytest.raises(TypeError, match='by keyword'):
        sw.identify(_record(*runs[0], 0.01), 2, 0, 2, 1)
    with pytest.raises(ValueError, match='offsets must be one of'):
        sw.identify(*runs[0], **plant.orders, offsets='detrend')


def test_offsets_mean_and_estimate(two_runs):
    plant, runs = two_runs
    u, y = runs[0]
    u_off, y_off = u + 3.0, y - 40.0
    # 'mean' removes the means and says so
    res = sw.identify(u_off, y_off, **plant.orders, offsets='mean')
    assert res.offsets['method'] == 'mean'
    assert res.offsets['u'][0] == pytest.approx(u_off.mean())
    assert res.offsets['y'][0] == pytest.approx(y_off.mean())
    # 'estimate' fits the output offset with the input as given
    res = sw.identify(u, y_off, **plant.orders, offsets='estimate')
    assert res.success and res.offsets['method'] == 'estimate'
    assert res.offsets['y'][0] == pytest.approx(-40.0, abs=0.5)
    y_hat = res.model.simulate(u).outputs + res.offsets['y'][0]
    assert sw.fit_percent(y_off, y_hat) == pytest.approx(res.fit, abs=1e-6)
    # without it, the same data fit far worse
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        none = sw.identify(u, y_off, **plant.orders)
    assert none.offsets['method'] == 'none' and none.fit < res.fit - 5
    lin = sw.identify_linear(u, y_off, nb=2, nf=4, nk=2, offsets='estimate')
    assert lin.offsets['y'][0] == pytest.approx(-40.0, abs=1.0)


def test_compare_takes_records_and_experiments(two_runs):
    plant, runs = two_runs
    one = sw.compare(plant, _record(*runs[0], 0.01), plot=False)
    assert one.fit == pytest.approx(sw.compare(plant, *runs[0],
                                               plot=False).fit)
    both = sw.compare(plant, [_record(u, y, 0.01) for u, y in runs],
                      plot=False, horizon=1)
    assert len(both) == 2 and all(r.fit > 80 and r.horizon == 1 for r in both)


def test_initial_state_estimate_recovers_a_plant_not_at_rest():
    """A slow plant whose record starts away from rest: estimating the
    past values (L1, backlash memory, L2) recovers it exactly; assuming
    rest does not."""
    plant = sw.SandwichSystem.from_coefficients(
        a=[-0.9], b=[1.0], c=[-1.6, 0.68], d=[0.5, 0.3], m1=1, m2=1.2,
        D1=0.3, D2=0.2, q1=1, q2=1)
    u = sw.examples.paper_input(1500, seed=3)
    x0 = 2 * np.random.default_rng(1).standard_normal(plant.nstates)
    y = plant.simulate(u, initial_state=x0).outputs
    zero = sw.identify(u, y, **plant.orders)
    est = sw.identify(u, y, **plant.orders, initial_state='estimate')
    assert sw.parameter_error(est.theta, plant.theta) < 1e-6
    assert est.fit > 99.999 and zero.fit < 99
    (ic,) = est.initial_conditions
    assert ic['x_past'].size == 1 and ic['v_past'].size == 2
    assert ic['y_past'].size == 2
    with pytest.raises(ValueError, match='initial_state'):
        sw.identify(u, y, **plant.orders, initial_state='guess')


@pytest.fixture(scope='module')
def pair():
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(1000, seed=3)
    y = sw.examples.add_noise(plant.simulate(u).outputs, 100, seed=4)
    return plant, (u, y)


def test_a_u_y_tuple_works_at_every_entry_point(pair):
    """`as_experiments` reads one (u, y) pair, and every entry point reads
    its data through it."""
    plant, (u, y) = pair
    data = sw.as_experiments((u, y))
    assert len(data) == 1 and data.dt is True
    np.testing.assert_array_equal(data.u[0], u)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        res = sw.identify((u, y), **plant.orders)
        np.testing.assert_array_equal(
            res.theta, sw.identify(u, y, **plant.orders).theta)
        assert sw.identify_linear((u, y), nb=3, nf=4, nk=2).model is not None
        assert sw.refine(plant, (u, y)).success
        assert sw.compare(plant, (u, y), plot=False).fit > 80
        assert sw.residuals(plant, (u, y), plot=False) is not None
        table = sw.select_structure((u, y), orders=[(2, 0, 2, 1)],
                                    include_linear=False)
        assert table.best['success']
        many, = sw.identify_many([(u, y)], **plant.orders, processes=1)
        np.testing.assert_array_equal(many.theta, res.theta)


def test_a_pair_of_columns_is_one_experiment():
    # (u[:, None], y[:, None]) was read as two experiments of one array
    # each, while [(u[:, None], y[:, None])] was one
    u = np.random.default_rng(0).standard_normal(50)
    y = 2 * u
    for data in ((u[:, None], y[:, None]), [(u[:, None], y[:, None])]):
        exps = sw.as_experiments(data)
        assert len(exps) == 1
        np.testing.assert_array_equal(exps.u[0], u)
        np.testing.assert_array_equal(exps.y[0], y)


def test_lists_of_arrays_for_u_and_y_say_how_to_give_experiments():
    # identify([u1, u2], [y1, y2]) with records of different lengths
    # raised numpy's "inhomogeneous shape" ValueError
    u = np.random.default_rng(1).standard_normal(60)
    y = np.cumsum(u)
    for uu, yy in (([u, u[:40]], [y, y[:40]]), ([u, u], [y, y]),
                   (u, [y, y])):
        with pytest.raises(TypeError, match=r'list of \(u, y\) pairs'):
            sw.as_experiments(uu, yy)
    with pytest.raises(TypeError, match='lists of 2 arrays'):
        sw.identify_linear([u, u[:40]], [y, y[:40]], nb=1, nf=1, nk=1)
    # a plain list of numbers is still one signal
    assert len(sw.as_experiments(list(u), list(y))) == 1


def test_experiments_built_by_hand_are_checked_and_keep_their_dt():
    # the constructor took anything, and identify then read dt=True
    u = sw.examples.paper_input(400, seed=2)
    y = sw.examples.paper_plant(dt=0.1).simulate(u).outputs
    data = sw.Experiments([(u, y), (u[:300], y[:300])], 0.1)
    assert len(data) == 2 and data.dt == 0.1 and data.n_samples == 700
    assert sw.as_experiments(data).dt == 0.1
    res = sw.identify_linear(data, nb=1, nf=2, nk=1)
    assert res.model.dt == 0.1
    with pytest.raises(ValueError, match='same length'):
        sw.Experiments([(u, y[:10])], 0.1)


def test_absolute_epoch_times_are_evenly_spaced():
    """Times logged as Unix epoch seconds (1.7e9) carry 2.4e-7 s of
    rounding, which the spacing check took for an uneven record."""
    u = np.random.default_rng(0).standard_normal(600)
    y = np.convolve(u, [0, 0.5, 0.25])[:600]
    rec = ct.TimeResponseData(1.7e9 + 0.001 * np.arange(600), y, inputs=u)
    assert sw.as_experiments(rec).dt == 0.001
    # on a short record the times' rounding leaves the mean step closer
    # than a rounding to 6 digits would
    short = 1.7e9 + 0.0012345 * np.arange(20)
    got = sw.as_experiments(ct.TimeResponseData(short, u[:20],
                                                inputs=u[:20])).dt
    assert got == pytest.approx(0.0012345, rel=1e-5)
    t = 1.7e9 + 0.001 * np.arange(600)
    t[300] += 0.0004
    with pytest.raises(ValueError, match="not evenly spaced"):
        sw.as_experiments(ct.TimeResponseData(t, y, inputs=u))


def test_experiments_built_from_one_record_or_one_pair_read_them_whole():
    # list() of a record gave (time, outputs): the time vector became u
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(400, seed=1)
    y = plant.simulate(u).outputs
    record = ct.TimeResponseData(0.01 * np.arange(u.size), y, inputs=u)
    data = sw.Experiments(record, None)
    assert len(data) == 1 and data.dt == 0.01
    np.testing.assert_array_equal(data[0][0], u)
    pair = sw.Experiments((u, y), 0.1)
    assert len(pair) == 1 and pair.dt == 0.1
    np.testing.assert_array_equal(pair[0][1], y)


def test_refine_as_an_empty_dict_refines_with_the_defaults():
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(1500, seed=1)
    y = plant.simulate(u).outputs
    got = [sw.identify(u, y, **plant.orders, method='bundle', refine=r)
           for r in ({}, True)]
    assert got[0].method == got[1].method == 'bundle+refine'
    np.testing.assert_array_equal(got[0].theta, got[1].theta)
    # and False, the documented default, is no error for 'oe'
    assert sw.identify(u[:600], y[:600], **plant.orders,
                       refine=False).success
