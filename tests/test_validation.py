"""Tests of the validation measures and `compare` against hand values."""

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest

import sandwichctl as sw


@pytest.fixture
def plant():
    return sw.examples.paper_plant()


# --- fit_percent / nrmse -------------------------------------------------

@pytest.mark.parametrize('y, yhat, expected', [
    # ||y - yhat|| = 1, ||y - mean|| = sqrt(2)
    ([1.0, 2.0, 3.0], [1.0, 2.0, 4.0], 1 / np.sqrt(2)),
    # error is half the signal: NRMSE 0.5
    ([0.0, 1.0, 0.0, -1.0], [0.0, 0.5, 0.0, -0.5], 0.5),
    # predicting the mean: NRMSE 1
    ([1.0, 3.0, 5.0], [3.0, 3.0, 3.0], 1.0),
    # perfect
    ([2.0, -1.0, 7.0], [2.0, -1.0, 7.0], 0.0),
    # sign flip of a zero-mean signal: ||2y|| / ||y|| = 2
    ([1.0, -1.0, 2.0, -2.0], [-1.0, 1.0, -2.0, 2.0], 2.0),
])
def test_nrmse_and_fit_hand_values(y, yhat, expected):
    np.testing.assert_allclose(sw.nrmse(y, yhat), expected, rtol=1e-15,
                               atol=0)
    np.testing.assert_allclose(sw.fit_percent(y, yhat),
                               100 * (1 - expected), rtol=1e-13, atol=1e-13)


def test_fit_is_offset_invariant(rng):
    y = rng.standard_normal(200)
    yhat = y + 0.1 * rng.standard_normal(200)
    np.testing.assert_allclose(sw.fit_percent(y + 10, yhat + 10),
                               sw.fit_percent(y, yhat), rtol=1e-12)


def test_accepts_column_vectors():
    y = np.array([[1.0], [2.0], [3.0]])
    assert sw.nrmse(y, y.T) == 0.0


@pytest.mark.parametrize('func', [sw.nrmse, sw.fit_percent,
                                  sw.max_relative_error])
def test_shape_mismatch_is_rejected(func):
    with pytest.raises(ValueError, match=r"same number of samples; got 3 "
                                         r"and 2"):
        func([1.0, 2.0, 3.0], [1.0, 2.0])


@pytest.mark.parametrize('func', [sw.nrmse, sw.fit_percent,
                                  sw.max_relative_error])
@pytest.mark.parametrize('which', ['y', 'yhat'])
def test_nan_is_rejected(func, which):
    good, bad = [1.0, 2.0, 3.0], [1.0, np.nan, 3.0]
    args = (bad, good) if which == 'y' else (good, bad)
    with pytest.raises(ValueError, match=rf"{which} must be finite; "
                                         r"sample 1 is nan"):
        func(*args)


def test_two_dimensional_signal_is_rejected():
    with pytest.raises(ValueError, match=r"y must be a 1-D array"):
        sw.nrmse(np.ones((3, 2)), np.ones((3, 2)))


@pytest.mark.parametrize('func', [sw.nrmse, sw.fit_percent])
def test_constant_y_is_rejected(func):
    with pytest.raises(ValueError, match=r"y is constant"):
        func([2.0, 2.0, 2.0], [1.0, 2.0, 3.0])


def test_norms_at_the_ends_of_the_float_range_stay_finite():
    # each norm is taken in units of its own largest entry: a y of 1e-300
    # against a yhat of 1 squared its error to inf, and a theta of 1e200
    # did too
    y = np.linspace(0.0, 1.0, 50)
    tiny = y * 1e-300
    assert sw.nrmse(tiny, np.ones(50)) == pytest.approx(
        np.sqrt(50) / np.linalg.norm(y - y.mean()) * 1e300, rel=1e-12)
    assert np.isfinite(sw.fit_percent(tiny, np.ones(50)))
    assert sw.nrmse(tiny, tiny * 1.01) == pytest.approx(
        sw.nrmse(y, y * 1.01), rel=1e-12)
    theta = np.array([0.5, -0.2, 1.0, 3.0])
    assert sw.parameter_error(theta * 1e200, theta) == pytest.approx(
        1e200, rel=1e-12)
    assert sw.parameter_error(theta, theta * 1e-300) == pytest.approx(
        1e300, rel=1e-12)
    assert sw.parameter_error(theta * 1e-300 * 1.1, theta * 1e-300) == \
        pytest.approx(0.1, rel=1e-12)
    # a diverged estimate in a history: nan or inf for its row, no warning
    rows = np.vstack([theta, 1.1 * theta, np.r_[np.nan, theta[1:]],
                      np.r_[np.inf, theta[1:]]])
    got = sw.parameter_error(rows, theta)
    assert got[:2] == pytest.approx([0.0, 0.1])
    assert np.isnan(got[2]) and got[3] == np.inf


