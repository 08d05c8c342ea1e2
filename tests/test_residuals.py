"""`residuals`: correlations against hand computations, the 99 % band, the
counts for a perfect and a wrong model, both model kinds, and bad input."""

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest

import sandwichctl as sw


@pytest.fixture(scope='module')
def noisy():
    """The paper plant on 4000 samples with white output noise."""
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(4000, seed=1)
    rng = np.random.default_rng(2)
    y = plant.simulate(u).outputs + 0.05 * rng.standard_normal(u.size)
    return plant, u, y


def _corr(a, b, k):
    """sum_t a(t) b(t + k) of centred signals (hand reference)."""
    a, b = a - a.mean(), b - b.mean()
    n = a.size
    return a[:n - k] @ b[k:] if k >= 0 else a[-k:] @ b[:n + k]


def test_band_and_hand_correlations(noisy):
    plant, u, y = noisy
    res = sw.residuals(plant, (u, y), lags=10, plot=False)
    e = y - plant.simulate(u).outputs
    np.testing.assert_allclose(res.residuals[0], e, rtol=0, atol=1e-12)
    assert res.n_samples == 4000
    assert res.bound == pytest.approx(2.58 / np.sqrt(4000), rel=1e-15)
    np.testing.assert_array_equal(res.lags, np.arange(11))
    np.testing.assert_array_equal(res.cross_lags, np.arange(-10, 11))
    r0 = _corr(e, e, 0)
    expected = [_corr(e, e, k) / r0 for k in range(11)]
    np.testing.assert_allclose(res.autocorrelation, expected, rtol=1e-12)
    scale = np.sqrt(r0 * _corr(u, u, 0))
    expected = [_corr(u, e, k) / scale for k in range(-10, 11)]
    np.testing.assert_allclose(res.cross_correlation, expected, rtol=1e-12,
                               atol=1e-15)
    assert res.outside_auto == int(np.sum(np.abs(res.autocorrelation[1:])
                                          > res.bound))
    assert res.outside_cross == int(np.sum(np.abs(res.cross_correlation)
                                           > res.bound))


def test_white_residuals_of_a_perfect_model(noisy):
    plant, u, y = noisy
    res = sw.residuals(plant, (u, y), plot=False)
    # 99 % band: about 1 % of the lags outside by chance
    assert res.outside_auto <= 2 and res.outside_cross <= 2
    text = repr(res)
    assert f"{res.outside_auto} of 25 outside" in text
    assert f"{res.outside_cross} of 51 outside" in text


def test_wrong_model_has_many_lags_outside(noisy):
    plant, u, y = noisy
    theta = plant.theta.copy()
    theta[0] *= 0.8                                 # c1 of L2 off by 20 %
    wrong = sw.SandwichSystem.from_theta(theta, **plant.orders)
    res = sw.residuals(wrong, (u, y), plot=False)
    assert res.outside_auto >= 12 and res.outside_cross >= 8


def test_sign_of_the_cross_lag(rng):
    """e(t) = u(t - 3): the input leads the residual by 3 samples."""
    u = rng.standard_normal(3000)
    y = 0.5 * u
    y[3:] += u[:-3]
    model = ct.tf([0.5], [1], 1)
    res = sw.residuals(model, (u, y), lags=5, plot=False)
    peak = res.cross_lags[np.argmax(np.abs(res.cross_correlation))]
    assert peak == 3
    assert res.cross_correlation[res.cross_lags == 3][0] == \
        pytest.approx(1.0, abs=0.01)
    assert res.outside_cross == 1


def test_linear_models_tf_ss_and_results_agree(noisy):
    plant, u, y = noisy
    fit = sw.identify_linear(u, y, nb=3, nf=4, nk=2)
    by_tf = sw.residuals(fit.model, (u, y), plot=False)
    by_ss = sw.residuals(ct.ss(fit.model), (u, y), plot=False)
    by_result = sw.residuals(fit, (u, y), plot=False)
    for other in (by_ss, by_result):
        np.testing.assert_allclose(other.autocorrelation,
                                   by_tf.autocorrelation, atol=1e-8)
        np.testing.assert_allclose(other.cross_correlation,
                                   by_tf.cross_correlation, atol=1e-8)
    # the linear model of backlash data leaves correlated residuals
    assert by_tf.outside_auto >= 20


def test_records_and_several_experiments(noisy):
    plant, u, y = noisy
    plant = sw.examples.paper_plant(dt=0.01)
    t = 0.01 * np.arange(u.size)
    rec = ct.TimeResponseData(t, y, inputs=u)
    one = sw.residuals(plant, rec, plot=False)
    ref = sw.residuals(plant, (u, y), plot=False)
    np.testing.assert_allclose(one.autocorrelation, ref.autocorrelation)
    half = u.size // 2
    two = sw.residuals(plant, [(u[:half], y[:half]), (u[half:], y[half:])],
                       lags=4, plot=False)
    assert two.n_samples == u.size and len(two.residuals) == 2
    e = [yy - plant.simulate(uu).outputs
         for uu, yy in ((u[:half], y[:half]), (u[half:], y[half:]))]
    sums = [sum(_corr(p, p, k) for p in e) for k in range(5)]
    np.testing.assert_allclose(two.autocorrelation,
                               np.array(sums) / sums[0], rtol=1e-12)


