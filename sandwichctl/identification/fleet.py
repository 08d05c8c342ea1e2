"""`identify_many`: identify a fleet of sandwich systems in parallel.

A factory with hundreds of axes, a condition monitor that re-identifies
every drive each month, a structure search over many records: each is many
independent calls of `identify`. `identify_many` runs them

- in local worker processes (`concurrent.futures.ProcessPoolExecutor`), by
  default one per core, or serially in this process with
  ``processes=1``;
- or on a `dask.distributed` cluster when a ``client`` is given (the
  optional extra ``sandwichctl[distributed]``).

The results come back in the order of the data sets and are those of
``identify`` on each set (`identify` is deterministic). The data are read
in this process, with `as_experiments`, so a bad record is reported
before any work starts, and the workers receive plain float arrays.

Workers are single-threaded: two identifications on two cores, each
with a BLAS pool of two threads, would put four busy threads on two
cores (OpenBLAS's threads spin while they wait). The local workers are
started (``spawn``) with ``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS``,
``MKL_NUM_THREADS``, ``VECLIB_MAXIMUM_THREADS`` and ``NUMBA_NUM_THREADS``
set to 1 (and their initializer sets them too). A dask worker started by a nanny (the default
of `dask.distributed.LocalCluster` and of ``dask worker``) already gets
the first three from dask's configuration
(``distributed.nanny.pre-spawn-environ``); start it with
``threads_per_worker=1`` so that each worker runs one identification at a
time. The nanny also sets ``MALLOC_TRIM_THRESHOLD_=65536``, which fixes
glibc's mmap threshold at 128 KiB, so that every array above it is
mapped and unmapped anew: identification then runs about 1.4x slower
(measured on the paper plant, N = 3,000). Remove it before starting the
cluster::

    key = 'distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_'
    with dask.config.set({key: None}):
        cluster = LocalCluster(n_workers=2, threads_per_worker=1)

With the ``spawn`` start method, a script that calls `identify_many` must
protect its entry point with ``if __name__ == '__main__':`` (as on macOS
and Windows for any process pool); notebooks need nothing.
"""

import collections.abc
import multiprocessing
import os
import signal
import sys
import threading
import warnings
from concurrent.futures import (BrokenExecutor, ProcessPoolExecutor,
                                as_completed)
from contextlib import contextmanager

import control as ct

from ..tools.experiments import as_experiments
from .pipeline import identify
from .._checks import (check_bool, check_int, check_option, check_order,
                       progress_bar)

__all__ = ['identify_many']

#: Environment of a single-threaded worker (BLAS, OpenMP and numba pools).
SINGLE_THREAD = {'OMP_NUM_THREADS': '1', 'OPENBLAS_NUM_THREADS': '1',
                 'MKL_NUM_THREADS': '1', 'VECLIB_MAXIMUM_THREADS': '1',
                 'NUMBA_NUM_THREADS': '1'}

ERRORS = ('raise', 'return')

#: Seconds after which idle local workers are shut down.
IDLE_TIMEOUT = 300.0