# --- max_relative_error --------------------------------------------------

def test_max_relative_error_hand_values():
    y = [1.0, -2.0, 4.0]
    yhat = [1.5, -2.0, 3.0]
    # largest error 1.0 at k = 2; max|y| = 4; range = 6
    assert sw.max_relative_error(y, yhat) == 0.25
    np.testing.assert_allclose(sw.max_relative_error(y, yhat, 'range'),
                               1 / 6, rtol=1e-15)
    assert sw.max_relative_error(y, y) == 0.0


def test_max_relative_error_negative_peak():
    # the peak magnitude counts, whatever its sign
    assert sw.max_relative_error([-5.0, 1.0], [-4.0, 1.0]) == 0.2


def test_max_relative_error_bad_scale():
    with pytest.raises(ValueError, match=r"scale must be 'peak' or 'range'"
                                         r"; got 'max'"):
        sw.max_relative_error([1.0, 2.0], [1.0, 2.0], scale='max')


def test_max_relative_error_zero_denominator():
    with pytest.raises(ValueError, match=r"peak magnitude"):
        sw.max_relative_error([0.0, 0.0], [1.0, 0.0])
    with pytest.raises(ValueError, match=r"range"):
        sw.max_relative_error([3.0, 3.0], [1.0, 0.0], scale='range')


# --- compare -------------------------------------------------------------

def test_compare_true_model_is_perfect(plant):
    u = sw.examples.paper_input(300, seed=3)
    y = plant.simulate(u).outputs
    result = sw.compare(plant, u, y, plot=False)
    assert isinstance(result, sw.CompareResult)
    assert result.fit == 100.0
    assert result.nrmse == 0.0
    assert result.max_relative_error == 0.0
    np.testing.assert_array_equal(result.yhat, y)
    np.testing.assert_array_equal(result.timepts, np.arange(300))
    assert result.ax is None


def test_compare_numbers_match_the_measures(plant, rng):
    u = sw.examples.paper_input(400, seed=4)
    y = plant.simulate(u).outputs + 0.1 * rng.standard_normal(400)
    result = sw.compare(plant, u, y, plot=False)
    yhat = plant.simulate(u).outputs
    np.testing.assert_array_equal(result.yhat, yhat)
    assert result.fit == sw.fit_percent(y, yhat)
    assert result.nrmse == sw.nrmse(y, yhat)
    assert result.max_relative_error == sw.max_relative_error(y, yhat)
    np.testing.assert_array_equal(result.error, y - yhat)
    assert result.as_dict() == {
        'name': 'paper', 'fit': result.fit, 'nrmse': result.nrmse,
        'max_relative_error': result.max_relative_error}
    assert 'fit=' in repr(result)


def test_compare_initial_state(plant):
    u = sw.examples.paper_input(50, seed=5)
    x0 = np.arange(1.0, plant.nstates + 1)
    y = plant.simulate(u, initial_state=x0).outputs
    assert sw.compare(plant, u, y, initial_state=x0, plot=False).fit == 100
    assert sw.compare(plant, u, y, plot=False).fit < 100


def test_compare_several_models_and_plot(plant):
    u = sw.examples.paper_input(300, seed=6)
    y = plant.simulate(u).outputs
    worse = sw.SandwichSystem.from_theta(
        plant.theta * 1.05, **plant.orders, dt=plant.dt, name='worse')
    linear = ct.tf([3.0, -0.15], [1, 1.3, 0.64, 0.064], 1, name='linear')
    fig, ax = plt.subplots()
    results = sw.compare([plant, worse, linear], u, y, ax=ax)
    plt.close(fig)
    assert isinstance(results, sw.CompareResultList)
    assert [r.name for r in results] == ['paper', 'worse', 'linear']
    assert results[0].fit == 100.0
    assert 0 < results[1].fit < 100
    # the linear reference is run through python-control
    ylin = ct.forced_response(linear, np.arange(300), u).outputs
    np.testing.assert_allclose(results[2].yhat, ylin, rtol=1e-12,
                               atol=1e-12)
    np.testing.assert_array_equal(results.fit, [r.fit for r in results])
    assert results.nrmse.shape == results.max_relative_error.shape == (3,)
    assert all(r.ax is ax for r in results)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend[0] == 'measured'
    assert legend[1] == 'paper: fit 100.0 %'
    assert legend[2] == f"worse: fit {results[1].fit:.1f} %"
    assert len(ax.get_lines()) == 4
    assert str(results).splitlines()[0].split() == [
        'model', 'fit', '%', 'nrmse', 'max', 'rel', 'err']


