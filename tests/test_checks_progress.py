"""The progress bars of `_checks`: the bar that concurrent searches share
has its total when it is made (tqdm's notebook widget keeps the total it
was made with), and fills to it."""

import threading
import warnings
from concurrent.futures import ThreadPoolExecutor
from types import SimpleNamespace

import numpy as np
import pytest
import tqdm.auto

import sandwichctl as sw
from sandwichctl._checks import (SHARE_UNITS, close_filled, progress_bar,
                                 shared_progress)


class _Recorder:
    """Stands for tqdm.auto.tqdm: the total it is made with, each update."""

    def __init__(self, made, total=None, **kwargs):
        self.total, self.kwargs = total, kwargs
        self.steps, self.closed = [], False
        self.lock = threading.Lock()
        made.append(self)

    def update(self, n=1):
        with self.lock:             # the shared bar updates under its lock
            self.steps.append(n)

    @property
    def n(self):
        return sum(self.steps)

    def close(self):
        self.closed = True


@pytest.fixture
def made(monkeypatch):
    """The bars `progress_bar` makes (tqdm.auto.tqdm recorded)."""
    bars = []
    monkeypatch.setattr(tqdm.auto, 'tqdm',
                        lambda **kw: _Recorder(bars, **kw))
    return bars


def _search(task, planned, ticks, close=True):
    """What `_search.Search.run` does with its bar."""
    bar = progress_bar(task.progress, total=planned, desc='starts',
                       leave=False)
    for _ in range(ticks):
        bar.update()
    if close:
        close_filled(bar)


@pytest.mark.parametrize('workers', [1, 3])
def test_shared_bar_has_its_total_when_made(made, workers):
    """Three searches (their ticks under, over and at their plans) on one
    thread or three: one bar, made with the total of three shares, that
    only grows and ends full; the task's ``progress`` is True again."""
    task = SimpleNamespace(progress=True)
    plans = [(24, 22), (84, 90), (7, 7)]
    with shared_progress(task, len(plans), 'identify: starts'):
        assert len(made) == 1 and made[0].total == 3 * SHARE_UNITS
        with ThreadPoolExecutor(workers) as pool:
            list(pool.map(lambda plan: _search(task, *plan), plans))
    bar, = made
    assert bar.total == sum(bar.steps) and min(bar.steps) > 0
    assert bar.closed and task.progress is True


def test_shared_bar_of_a_search_that_raised_is_not_full(made):
    """A search that ends without closing its share leaves it unfilled."""
    task = SimpleNamespace(progress=True)
    with shared_progress(task, 2, 'identify: starts'):
        _search(task, 10, 10)
        _search(task, 10, 5, close=False)
    assert sum(made[0].steps) == SHARE_UNITS + SHARE_UNITS // 2


@pytest.mark.parametrize('progress, n', [(True, 1), (False, 3)])
def test_no_shared_bar_for_one_search_or_without_progress(made, progress,
                                                          n):
    task = SimpleNamespace(progress=progress)
    with shared_progress(task, n, 'identify: starts'):
        assert task.progress is progress
    assert made == []


def test_identify_counts_its_searches_on_a_bar_of_known_total(made):
    """identify with integrators='auto' (three searches: none, in L1, in
    L2) shows one bar, made with its final count as total, and fits the
    model it fits without the bar."""
    case = sw.data.random_case(3, n=600, snr=100, integrating='L1')
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        with_bar = sw.identify(case.u, case.y, **case.orders, progress=True)
        without = sw.identify(case.u, case.y, **case.orders)
    np.testing.assert_array_equal(with_bar.theta, without.theta)
    bar, = made
    assert bar.total == 3 * SHARE_UNITS == sum(bar.steps)
    assert bar.closed


@pytest.mark.parametrize('planned, ticks', [(24, 22), (7, 7), (5, 9)])
def test_a_lone_search_bar_closes_full(made, planned, ticks):
    """A search alone on its bar (no sharing) closes it at its total when
    its steps ran fewer ticks than planned (tqdm's notebook widget closed
    short turns red), and leaves it alone at or above it."""
    _search(SimpleNamespace(progress=True), planned, ticks)
    bar, = made
    assert bar.closed and bar.n == max(planned, ticks)


def test_identify_alone_closes_its_bar_full(made):
    """A plain identify with progress=True (one search) ends with its bar
    at the total its steps planned: random_case(28)'s steps tick 23 of the
    24 planned."""
    case = sw.data.random_case(28, n=600, snr=100)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        sw.identify(case.u, case.y, **case.orders, progress=True)
    starts = [b for b in made if b.kwargs.get('desc') == 'identify: starts']
    assert len(starts) == 1 and starts[0].closed
    assert starts[0].n == starts[0].total > 0
