"""offsets='estimate' does not depend on where the output sits: the fits
run on the output less the first experiment's first sample, and the
estimated offsets come back in the user's coordinates."""

import warnings

import numpy as np
import pytest

import sandwichctl as sw

CASE = sw.data.random_case(3, n=3000, snr=100, integrating='L1')
SPREAD = float(np.std(CASE.y))


def _estimated(level):
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        return sw.identify(CASE.u, CASE.y + level * SPREAD,
                           **CASE.plant.orders, offsets='estimate')


@pytest.fixture(scope='module')
def without_offset():
    """The identification of the record as it is (both levels use it)."""
    return _estimated(0.0)


@pytest.mark.parametrize('level', [5.0, 50.0])
def test_an_output_offset_moves_only_the_estimated_offset(level,
                                                          without_offset):
    # at 50 spreads the free linear fit stopped at 2 %, the integrator was
    # never tried, and the result said success with a fresh-data fit of 73
    # against 96 to 99 without the offset
    base, moved = without_offset, _estimated(level)
    assert base.success and moved.success
    assert moved.integrators == base.integrators == {'L1': 1, 'L2': 0}
    np.testing.assert_allclose(moved.theta, base.theta, rtol=1e-5,
                               atol=1e-8 * np.max(np.abs(base.theta)))
    assert moved.fit == pytest.approx(base.fit, abs=1e-6)
    assert moved.offsets['y'][0] - base.offsets['y'][0] == pytest.approx(
        level * SPREAD, rel=1e-6)
    # the model from rest plus the offset reproduces the fit
    yhat = moved.model.simulate(CASE.u).outputs + moved.offsets['y'][0]
    assert sw.fit_percent(CASE.y + level * SPREAD, yhat) == pytest.approx(
        moved.fit, abs=0.05)


def test_the_linear_fit_and_its_output_are_in_the_users_coordinates():
    o = CASE.orders
    shape = dict(nb=o['nb'] + o['nd'] + 1, nf=o['na'] + o['nc'], nk=1,
                 offsets='estimate')
    level = 500 * SPREAD
    base = sw.identify_linear(CASE.u, CASE.y, **shape)
    moved = sw.identify_linear(CASE.u, CASE.y + level, **shape)
    np.testing.assert_allclose(moved.F, base.F, atol=1e-6)
    assert moved.fit == pytest.approx(base.fit, abs=1e-6)
    np.testing.assert_allclose(moved.yhat, base.yhat + level, atol=1e-6 *
                               level)
    np.testing.assert_allclose(moved.residuals, CASE.y + level - moved.yhat,
                               atol=1e-9 * level)
    assert moved.offsets['y'][0] - base.offsets['y'][0] == pytest.approx(
        level, rel=1e-6)


@pytest.mark.parametrize('offsets', ['none', 'estimate'])
def test_an_input_at_an_operating_point_is_not_a_success(offsets):
    # u + 500 (1,200 of its spreads): the model from rest at u = 0 saw a
    # step it never had; the fits beat the linear baselines (20 % against
    # 6 %) and said success, with a fit on fresh data below zero (there
    # with 3,000 samples; 1,500 say the same)
    case = sw.data.random_case(2, n=1500, snr=20)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        res = sw.identify(case.u + 500, case.y, **case.plant.orders,
                          offsets=offsets)
    assert not res.success
    assert res.message.startswith('the input starts 1.2')
    assert "offsets='mean'" in res.message
    lin = sw.identify_linear(case.u + 500, case.y, nb=5, nf=6, nk=1,
                             offsets=offsets)
    assert not lin.success and 'standard deviations from zero' in \
        lin.message
    ok = sw.identify_linear(case.u + 500, case.y, nb=5, nf=6, nk=1,
                            offsets='mean')
    assert ok.success, ok.message


def test_experiments_at_other_levels_keep_the_fit_of_the_users_data():
    # shifting each experiment by its own first sample dropped the gap
    # between their levels from the fit's spread (identify_linear: 35.3
    # against 70.6 on the data as given)
    rng = np.random.default_rng(4)
    u = [rng.standard_normal(600) for _ in range(2)]
    y = [np.convolve(part, [0.0, 1.0, 0.5])[:600] + level
         + 0.3 * rng.standard_normal(600) for part, level in zip(u, (10, 13))]
    res = sw.identify_linear(list(zip(u, y)), nb=2, nf=1, nk=1,
                             offsets='estimate')
    y_all = np.concatenate(y)
    assert res.fit == pytest.approx(100 * (1 - np.linalg.norm(
        y_all - res.yhat) / np.linalg.norm(y_all - y_all.mean())))
    np.testing.assert_allclose(res.offsets['y'], [10, 13], atol=0.05)


def test_a_step_from_rest_is_not_an_operating_point():
    # its mean is 26 of its standard deviations from zero, but it starts
    # at rest
    u = np.r_[np.zeros(3), np.ones(1997)]
    u = u + 0.01 * np.random.default_rng(5).standard_normal(u.size)
    y = np.convolve(u, [0.0, 0.6, 0.3])[:u.size]
    res = sw.identify_linear(u, y, nb=2, nf=0, nk=1)
    assert res.success, res.message


def test_mean_offsets_on_an_integrating_model_warn():
    """offsets='mean' changes an integrating plant's drift: identify says
    so when its model integrates, as select_structure does."""
    case = sw.data.random_case(4, integrating=True, n=1000)
    with pytest.warns(sw.IdentificationWarning, match="integrates.*"
                      "offsets='estimate'"):
        res = sw.identify(case.u, case.y, **case.orders, offsets='mean')
    assert res.integrators['L1']