def test_compare_nonlinear_iosystem_uses_python_control(plant):
    u = sw.examples.paper_input(40, seed=7)
    y = plant.simulate(u).outputs
    bl = sw.Backlash(1.0, 1.0, 0.2, 0.2, dt=1, name='bl')
    result = sw.compare(bl, u, y, plot=False, labels='backlash only')
    np.testing.assert_allclose(result.yhat, bl.response(u), rtol=1e-14)
    assert result.name == 'backlash only'


def test_compare_result_plot(plant):
    u = sw.examples.paper_input(30, seed=8)
    result = sw.compare(plant, u, plant.simulate(u).outputs, plot=False)
    fig, ax = plt.subplots()
    assert result.plot(ax) is ax
    plt.close(fig)


def test_compare_timepts_for_sampled_model():
    plant = sw.examples.paper_plant(dt=0.5)
    u = sw.examples.paper_input(10, seed=9)
    result = sw.compare(plant, u, plant.simulate(u).outputs, plot=False)
    np.testing.assert_allclose(result.timepts, 0.5 * np.arange(10))


def test_compare_errors(plant):
    u = np.ones(5)
    with pytest.raises(ValueError, match=r"u and y must have the same "
                                         r"number of samples; got 5 and 4"):
        sw.compare(plant, u, np.arange(4.0), plot=False)
    with pytest.raises(ValueError, match=r"y must be finite"):
        sw.compare(plant, u, [0, 1, np.nan, 2, 3], plot=False)
    with pytest.raises(TypeError, match=r"model must be a SandwichSystem "
                                        r"or a python-control system"):
        sw.compare(lambda u: u, u, np.arange(5.0), plot=False)
    with pytest.raises(ValueError, match=r"single-input single-output"):
        sw.compare(ct.ss(np.eye(2) * 0.5, np.eye(2), np.eye(2), 0, 1), u,
                   np.arange(5.0), plot=False)
    with pytest.raises(ValueError, match=r"labels must have one entry per "
                                         r"model \(1\); got 2"):
        sw.compare(plant, u, np.arange(5.0), labels=['a', 'b'], plot=False)
    with pytest.raises(ValueError, match=r"non-empty list"):
        sw.compare([], u, np.arange(5.0), plot=False)
    with pytest.raises(ValueError, match=r"timepts is required for a "
                                         r"continuous-time model"):
        sw.compare(ct.tf(1, [1, 1]), u, np.arange(5.0), plot=False)
    with pytest.raises(ValueError, match=r"y is constant"):
        sw.compare(plant, u, np.zeros(5), plot=False)


def test_compare_unstable_model_reports_instead_of_nan():
    unstable = ct.tf([1.0], [1, -10.0], 1, name='unstable')
    u = np.ones(400)
    with pytest.raises(ValueError, match=r"not finite .* unstable"):
        sw.compare(unstable, u, np.arange(400.0), plot=False)


# --- compare(horizon=k): k-step-ahead prediction ------------------------

def _direct_k_step(y, v, k):
    """Transcription of the k-step predictor for the paper's L2, eq. (5.2):
    y(s) = -1.2 y(s-1) - 0.32 y(s-2) + 2 v(s-1) - 0.1 v(s-2), run for
    s = t-k+1..t from the measured y up to t-k (zero before sample 0)."""
    n = y.size
    out = np.zeros(n)
    for t in range(n):
        own = {}

        def past(s):
            if s < 0:
                return 0.0
            return y[s] if s <= t - k else own[s]

        def vv(s):
            return v[s] if s >= 0 else 0.0

        for s in range(t - k + 1, t + 1):
            own[s] = (-1.2 * past(s - 1) - 0.32 * past(s - 2)
                      + 2.0 * vv(s - 1) - 0.1 * vv(s - 2))
        out[t] = own[t]
    return out


