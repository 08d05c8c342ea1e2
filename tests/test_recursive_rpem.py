"""The recursive prediction-error estimator (method='rpem'): projection
into the domain, recovery from divergence, series-parallel convergence,
option checks."""

import numpy as np
import pytest

import sandwichctl as sw
from conftest import paper_data as _data
from sandwichctl.identification._predictor import is_stable


def _in_domain(theta, o):
    na, nb, nc, nd = o
    im = nc + na
    return (np.all(theta[im:im + 2] > 0) and np.all(theta[im + 2:im + 4] >= 0)
            and is_stable(theta, 0, nc, 0.0) and is_stable(theta, nc, na, 0.0))


def test_rpem_projection_keeps_every_estimate_in_the_domain():
    plant, u, y = _data(3000, seed=1, snr=10)
    res = sw.identify(u, y, **plant.orders, method='rpem', P0=1e3,
                      max_step=5.0)
    o = tuple(plant.orders[k] for k in ('na', 'nb', 'nc', 'nd'))
    assert res.history.shape == (3000, 9)
    assert all(_in_domain(th, o) for th in res.history)
    assert res.counts['limited'] + res.counts['rejected'] > 0


def test_rpem_recovers_from_divergence_instead_of_blowing_up():
    # a start with a near-unstable L2, a huge initial covariance and an
    # error limit the first predictions exceed: the safeguards must reset
    # the model and P and carry on
    plant, u, y = _data(3000, seed=2)
    theta0 = np.array([-1.9, 0.95, 0, 0, 0.1, 0.1, 0.1, 0.1, 0])
    res = sw.identify(u, y, **plant.orders, method='rpem', theta0=theta0,
                      P0=1e4, p_max=1e5, err_limit=2 * np.std(y),
                      warmup=3000)
    assert 'diverged' not in res.message
    assert np.all(np.isfinite(res.history)) and res.counts['reset'] > 0
    # after the resets the estimator still reduces the prediction error
    e = res.errors
    assert np.mean(e[-500:] ** 2) < 0.2 * np.mean(e[:500] ** 2)


def test_rpem_that_only_resets_is_no_success():
    # at 1e60 the covariance's trace overflows at every sample: the
    # estimate stays theta0, which was reported as a success
    plant, u, y = _data(500, seed=0)
    ri = sw.RecursiveIdentifier(**plant.orders, method='rpem')
    ri.update_many(u * 1e60, y * 1e60)
    res = ri.result()
    assert res.counts['reset'] > 250
    assert not res.success and 'did not learn' in res.message
    ok = sw.RecursiveIdentifier(**plant.orders, method='rpem')
    ok.update_many(u, y)
    assert ok.result().success and ok.result().counts['reset'] == 0
    with pytest.raises(ValueError, match='u has peak magnitude'):
        ok.update_many(u * 1e200, y)


def test_rpem_series_parallel_converges_noise_free():
    plant, u, y = _data(3000, seed=1)
    res = sw.identify(u, y, **plant.orders, method='rpem', warmup=3000)
    assert sw.parameter_error(res.theta, plant.theta) < 0.01


@pytest.mark.parametrize('kwargs, match', [
    (dict(lam0=1.5), r'lam0 must be in \(0, 1\]'),
    (dict(P0=-1), 'P0 must be a finite number > 0'),
    (dict(warmup=-1), 'warmup must be an integer >= 0'),
])
def test_rpem_bad_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        sw.RecursiveIdentifier(2, 0, 2, 1, method='rpem', **kwargs)