def test_plot_two_panels(noisy):
    plant, u, y = noisy
    res = sw.residuals(plant, (u[:500], y[:500]), lags=8)
    assert len(res.axes) == 2
    assert res.axes[0].get_xlabel() == 'lag'
    fig, axs = plt.subplots(2, 1)
    again = res.plot(ax=axs)
    assert again[1] is axs[1]
    plt.close('all')


@pytest.mark.parametrize('kwargs, error, match', [
    (dict(lags=0), ValueError, 'lags'),
    (dict(lags=500), ValueError, 'lags must be below'),
    (dict(lags=2.5), TypeError, 'lags'),
    (dict(ax='axes'), TypeError, 'ax must be'),
])
def test_bad_options(noisy, kwargs, error, match):
    plant, u, y = noisy
    with pytest.raises(error, match=match):
        sw.residuals(plant, (u[:500], y[:500]), **kwargs)


def test_bad_models_and_data(noisy):
    plant, u, y = noisy
    data = (u[:300], y[:300])
    with pytest.raises(TypeError, match='model must be'):
        sw.residuals('plant', data, plot=False)
    with pytest.raises(ValueError, match='discrete-time'):
        sw.residuals(ct.tf([1], [1, 1]), data, plot=False)
    with pytest.raises(ValueError, match='single-input'):
        sw.residuals(ct.tf([[[1]], [[1]]], [[[1, 0]], [[1, 0]]], 1), data,
                     plot=False)
    with pytest.raises(ValueError, match='dt = 0.01 but model'):
        rec = ct.TimeResponseData(0.01 * np.arange(300), y[:300],
                                  inputs=u[:300])
        sw.residuals(sw.examples.paper_plant(dt=0.02), rec, plot=False)
    with pytest.raises(TypeError, match='data'):
        sw.residuals(plant, u, plot=False)
    with pytest.raises(ValueError, match='same length'):
        sw.residuals(plant, (u[:300], y[:200]), plot=False)
    with pytest.raises(ValueError, match='not finite'):
        sw.residuals(ct.tf([1], [1, -50], 1), data, plot=False)
    with pytest.raises(ValueError, match='constant'):
        sw.residuals(plant, (u[:300], plant.simulate(u[:300]).outputs),
                     plot=False)


def test_error_bands_measure_the_relative_error_per_band(rng):
    from sandwichctl.tools.residuals import error_bands, BANDS_PER_DECADE
    yhat = np.cumsum(rng.standard_normal(5000))
    # a residual proportional to the output is that share in every band
    w, delta = error_bands(0.2 * yhat + 3.0, yhat)
    np.testing.assert_allclose(delta, 0.2, rtol=1e-9)
    assert w[0] > 2 * np.pi * 4 / 5000 and w[-1] < np.pi
    ratio = np.diff(np.log10(w))
    assert np.all(ratio >= 1 / BANDS_PER_DECADE * (1 - 1e-9))
    # white noise against a random walk: small at low, larger at high
    # frequencies
    w, delta = error_bands(0.05 * rng.standard_normal(5000), yhat)
    assert delta[0] < 0.01 < 0.05 < delta[-1]
    assert error_bands(np.ones(10), np.ones(10))[0].size == 0


def test_identify_keeps_the_error_bands_of_its_baseline():
    case = sw.data.drive_case(0, 'position', 0.0, n=2000)
    res = sw.identify(case.u, case.y, na=1, nb=0, nc=1, nd=0, q1=1, q2=0,
                      dt=case.dt)
    w, delta = res.linear['error_bands']
    assert w.size == delta.size > 10 and np.all(np.isfinite(delta))
    wr, rel, sigma = res.linear['relative_error']
    np.testing.assert_array_equal(wr, w)
    assert np.all(np.isfinite(rel)) and np.all(sigma >= 0)
    # what Delta leaves of the residual's power is what sigma counts
    assert np.all(np.abs(rel) <= delta * (1 + 1e-9))


def test_relative_error_measures_gain_and_phase_of_a_missing_lag(
        lagged_fit):
    from sandwichctl.tools.residuals import relative_error
    # a first-order fit of a plant with a second, unmodelled lag
    P, lin = lagged_fit
    w, rel, sigma = relative_error(lin.residuals, lin.yhat)
    z = np.exp(1j * w)
    true = (np.polyval(P.num[0][0], z) / np.polyval(P.den[0][0], z)
            / (np.polyval(lin.model.num[0][0], z)
               / np.polyval(lin.model.den[0][0], z))) - 1
    sure = sigma < 0.05
    assert sure.sum() > 10 and np.max(np.abs(true[sure])) > 0.5
    # band averages of a relative error that turns by 90 deg per decade
    assert np.all(np.abs(rel - true)[sure] < 0.05 + 0.1 * np.abs(true[sure]))
    assert relative_error(np.ones(10), np.ones(10))[1].size == 0