@pytest.mark.parametrize('k', [1, 2, 3, 7, 30])
def test_k_step_prediction_matches_direct_transcription(plant, rng, k):
    u = sw.examples.paper_input(30, seed=10)
    y = plant.simulate(u).outputs + 0.3 * rng.standard_normal(30)
    v = plant.simulate(u, internal=True).outputs[2]
    result = sw.compare(plant, u, y, plot=False, horizon=k)
    np.testing.assert_allclose(result.yhat, _direct_k_step(y, v, k),
                               rtol=1e-12, atol=1e-12)
    assert result.horizon == k
    assert result.fit == sw.fit_percent(y, result.yhat)


def test_one_step_is_the_series_parallel_predictor(plant, rng):
    # horizon=1: eq. (5.2) with the measured past outputs, in closed form
    u = sw.examples.paper_input(200, seed=11)
    y = plant.simulate(u).outputs + 0.2 * rng.standard_normal(200)
    v = plant.simulate(u, internal=True).outputs[2]
    yp, vp = np.r_[0.0, 0.0, y], np.r_[0.0, 0.0, v]
    expected = (-1.2 * yp[1:-1] - 0.32 * yp[:-2] + 2.0 * vp[1:-1]
                - 0.1 * vp[:-2])
    np.testing.assert_allclose(
        sw.compare(plant, u, y, plot=False, horizon=1).yhat, expected,
        rtol=1e-12, atol=1e-12)


def test_k_step_uses_only_outputs_k_samples_back(plant, rng):
    u = sw.examples.paper_input(80, seed=12)
    y = plant.simulate(u).outputs + 0.1 * rng.standard_normal(80)
    bumped = y.copy()
    bumped[40] += 1.0
    for k in (1, 4):
        a = sw.compare(plant, u, y, plot=False, horizon=k).yhat
        b = sw.compare(plant, u, bumped, plot=False, horizon=k).yhat
        np.testing.assert_array_equal(a[:40 + k], b[:40 + k])
        assert a[40 + k] != b[40 + k]


@pytest.mark.parametrize('extra', [0, 25])
def test_long_horizon_is_the_free_run(plant, rng, extra):
    u = sw.examples.paper_input(60, seed=13)
    y = plant.simulate(u).outputs + 0.5 * rng.standard_normal(60)
    pred = sw.compare(plant, u, y, plot=False, horizon=60 + extra)
    np.testing.assert_allclose(pred.yhat, plant.simulate(u).outputs,
                               rtol=1e-10, atol=1e-10)
    # with exact data every horizon reproduces the output
    exact = plant.simulate(u).outputs
    for k in (1, 5):
        np.testing.assert_allclose(
            sw.compare(plant, u, exact, plot=False, horizon=k).yhat, exact,
            rtol=1e-10, atol=1e-10)


