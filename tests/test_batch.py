"""`refine` (batch output-error refinement): recovery with standard
errors, unstable and multi starts, the refine option of `identify`, and
the checks every batch estimator shares."""

import numpy as np
import pytest

import sandwichctl as sw
from conftest import paper_data as _data


def test_refine_recovers_and_reports_uncertainty():
    plant, u, y = _data(3000, seed=3, snr=46.5)
    start = sw.SandwichSystem.from_theta(plant.theta * 1.1, **plant.orders)
    res = sw.refine(start, u, y)
    assert res.success and res.method == 'refine'
    err = sw.parameter_error(res.theta, plant.theta)
    assert err < 0.02
    # standard errors are positive and of the size of the actual error
    assert np.all(res.std > 0) and np.all(res.std < 0.1)
    assert np.all(np.abs(res.theta - plant.theta) < 6 * res.std)
    # white noise at SNR 46.5 caps the fit at 100 (1 - 1/sqrt(1 + 46.5))
    assert abs(res.fit - 100 * (1 - 1 / np.sqrt(47.5))) < 1.0
    np.testing.assert_allclose(res.fit, sw.fit_percent(
        y, res.model.simulate(u).outputs), rtol=1e-9)


def test_refine_starts_from_an_unstable_model():
    plant, u, y = _data(2000, seed=4)
    bad = plant.theta.copy()
    bad[:2] = [2.5, 1.6]                       # L2 poles outside the circle
    start = sw.SandwichSystem.from_theta(bad, **plant.orders)
    res = sw.refine(start, u, y, n_starts=3, seed=0)
    assert res.success and np.isfinite(res.cost)
    assert sw.parameter_error(res.theta, plant.theta) < 1e-6


def test_multistart_never_worse_than_single_start():
    plant, u, y = _data(2000, seed=5, snr=10)
    start = sw.SandwichSystem.from_theta(
        np.array([0.5, -0.2, 0.0, 0.0, 1.0, 1.0, 0.1, 0.1, 0.0]),
        **plant.orders)
    # at SNR 10 the data do not pin down d1 (-0.05), and refine says so
    with pytest.warns(sw.IdentificationWarning, match=r"\['d1'\] are poorly"):
        one = sw.refine(start, u, y)
    with pytest.warns(sw.IdentificationWarning, match=r"\['d1'\] are poorly"):
        many = sw.refine(start, u, y, n_starts=4, seed=1)
    assert many.cost <= one.cost * (1 + 1e-12)      # to rounding


def test_oe_default_meets_the_noise_free_goal():
    plant, u, y = _data(2000, seed=6)
    res = sw.identify(u, y, **plant.orders)
    assert res.method == 'oe' and res.success
    assert sw.parameter_error(res.theta, plant.theta) < 1e-3
    assert res.model.orders == plant.orders
    assert res.fit > res.linear['fit'] and res.cost <= res.linear['cost']


def test_refine_option_of_identify():
    plant, u, y = _data(4000, seed=7)
    res = sw.identify(u, y, **plant.orders, method='bundle', refine=True)
    assert res.method == 'bundle+refine'
    assert sw.parameter_error(res.theta, plant.theta) < 1e-3


def test_input_inside_the_dead_band_is_refused():
    # |x| stays well inside the dead band of width D1 + D2: y is all zero
    plant, u, y = _data(2000, seed=8, scale=0.01)
    assert not np.any(y)
    with pytest.raises(ValueError, match='y is constant'):
        sw.identify(u, y, **plant.orders, method='rpem', refine=True)


def test_overparametrised_orders_warn():
    plant, u, y = _data(1500, seed=9, snr=20)
    with pytest.warns(RuntimeWarning, match='poorly determined'):
        sw.identify(u, y, na=4, nb=2, nc=4, nd=3, method='rpem',
                    warmup=1500, refine=True)


@pytest.mark.parametrize('kwargs, exc, match', [
    (dict(model='plant'), TypeError, 'model must be a SandwichSystem'),
    (dict(y=np.zeros(10)), ValueError, 'same length'),
    (dict(n_starts=0), ValueError, 'n_starts must be an integer >= 1'),
    (dict(u=np.sin(np.arange(10.0)), y=np.cos(np.arange(10.0))), ValueError,
     'too few'),
    (dict(u=np.zeros(500)), ValueError, 'u is constant'),
    (dict(offsets='both'), ValueError, 'offsets must be one of'),
])
def test_refine_bad_input(kwargs, exc, match):
    plant = sw.examples.paper_plant()
    args = dict(model=plant, u=np.sin(np.arange(500.0)),
                y=np.cos(np.arange(500.0)))
    args.update(kwargs)
    with pytest.raises(exc, match=match):
        sw.refine(**args)


@pytest.mark.parametrize('scale', [1e200, 1e-200])
def test_refine_refuses_data_beyond_the_scale_identify_takes(scale):
    """refine leaked overflow warnings and an internal error on data of
    1e200 and returned fit -inf on 1e-200; it refuses them as identify
    does."""
    plant, u, y = _data(300, seed=1)
    with pytest.raises(ValueError, match="u has peak magnitude.*rescale u"):
        sw.refine(plant, u * scale, y * scale)