def identify_many(datasets, na=None, nb=None, nc=None, nd=None, q1=1, q2=1,
                  client=None, processes=None, progress=False,
                  errors='raise', **identify_kwargs):
    """Identify one sandwich system per data set, in parallel.

    Every data set is identified by ``identify(data, na=na, nb=nb, nc=nc,
    nd=nd, q1=q1, q2=q2, **identify_kwargs)``, in a worker process or on a
    dask cluster; the results are the same as those calls, in the same
    order.

    Parameters
    ----------
    datasets : sequence
        A list or tuple of data sets, each in a form `identify` accepts:
        a ``(u, y)`` pair of 1-D arrays, a ``control.TimeResponseData``
        with one input and one output, or a list of experiments (pairs or
        records, see `as_experiments`) whose costs are summed.
    na, nb, nc, nd : int
        Orders of eq. (2.1), the same for every data set (as in
        `identify`).
    q1, q2 : int, optional
        Known delays (default 1).
    client : dask.distributed.Client, optional
        Run on this dask cluster (``client.scatter`` of the data, then
        ``client.map``). Default None: local processes. Needs the extra
        ``sandwichctl[distributed]``.
    processes : int, optional
        Number of local worker processes, without `client`. Default: one
        per core (``os.cpu_count()``), at most one per data set.
        ``processes=1`` runs the data sets one after the other in this
        process, with no pool. From a script, call it under ``if
        __name__ == '__main__':``: the workers start by importing the
        script again (Jupyter needs nothing).
    progress : bool, optional
        Show a progress bar (tqdm) over the data sets.
    errors : {'raise', 'return'}, optional
        What a data set on which `identify` raises does. Either way every
        data set is run, so one failure loses no other result.
        ``'raise'`` (default): once all have finished, the exception of
        the first failed data set (in input order) is raised; its
        ``results`` attribute holds the list of all results, with the
        exceptions in the failed slots, and a note names the failed
        data sets. ``'return'``: the list is returned, with each failure's
        exception object in its slot (test with ``isinstance(r,
        Exception)``). A numerical failure is not an exception: it is a
        result with ``success=False``, as in `identify`.
    **identify_kwargs
        Further arguments of `identify` (``method``, ``dt``, ``offsets``,
        ``integrators``, options of the method, ...), the same for every
        data set. Its ``progress`` bar is not available here.

    Returns
    -------
    list of IdentificationResult
        One per data set, in the order of `datasets` (with
        ``errors='return'``, exceptions in the slots that failed).

    Raises
    ------
    TypeError
        If `datasets` is not a list or tuple, a data set is not in a form
        `identify` accepts, an order is missing, or `client` is not a
        ``dask.distributed.Client``.
    ValueError
        If `datasets` is empty, a data set is malformed (the message names
        it, e.g. ``datasets[3]``), or `processes` or `errors` is invalid.
    ImportError
        If `client` is given and dask.distributed is not installed.

    Warns
    -----
    Warning
        Each identification's warnings (e.g. poorly determined
        parameters), issued again here in their own category, with the
        data set in front (``datasets[3]: ...``).

    See Also
    --------
    identify : one data set.
    as_experiments : the accepted forms of data.

    Notes
    -----
    Each identification runs single-threaded (module documentation), so
    on a machine with n cores up to n data sets run at once. Starting the
    local workers costs about a second (each imports sandwichctl); they
    are kept for the next call with the same number of processes, and
    shut down after five idle minutes. For a few short records,
    ``processes=1`` may be quicker. If a local worker dies (killed, out
    of memory), the data sets left unfinished are run once more on new
    workers; on a dask cluster, dask reschedules them.

    Examples
    --------
    Three copies of the Section 5 plant whose play has grown:

    >>> import sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> datasets = []
    >>> for k, scale in enumerate([1.0, 1.5, 2.0]):
    ...     co = plant.coefficients
    ...     co['D1'], co['D2'] = scale * co['D1'], scale * co['D2']
    ...     axis = sw.SandwichSystem.from_coefficients(**co)
    ...     u = sw.examples.paper_input(1500, seed=k)
    ...     datasets.append((u, axis.simulate(u).outputs))
    >>> results = sw.identify_many(datasets, **plant.orders, processes=2)

    The identified models are normalised (b0 = 1), so their thresholds
    are D1 / 1.5 of the plant's:

    >>> [round(r.model.coefficients['D1'], 3) for r in results]
    [0.333, 0.5, 0.667]
    >>> all(r.success for r in results)
    True
    """
    errors = check_option('errors', errors, ERRORS)
    progress = check_bool('progress', progress)
    if client is None:
        processes = _check_processes(processes)
    else:
        distributed = _import_distributed(client)
        if not isinstance(client, distributed.Client):
            raise TypeError(
                f"client must be a dask.distributed.Client (or None for "
                f"local processes); got {type(client).__name__} {client!r}")
        if processes is not None:
            raise ValueError(
                f"processes applies to local processes; with a client the "
                f"cluster's workers run the data sets (got processes="
                f"{processes!r}): leave processes=None")
    orders = _check_orders(na, nb, nc, nd, q1, q2)
    dt = identify_kwargs.pop('dt', True)
    jobs = _read_datasets(datasets, dt)
    options = dict(identify_kwargs)
    if client is not None:
        outcomes = _run_dask(client, jobs, orders, options, progress)
    elif min(processes, len(jobs)) == 1:
        outcomes = _run_serial(jobs, orders, options, progress)
    else:
        outcomes = _run_processes(jobs, orders, options, progress,
                                  min(processes, len(jobs)))
    results = []
    for i, out in enumerate(outcomes):
        if isinstance(out, BaseException):
            results.append(out)
            continue
        result, caught = out
        for message, category in caught:
            warnings.warn(f"datasets[{i}]: {message}", category,
                          stacklevel=2)
        results.append(result)
    failed = [i for i, r in enumerate(results) if isinstance(r, Exception)]
    if failed and errors == 'raise':
        exc = results[failed[0]]
        exc.results = results
        if hasattr(exc, 'add_note'):             # Python >= 3.11
            others = (f" (and {len(failed) - 1} more: datasets"
                      f"{failed[1:]})" if len(failed) > 1 else "")
            exc.add_note(
                f"identify_many: datasets[{failed[0]}] failed{others}; the "
                f"exception's `results` attribute holds every data set's "
                f"result, and errors='return' returns them")
        raise exc
    return results