def test_k_step_of_linear_models(rng):
    # y(t) = 1.5 y(t-1) - 0.7 y(t-2) + u(t-1) + 0.5 u(t-2)
    tf = ct.tf([1.0, 0.5], [1.0, -1.5, 0.7], 1, name='lin')
    u = rng.standard_normal(50)
    y = ct.forced_response(tf, np.arange(50), u).outputs \
        + 0.2 * rng.standard_normal(50)
    yp, up = np.r_[0.0, 0.0, y], np.r_[0.0, 0.0, u]
    expected = 1.5 * yp[1:-1] - 0.7 * yp[:-2] + up[1:-1] + 0.5 * up[:-2]
    for sys in (tf, ct.ss(tf)):
        np.testing.assert_allclose(
            sw.compare(sys, u, y, plot=False, horizon=1).yhat, expected,
            rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(
        sw.compare(tf, u, y, plot=False, horizon=50).yhat,
        ct.forced_response(tf, np.arange(50), u).outputs, rtol=1e-10,
        atol=1e-10)


def test_horizon_is_labelled_in_repr_and_plot(plant):
    u = sw.examples.paper_input(50, seed=14)
    y = plant.simulate(u).outputs
    fig, ax = plt.subplots()
    result = sw.compare(plant, u, y, ax=ax, horizon=3)
    plt.close(fig)
    assert 'horizon=3' in repr(result)
    assert 'horizon' not in repr(sw.compare(plant, u, y, plot=False))
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend[1] == 'paper: 3-step fit 100.0 %'
    assert '3-step' in ax.get_title()


def test_horizon_errors(plant):
    u = sw.examples.paper_input(20, seed=15)
    y = plant.simulate(u).outputs
    with pytest.raises(ValueError, match=r"horizon must be an integer >= 1;"
                                         r" got 0"):
        sw.compare(plant, u, y, plot=False, horizon=0)
    with pytest.raises(TypeError, match=r"horizon must be an integer"):
        sw.compare(plant, u, y, plot=False, horizon=1.5)
    with pytest.raises(ValueError, match=r"initial_state applies to the "
                                         r"free-run simulation"):
        sw.compare(plant, u, y, plot=False, horizon=1,
                   initial_state=np.zeros(plant.nstates))
    bl = sw.Backlash(1.0, 1.0, 0.2, 0.2, dt=1, name='bl')
    with pytest.raises(TypeError, match=r"horizon \(k-step prediction\) "
                                        r"needs a SandwichSystem"):
        sw.compare(bl, u, y, plot=False, horizon=1)
    with pytest.raises(ValueError, match=r"needs a discrete-time model"):
        sw.compare(ct.tf(1, [1, 1]), u, y, plot=False, horizon=1,
                   timepts=np.arange(20.0))


def test_one_step_needs_only_a_stable_l1(plant):
    # an unstable L2 (c2 = 3: poles of modulus sqrt(3)) overflows in
    # simulation, but L2 run from the measured outputs one step ahead
    # stays finite
    u = sw.examples.paper_input(1500, seed=16)
    y = plant.simulate(u).outputs
    theta = plant.theta.copy()
    theta[1] = 3.0
    bad = sw.SandwichSystem.from_theta(theta, **plant.orders)
    with pytest.raises(ValueError, match=r"not finite"):
        sw.compare(bad, u, y, plot=False)
    assert np.isfinite(sw.compare(bad, u, y, plot=False, horizon=1).fit)


def test_compare_refuses_data_sampled_at_another_rate_than_the_model():
    """A linear model at dt = 0.1 on data at 0.2 ran silently at the
    data's rate (fit 49 %, or 100 % one step ahead)."""
    u = np.random.default_rng(0).standard_normal(300)
    G = ct.tf([0.5], [1, -0.5], 0.1)
    y = ct.forced_response(G, inputs=u).outputs
    rec = ct.TimeResponseData(0.2 * np.arange(300), y, inputs=u)
    for horizon in (None, 1):
        with pytest.raises(ValueError, match=r"\(timepts\) are 0.2 apart "
                           r"on average but model .* has dt = 0.1"):
            sw.compare(G, rec, plot=False, horizon=horizon)
    with pytest.raises(ValueError, match="0.2 apart"):   # per experiment
        sw.compare(G, sw.Experiments([(u, y), (u, y)], 0.2), plot=False)
    same = ct.TimeResponseData(0.1 * np.arange(300), y, inputs=u)
    assert sw.compare(G, same, plot=False).fit > 99.99


def test_k_step_prediction_of_a_model_without_past_outputs_is_its_run():
    """With nc = 0 (an FIR L2) or a static model, the k-step prediction
    uses no measured output: it is the free run (it raised numpy's
    TypeError)."""
    plant = sw.SandwichSystem.from_coefficients(
        a=[-0.5], b=[1.0], c=[], d=[1.0, 0.5], m1=1, m2=1, D1=0.1, D2=0.1)
    u = np.random.default_rng(0).standard_normal(300)
    y = np.asarray(plant.simulate(u).outputs).ravel()
    for k in (1, 5):
        got = sw.compare(plant, u, y, horizon=k, plot=False)
        np.testing.assert_allclose(got.yhat, y, atol=1e-12)
    static = sw.compare(ct.tf([2.0], [1.0], 1), u, 2 * u, horizon=1,
                        plot=False)
    np.testing.assert_allclose(static.yhat, 2 * u)


def test_an_initial_state_of_another_layout_names_the_model():
    # python-control's "Parameter `X0`: Wrong shape" named neither
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(200, seed=1)
    G = ct.tf([1.0], [1, -0.5], 1, name='first')
    with pytest.raises(ValueError, match="initial_state has 6 entries, and "
                       "model 'first' has 1 state "):
        sw.compare([plant, G], u, plant.simulate(u).outputs,
                   initial_state=np.zeros(6), plot=False)
