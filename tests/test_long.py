"""The long-record path of `identify` (`identification._long`): the search
on the leading samples, the refinement on all of them.

The thresholds are lowered (monkeypatched) so that short records take the
path; no timing is asserted (see benchmarks/bench_long_records.py)."""

import warnings

import numpy as np
import pytest

import sandwichctl as sw
from sandwichctl.identification import _long, _predictor
from sandwichctl.identification._problem import Problem

N = 6000


@pytest.fixture(scope='module')
def record():
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(N, seed=3)
    y = sw.examples.add_noise(plant.simulate(u).outputs, 100, seed=1003)
    return plant, u, y


def _identify(monkeypatch, record, threshold, head=2000, **kw):
    """identify on `record` with the long-record path above `threshold`
    samples, counting the simulations of the whole record."""
    plant, u, y = record
    monkeypatch.setattr(_long, 'LONG_RECORD', threshold)
    monkeypatch.setattr(_long, 'LONG_HEAD', head)
    calls = []
    choose = _predictor._kernel

    def chosen(o, kind, n, *rings):
        kernel = choose(o, kind, n, *rings)

        def counted(theta, o, up, *args):
            calls.append(up.size - _predictor.padding(o))
            return kernel(theta, o, up, *args)
        return counted
    monkeypatch.setattr(_predictor, '_kernel', chosen)
    res = sw.identify(u, y, **plant.orders, **kw)
    monkeypatch.undo()
    return res, sum(size >= N for size in calls)