# ----------------------------------------------------------------------
# Arguments and data, read in the calling process
# ----------------------------------------------------------------------
def _check_processes(processes):
    if processes is None:
        return os.cpu_count() or 1
    return check_int('processes', processes, 1)


def _check_orders(na, nb, nc, nd, q1, q2):
    values = dict(na=na, nb=nb, nc=nc, nd=nd, q1=q1, q2=q2)
    missing = [k for k in ('na', 'nb', 'nc', 'nd') if values[k] is None]
    if missing:
        raise TypeError(f"identify_many needs the orders {missing} (e.g. "
                        f"identify_many(datasets, na=2, nb=0, nc=2, nd=1))")
    return {k: check_order(k, v) for k, v in values.items()}


def _import_distributed(client):
    try:
        import distributed
    except ImportError as exc:
        raise ImportError(
            f"client={type(client).__name__} needs dask.distributed, which "
            f"is not installed: pip install 'sandwichctl[distributed]' (or "
            f"leave client=None to run in local processes)") from exc
    return distributed


def _read_datasets(datasets, dt):
    """[(pairs, dt)] with pairs a list of (u, y) float arrays, per set."""
    if isinstance(datasets, (str, bytes)) or not isinstance(
            datasets, collections.abc.Sequence):
        raise TypeError(
            f"datasets must be a list or tuple of data sets ((u, y) pairs, "
            f"records or lists of experiments); got "
            f"{type(datasets).__name__}"
            + (" (for one data set, use sw.identify)"
               if isinstance(datasets, ct.TimeResponseData) else ""))
    if len(datasets) == 0:
        raise ValueError("datasets is empty: give at least one data set")
    jobs = []
    for i, item in enumerate(datasets):
        where = f"datasets[{i}]"
        try:
            data = as_experiments(item, dt=None if dt is True else dt)
        except (TypeError, ValueError) as exc:
            raise type(exc)(f"{where}: {exc}") from None
        jobs.append(([(u, y) for u, y in data], data.dt))
    return jobs


