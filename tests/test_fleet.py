"""identify_many: the results of serial identify, in input order, from
local processes and from a dask LocalCluster; failures kept per data set;
bad arguments named."""

import sys
import warnings

import numpy as np
import control as ct
import pytest

import sandwichctl as sw
from sandwichctl.identification import fleet

PLANT = sw.examples.paper_plant()
ORDERS = PLANT.orders
#: Backlash widths growing from the paper's D1 = 0.5, D2 = 0.6.
SCALES = (1.0, 1.5, 2.0, 2.5)
N = 1500


def _axis(scale):
    co = PLANT.coefficients
    co['D1'], co['D2'] = scale * co['D1'], scale * co['D2']
    return sw.SandwichSystem.from_coefficients(**co)


@pytest.fixture(scope='module')
def datasets():
    """Four seeded (u, y) records of the paper plant, SNR 100."""
    out = []
    for k, scale in enumerate(SCALES):
        u = sw.examples.paper_input(N, seed=k)
        y = sw.examples.add_noise(_axis(scale).simulate(u).outputs, 100,
                                  seed=10 + k)
        out.append((u, y))
    return out


@pytest.fixture(scope='module')
def serial(datasets):
    return [sw.identify(u, y, **ORDERS) for u, y in datasets]


@pytest.fixture(scope='module')
def client():
    distributed = pytest.importorskip('distributed')   # the 'test' extra
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1,
                                  processes=True, dashboard_address=None,
                                  silence_logs=40) as cluster, \
            distributed.Client(cluster) as c:
        yield c


def _assert_same(results, expected):
    assert len(results) == len(expected)
    for got, want in zip(results, expected):
        assert isinstance(got, sw.IdentificationResult)
        np.testing.assert_array_equal(got.theta, want.theta)
        np.testing.assert_array_equal(got.model.theta, want.model.theta)
        assert got.model.orders == want.model.orders
        assert got.success == want.success and got.fit == want.fit
        assert set(got) == set(want)


def test_serial_identify_recovers_growing_widths(serial):
    """The reference itself: each record gives its own width (SNR 100;
    widths of the normalised models, b0 = 1)."""
    def width(model):
        co = model.normalized().coefficients
        return co['D1'] + co['D2']
    np.testing.assert_allclose([width(r.model) for r in serial],
                               [width(_axis(s)) for s in SCALES], rtol=0.05)


def test_local_processes_equal_serial(datasets, serial):
    _assert_same(sw.identify_many(datasets, **ORDERS, processes=2), serial)


def test_in_process_equals_serial(datasets, serial):
    _assert_same(sw.identify_many(datasets, **ORDERS, processes=1), serial)


def test_dask_client_equals_serial(datasets, serial, client):
    _assert_same(sw.identify_many(datasets, **ORDERS, client=client),
                 serial)


def test_input_order_kept(datasets, serial, client):
    """Reversed input, reversed output (results are matched to their
    data set, not to the order in which they finish)."""
    _assert_same(sw.identify_many(datasets[::-1], **ORDERS, processes=2),
                 serial[::-1])
    _assert_same(sw.identify_many(datasets[::-1], **ORDERS, client=client),
                 serial[::-1])


def test_every_data_form(datasets, serial):
    """A record, a list of experiments and a pair, in one call, with the
    arguments of identify (dt from the record) passed through."""
    (u0, y0), (u1, y1) = datasets[:2]
    record = ct.TimeResponseData(0.01 * np.arange(N), y0, inputs=u0)
    experiments = [(u1[:800], y1[:800]), (u1[800:], y1[800:])]
    forms = [record, experiments, datasets[2]]
    got = sw.identify_many(forms, **ORDERS, processes=2, name='axis')
    want = [sw.identify(record, **ORDERS, name='axis'),
            sw.identify(experiments, **ORDERS, name='axis'),
            sw.identify(*datasets[2], **ORDERS, name='axis')]
    _assert_same(got, want)
    assert got[0].model.dt == pytest.approx(0.01) and got[0].model.name == 'axis'
    assert got[1].n_experiments == 2