@pytest.fixture(scope='module')
def both(record):
    """(long-record result, its whole-record simulations), the same of
    the exhaustive search."""
    with pytest.MonkeyPatch.context() as mp:
        long = _identify(mp, record, threshold=N // 2)
    with pytest.MonkeyPatch.context() as mp:
        exhaustive = _identify(mp, record, threshold=N)
    return long, exhaustive


def test_long_path_taken_above_threshold_and_said(both):
    (res, _), (exh, _) = both
    assert res.long_record == {'samples': N, 'head': 2000}
    assert "long record: the search ran on the leading 2,000 of 6,000 " \
           "samples" in res.message
    assert res.success
    assert exh.long_record is None and "long record" not in exh.message


def test_long_path_simulates_the_record_fewer_times(both):
    (_, n_long), (_, n_exh) = both
    assert 0 < n_long <= n_exh / 5, (n_long, n_exh)


def test_long_path_fits_as_the_exhaustive_search(both, record):
    (res, _), (exh, _) = both
    plant = record[0]
    assert res.fit == pytest.approx(exh.fit, abs=0.01)          # points
    err = sw.parameter_error(res.theta, plant.theta)
    assert err <= 1.2 * sw.parameter_error(exh.theta, plant.theta) + 1e-4
    assert res.fit >= res.linear['fit']
    # the baseline is the linear fit of all the samples, from the leading
    # samples' fit: the same optimum as from the ARX start here, each
    # stopped within the data's precision of it (`_linear.PRECISION`)
    assert res.linear['fit'] == pytest.approx(exh.linear['fit'], abs=1e-4)


def test_the_leading_samples_linear_fit_starts_that_of_all():
    from types import SimpleNamespace
    head = {'B': np.array([0.4, 0.2]), 'Ff': np.array([1.0, -0.5, 0.06])}
    # B in the leading samples' units (u / 2, y / 1) is B / 2 in the
    # user's, and B / 2 * 2 / 4 in those of all the samples (u / 2, y / 4)
    b, free = _long._carried_linear(head, SimpleNamespace(su=2.0, sy=1.0),
                                    SimpleNamespace(su=2.0, sy=4.0))
    np.testing.assert_allclose(b, [0.1, 0.05])
    np.testing.assert_array_equal(free, [1.0, -0.5, 0.06])


def _one_and_two_threads(monkeypatch, identify):
    """{workers: identify()} on the long path with 1 and 2 threads, which
    must give the same model and message, bit for bit."""
    monkeypatch.setattr(_long, 'LONG_RECORD', 3000)
    monkeypatch.setattr(_long, 'LONG_HEAD', 2000)
    monkeypatch.delenv('OMP_NUM_THREADS', raising=False)
    out = {}
    for workers in (1, 2):
        monkeypatch.setattr(_long, 'WORKERS', workers)
        with warnings.catch_warnings():
            warnings.simplefilter('ignore', RuntimeWarning)
            out[workers] = identify()
    assert out[1].long_record is not None
    np.testing.assert_array_equal(out[2].theta, out[1].theta)
    assert out[2].message == out[1].message
    return out


def test_two_threads_give_the_one_threads_model(monkeypatch, record):
    """Stage 2's baseline beside stage 1, the starts of step 6 and the
    smoothed path's differences on threads: the same model and baseline
    as on one thread, bit for bit."""
    plant, u, y = record
    out = _one_and_two_threads(
        monkeypatch, lambda: sw.identify(u, y, **plant.orders))
    assert out[2].linear['cost'] == out[1].linear['cost']


def test_a_set_stop_ends_the_linear_fit_before_its_next_iteration():
    import threading
    from sandwichctl.identification._linear import fit_oe
    rng = np.random.default_rng(0)
    u = rng.standard_normal(2000)
    y = np.convolve(u, [0.0, 0.5, 0.3])[:2000] + 0.01 * rng.standard_normal(
        2000)
    stop = threading.Event()
    stop.set()
    out = fit_oe(u, y, (2, 2, 1), 0, stop=stop)
    assert out['nit'] == 0 and not out['converged']
    assert out['message'] == "stopped: the fit is no longer wanted"
    assert fit_oe(u, y, (2, 2, 1), 0)['converged']


def test_one_thread_where_the_process_is_limited_to_one(monkeypatch):
    monkeypatch.setenv('OMP_NUM_THREADS', '1')     # identify_many's workers
    assert _long.threads() == 1
    monkeypatch.delenv('OMP_NUM_THREADS')
    assert _long.threads() == _long.WORKERS == 2


def test_an_error_in_stage_1_stops_the_baseline_beside_it(monkeypatch,
                                                         record):
    import threading
    plant, u, y = record
    monkeypatch.setattr(_long, 'LONG_RECORD', 3000)
    monkeypatch.setattr(_long, 'LONG_HEAD', 2000)
    monkeypatch.delenv('OMP_NUM_THREADS', raising=False)
    seen, original = {}, _long.Task.fit_linear

    def fit_linear(self, scaled, k, start=None, stop=None, **kw):
        if stop is None:                # step 2 on the leading samples
            return original(self, scaled, k, start, **kw)
        seen['stop'] = stop             # the baseline beside stage 1
        stop.wait(timeout=30)
        return {}

    def failing_search(task, linears=None):
        raise KeyboardInterrupt

    monkeypatch.setattr(_long.Task, 'fit_linear', fit_linear)
    monkeypatch.setattr(_long, 'search', failing_search)
    before = threading.active_count()
    with pytest.raises(KeyboardInterrupt):
        sw.identify(u, y, **plant.orders)
    assert seen['stop'].is_set()
    assert threading.active_count() == before   # no fit left running


def test_long_path_with_experiments_offsets_and_initial_states(
        monkeypatch, record):
    plant, u, y = record
    data = [(u[:3500], y[:3500] + 0.3), (u[3500:], y[3500:] - 0.2)]
    monkeypatch.setattr(_long, 'LONG_RECORD', 3000)
    monkeypatch.setattr(_long, 'LONG_HEAD', 2000)
    with warnings.catch_warnings():  # the offsets blur D1, D2 (identify)
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        res = sw.identify(data, **plant.orders, offsets='estimate',
                          initial_state='estimate')
    assert res.long_record['samples'] == N and res.success
    # the offsets' common part trades against the backlash's asymmetry
    # (see identify's offsets); their difference is determined
    first, second = res.offsets['y']
    assert first - second == pytest.approx(0.5, abs=0.05)
    assert max(abs(first - 0.3), abs(second + 0.2)) < 0.1


def test_carried_keeps_model_offsets_and_initial_states(record):
    """A phi of the leading samples' problem, carried to the whole
    record's (scaled by other spreads), is the same model, offsets and
    initial conditions in the user's units."""
    plant, u, y = record
    orders = plant.orders
    parts = [(u[:4000], 3 * y[:4000]), (u[4000:], 3 * y[4000:])]
    full = Problem([p[0] for p in parts], [p[1] for p in parts], orders,
                   offsets=True, inits=True)
    head = Problem([p[0][:300] for p in parts], [p[1][:300] for p in parts],
                   orders, offsets=True, inits=True)
    assert head.su != full.su and head.sy != full.sy
    rng = np.random.default_rng(1)
    phi_h = head.phi_of_model(plant)
    phi_h[head.st.q:] = rng.standard_normal(head.st.size - head.st.q)
    phi = _long._carried(head, full, phi_h)
    np.testing.assert_allclose(full.model(phi).theta, head.model(
        phi_h).theta, rtol=1e-12)
    np.testing.assert_allclose(_user_units(full, phi),
                               _user_units(head, phi_h), rtol=1e-12)


def _user_units(prob, phi):
    """Output offsets and initial conditions of phi in the user's units,
    as `Problem.result` reports them."""
    st = prob.st
    out = [prob.sign * prob.sy * phi[st.q:st.q + st.n_off]]
    for e in range(st.n_inits):
        x, v, y = st.init(phi, e)
        out += [prob.su * x, prob.sy * v, prob.sign * prob.sy * y]
    return np.concatenate(out)


def test_constant_leading_samples_search_the_whole_record(
        monkeypatch, record):
    """An input at rest over the leading samples cannot show the search
    a basin: the whole record is searched, as below the threshold."""
    plant, u, _ = record
    u = np.r_[np.zeros(2500), u[2500:]]
    y = plant.simulate(u).outputs
    monkeypatch.setattr(_long, 'LONG_RECORD', 3000)
    monkeypatch.setattr(_long, 'LONG_HEAD', 2000)
    res = sw.identify(u, y, **plant.orders)
    assert res.long_record is None and "long record" not in res.message
    assert res.success


def test_stage_1_smoothed_path_on_its_leading_samples(monkeypatch, record):
    """Step 8's smoothed problems run on the first `PATH_SAMPLES` of stage
    1's samples and its exact refinement on all of them; the exhaustive
    search of a shorter record smooths on every sample."""
    from sandwichctl.identification import _search
    seen, smooth = [], _search.smooth_refine

    def spy(st, phi, u, y, *args, path=None, **kw):
        seen.append((sum(p.size for p in u), None if path is None else
                     sum(p.size for p in path[0] + path[1])))
        return smooth(st, phi, u, y, *args, path=path, **kw)
    monkeypatch.setattr(_search, 'smooth_refine', spy)
    monkeypatch.setattr(_long, 'PATH_SAMPLES', 800)
    res, _ = _identify(monkeypatch, record, threshold=N // 2)
    assert res.long_record is not None and seen
    assert all(n == 2000 and both == 2 * 800 for n, both in seen)
    monkeypatch.setattr(_search, 'smooth_refine', spy)
    seen.clear()
    _identify(monkeypatch, record, threshold=N)
    assert seen and all(n == N and path is None for n, path in seen)


def test_integrator_splits_side_by_side_give_the_one_threads_model(
        monkeypatch):
    """With integrators='auto' on integrating data stage 1 searches every
    integrator split, on two threads side by side: the same model, verdict
    and message as on one thread."""
    from sandwichctl.data import random_case
    case = random_case(105, n=4000, snr=100, integrating=True)
    out = _one_and_two_threads(
        monkeypatch, lambda: sw.identify(case.u, case.y, **case.orders))
    assert "integrators='auto' chose" in out[1].message
    assert out[2].integrators == out[1].integrators == {'L1': 1, 'L2': 0}