# ----------------------------------------------------------------------
# The work, in a worker (or here)
# ----------------------------------------------------------------------
def _identify_job(pairs, dt, orders, options):
    """`identify` on one data set: (result, warnings). The result travels
    back by pickle (a SandwichSystem pickles as its parts)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        result = identify(list(pairs), dt=dt, **orders, **options)
    return result, [(str(w.message), w.category) for w in caught]


def _init_worker():
    """Worker initializer: one thread for BLAS, OpenMP and numba, and
    Ctrl-C left to the calling process (an interrupt in a terminal or a
    notebook reaches the whole process group: the caller cancels the
    pending data sets, and the workers stay usable)."""
    os.environ.update(SINGLE_THREAD)
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextmanager
def _environment(values):
    """Set environment variables for the duration of the block."""
    saved = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _bar(total, progress):
    return progress_bar(progress, total=total, desc='identify_many',
                        unit='set')


def _run_serial(jobs, orders, options, progress):
    outcomes = []
    with _bar(len(jobs), progress) as bar:
        for pairs, dt in jobs:
            try:
                outcomes.append(_identify_job(pairs, dt, orders, options))
            except Exception as exc:                # noqa: BLE001
                outcomes.append(exc)
            bar.update()
    return outcomes


def _run_processes(jobs, orders, options, progress, processes):
    """Run the jobs on the kept pool. If a worker dies (killed, out of
    memory, a crash), the pool breaks and every unfinished job fails with
    `BrokenExecutor`: those are run once more on a new pool."""
    outcomes = [None] * len(jobs)
    todo = list(range(len(jobs)))
    with _bar(len(jobs), progress) as bar:
        for _ in range(2):
            pool = _POOL.acquire(processes)
            broken = False
            try:
                broken = _run_on(pool, jobs, todo, outcomes, bar,
                                 orders=orders, options=options)
            finally:
                _POOL.release(pool, discard=broken)
            todo = [i for i in todo
                    if isinstance(outcomes[i], BrokenExecutor)]
            if not todo:
                break
    if getattr(sys.modules.get('__main__'), '__file__', None):
        for i in todo:          # broken twice, from a script
            outcomes[i] = BrokenExecutor(
                f"{outcomes[i]} (the workers start by importing the "
                f"calling script again: put the call under `if __name__ "
                f"== '__main__':`)")
    return outcomes


def _run_on(pool, jobs, todo, outcomes, bar, *, orders, options):
    """Run the jobs `todo` on `pool` into `outcomes`; True if it broke."""
    futures = {}
    try:
        # a new worker is started by `submit`: inside `_environment`, so
        # that its interpreter reads the single-thread environment before
        # it loads BLAS
        with _environment(SINGLE_THREAD):
            for i in todo:
                futures[pool.submit(_identify_job, *jobs[i], orders,
                                    options)] = i
    except BrokenExecutor as exc:     # a kept worker died since the last call
        for i in todo:
            outcomes[i] = exc
        for future in futures:
            future.cancel()
        return True
    broken = False
    try:
        for future in as_completed(futures):
            i = futures[future]
            exc = future.exception()
            outcomes[i] = exc if exc is not None else future.result()
            if isinstance(exc, BrokenExecutor):
                broken = True
            else:
                bar.update()
    except BaseException:             # e.g. KeyboardInterrupt: stop the rest
        for future in futures:        # (those running finish in the workers)
            future.cancel()
        raise
    return broken


class _Pool:
    """One pool of local workers, kept between calls.

    Starting a worker costs about a second (a fresh interpreter imports
    sandwichctl), so the pool is reused by the next call with the same
    number of processes, and shut down after `IDLE_TIMEOUT` seconds
    without work (or at exit). The ``spawn`` start method gives each
    worker a fresh interpreter, which reads the single-thread environment
    before it loads BLAS (a forked worker would inherit this process's
    BLAS threads, and forking a process with threads is unsafe).
    """

    def __init__(self):
        self._lock = threading.Lock()
        self._executor = None          # the kept pool
        self._processes = None
        self._users = {}               # executor -> calls using it
        self._timer = None

    def _new(self, processes):
        return ProcessPoolExecutor(
            max_workers=processes, initializer=_init_worker,
            mp_context=multiprocessing.get_context('spawn'))

    def acquire(self, processes):
        """A pool of `processes` workers for one call."""
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
            kept = self._executor
            if kept is not None and self._processes != processes \
                    and kept not in self._users:
                kept.shutdown(wait=False, cancel_futures=True)
                kept = self._executor = None
            if kept is None:
                executor = self._executor = self._new(processes)
                self._processes = processes
            elif self._processes == processes:
                executor = kept
            else:               # another call uses the kept pool: a one-off
                executor = self._new(processes)
            self._users[executor] = self._users.get(executor, 0) + 1
            return executor

    def release(self, executor, discard=False):
        """The call is done with `executor`; `discard` a broken pool (or
        one whose work was interrupted) rather than keep it."""
        with self._lock:
            if discard and executor is self._executor:
                self._executor = self._processes = None
            self._users[executor] -= 1
            if self._users[executor]:
                return
            del self._users[executor]
            if executor is self._executor:
                self._timer = threading.Timer(IDLE_TIMEOUT, self.shutdown)
                self._timer.daemon = True
                self._timer.start()
            else:
                executor.shutdown(wait=False, cancel_futures=True)

    def shutdown(self, wait=False):
        """Shut the kept pool down if no call is using it (the idle timer
        calls this; so may a benchmark that times a cold start)."""
        with self._lock:
            kept = self._executor
            if kept is not None and kept not in self._users:
                self._executor = self._processes = None
            else:
                kept = None
        if kept is not None:
            kept.shutdown(wait=wait, cancel_futures=True)


_POOL = _Pool()


def _run_dask(client, jobs, orders, options, progress):
    from distributed import as_completed as dask_completed
    data = client.scatter([pairs for pairs, _ in jobs], hash=False)
    futures = client.map(_identify_job, data, [dt for _, dt in jobs],
                         orders=orders, options=options, pure=False)
    index = {future.key: i for i, future in enumerate(futures)}
    outcomes = [None] * len(jobs)
    try:
        with _bar(len(jobs), progress) as bar:
            for future in dask_completed(futures):
                i = index[future.key]
                if future.status == 'error':
                    outcomes[i] = future.exception()
                else:
                    outcomes[i] = future.result()
                bar.update()
    except BaseException:             # e.g. KeyboardInterrupt: stop the rest
        client.cancel(futures + list(data))
        raise
    return outcomes