def test_a_failure_loses_no_other_result(datasets, serial, client):
    u, y = datasets[0]
    bad = (u, np.zeros_like(y))                # constant y: identify raises
    sets = [datasets[0], bad, datasets[1]]
    for where in (dict(processes=2), dict(client=client)):
        out = sw.identify_many(sets, **ORDERS, errors='return', **where)
        assert isinstance(out[1], ValueError) and 'constant' in str(out[1])
        _assert_same([out[0], out[2]], serial[:2])
    with pytest.raises(ValueError, match='constant') as info:
        sw.identify_many(sets, **ORDERS, processes=1)
    assert info.value.results[1] is not None
    _assert_same([info.value.results[0], info.value.results[2]], serial[:2])
    assert any('datasets[1]' in note
               for note in getattr(info.value, '__notes__', ['datasets[1]']))


@pytest.mark.parametrize('bad, exc, match', [
    ((x for x in []), TypeError, 'datasets must be a list or tuple'),
    (np.zeros((2, 2, 100)), TypeError, 'datasets must be'),
    ('data', TypeError, 'datasets must be'),
    ([], ValueError, 'datasets is empty'),
])
def test_bad_datasets(bad, exc, match):
    with pytest.raises(exc, match=match):
        sw.identify_many(bad, **ORDERS)


def test_bad_data_set_is_named(datasets):
    u, y = datasets[0]
    with pytest.raises(ValueError, match=r'datasets\[1\].*same length'):
        sw.identify_many([datasets[0], (u, y[:-1])], **ORDERS)
    with pytest.raises(TypeError, match=r'datasets\[0\]'):
        sw.identify_many([u], **ORDERS)


@pytest.mark.parametrize('kwargs, exc, match', [
    (dict(client='tcp://127.0.0.1:8786'), TypeError, 'client must be'),
    (dict(client=4), TypeError, 'client must be'),
    (dict(processes=0), ValueError, 'processes'),
    (dict(processes=1.5), TypeError, 'processes'),
    (dict(errors='ignore'), ValueError, 'errors'),
    (dict(na=None), TypeError, r"\['na'\]"),
])
def test_bad_arguments(datasets, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        sw.identify_many(datasets, **dict(ORDERS, **kwargs))


def test_processes_with_client(datasets, client):
    with pytest.raises(ValueError, match='processes'):
        sw.identify_many(datasets, **ORDERS, client=client, processes=2)


def test_warnings_are_issued_with_the_data_set(datasets, monkeypatch):
    """A worker's warnings reach the caller, naming the data set."""
    def identify(data, **kwargs):
        warnings.warn(f"{len(data[0][0])} samples", RuntimeWarning)
        return sw.IdentificationResult(theta=np.zeros(1))
    monkeypatch.setattr(fleet, 'identify', identify)
    u, y = datasets[0]
    with pytest.warns(RuntimeWarning) as record:
        sw.identify_many([(u, y), (u[:100], y[:100])], **ORDERS,
                         processes=1)
    assert [str(w.message) for w in record] == [
        'datasets[0]: 1500 samples', 'datasets[1]: 100 samples']
    assert all(w.filename == __file__ for w in record)


def test_client_without_dask_names_the_extra(datasets, monkeypatch):
    monkeypatch.setitem(sys.modules, 'distributed', None)
    with pytest.raises(ImportError, match=r'sandwichctl\[distributed\]'):
        sw.identify_many(datasets, **ORDERS, client=object())


def test_a_pool_broken_twice_from_a_script_names_the_main_guard(
        datasets, monkeypatch):
    """A script without `if __name__ == '__main__':` has its workers
    import it again; when the pool breaks twice the error says so (a
    helper's review saw BrokenProcessPool in every slot, without a
    word on the cause). The workers are not started here: the run on
    the pool is replaced by one that breaks."""
    from concurrent.futures import BrokenExecutor

    def broken_run(pool, jobs, todo, outcomes, bar, **kw):
        for i in todo:
            outcomes[i] = BrokenExecutor('a child process terminated')
        return True

    monkeypatch.setattr(fleet, '_run_on', broken_run)
    monkeypatch.setattr(sys.modules['__main__'], '__file__', 'script.py',
                        raising=False)
    out = sw.identify_many(datasets[:2], **ORDERS, processes=2,
                           errors='return')
    assert all(isinstance(r, BrokenExecutor) for r in out)
    assert all("if __name__ == '__main__'" in str(r) for r in out)
