"""Long records (issue 24, item 7): identify on N = 1e6 in <= 5 s.

Prints, in one run, the new long-record path of ``sw.identify`` (the
search on the leading 50,000 samples, the refinement on all of them,
`_long`) side by side with the exhaustive search on every sample that
records of up to 200,000 samples still get (forced here through the
private switch ``_long.LONG_RECORD``):

(a) the paper's plant, N = 1e6, SNR 100, one row per seed: the median
    time of repeated runs, the simulations of the whole record (calls of
    the simulation kernels on all N samples) and every simulated sample
    in record lengths (the leading samples' runs included; the linear
    fits, by scipy's lfilter, are not counted), the fit and the
    parameter error against the true plant;
(b) seeded random plants of ``sw.data.random_case`` (SNR 100) at
    N = 1e5, with the threshold lowered so that the long-record path
    runs there too, and optionally (``--n-random``) at other lengths;
(c) with ``--baseline-seeds``, the linear baseline of the whole record
    (stage 2 of the long-record path) on random plants at N = 1e6: the
    output-error fit from the ARX start on all the samples (what the
    path did before) against the one from the fit of the leading
    `_long.LONG_HEAD` samples (what it does now): iterations, time and
    cost. ``--arx-repeat`` adds rows of the long-record path with that
    baseline from the ARX start, to compare in one run.

Run: python benchmarks/bench_long_records.py [--seeds 3] [--repeat 3]
     [--old-repeat 1] [--random-seeds 0 1] [--n-random 100000]
     [--baseline-seeds 0 1 2 3 4 5 6 7] [--arx-repeat 3]
     [--serial-repeat 3] [--generic-repeat 3] [--heads 20000 10000]
     [--whole-path-repeat 3]
(``--old-repeat 0``: the long-record path alone; ``--serial-repeat``
adds rows of the long-record path on one thread, `_long.WORKERS` = 1;
``--generic-repeat`` rows with the simulation kernels for any orders
and the linear fits' normal equations from their Jacobian, as before the
kernels compiled for the orders and the lagged correlations of a long
record (`_predictor.SPECIALIZE_FROM`); ``--heads`` rows with the search on other
numbers of leading samples, `_long.LONG_HEAD`; ``--whole-path-repeat``
rows with stage 1's smoothed path (step 8) on all the leading samples
instead of the first `_long.PATH_SAMPLES` of them, as before
2026-11-27. The timings are medians
of the repeats: the first run of a set of orders on a machine also
compiles its kernels, about 4 s, which numba's cache then keeps.)
"""

import argparse
import contextlib
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from sandwichctl.identification import _long, _predictor  # noqa: E402
from _timing import median_time, print_table               # noqa: E402

TARGET = 5.0                    # seconds at N = 1e6


class Counter:
    """Counts the samples each simulation kernel of `_predictor` runs
    over (the kernel `_predictor._kernel` chooses: compiled for the
    orders, or for any; its padded input is the third argument)."""

    def __init__(self, n):
        self.n, self.full, self.samples = n, 0, 0

    @contextlib.contextmanager
    def counting(self):
        choose = _predictor._kernel

        def chosen(o, kind, n, *rings):
            kernel = choose(o, kind, n, *rings)

            def counted(theta, o, u, *args):
                size = u.size - _predictor.padding(o)
                self.samples += size
                self.full += size >= self.n
                return kernel(theta, o, u, *args)
            return counted

        _predictor._kernel = chosen
        try:
            yield self
        finally:
            _predictor._kernel = choose


@contextlib.contextmanager
def path(long, threshold=None, arx=False, serial=False, head=None,
         generic=False, whole_path=False):
    """The long-record path (at `threshold`, default the library's) or
    the exhaustive search (``long=False``); with `arx`, the long-record
    path's baseline of all the samples from the ARX start (as before it
    started from the leading samples' fit); with `serial`, on one thread
    (`_long.WORKERS` = 1); with `head`, the search on that many leading
    samples (`_long.LONG_HEAD`); with `generic`, the simulation kernels for
    any orders and the linear fits' Jacobian on every record
    (`_predictor.SPECIALIZE_FROM` = inf, as before the kernels compiled
    for the orders and `_linear._lagged_normal`); with `whole_path`,
    stage 1's smoothed path on all its samples (`_long.PATH_SAMPLES` =
    None)."""
    saved, carried, workers = (_long.LONG_RECORD, _long._carried_linear,
                               _long.WORKERS)
    saved_head, saved_from = _long.LONG_HEAD, _predictor.SPECIALIZE_FROM
    saved_path = _long.PATH_SAMPLES
    if whole_path:
        _long.PATH_SAMPLES = None
    _long.LONG_RECORD = (threshold or saved) if long else np.inf
    if head:
        _long.LONG_HEAD = head
    if arx:
        _long._carried_linear = lambda *args: None
    if serial:
        _long.WORKERS = 1
    if generic:
        _predictor.SPECIALIZE_FROM = np.inf
    try:
        yield
    finally:
        _long.LONG_RECORD, _long._carried_linear = saved, carried
        _long.WORKERS, _long.LONG_HEAD = workers, saved_head
        _predictor.SPECIALIZE_FROM = saved_from
        _long.PATH_SAMPLES = saved_path


def identify(u, y, orders):
    with warnings.catch_warnings():      # speed and accuracy only
        warnings.simplefilter('ignore')
        return sw.identify(u, y, **orders)


def measure(u, y, plant, repeat, **kw):
    """(median time, whole-record simulations, record lengths simulated,
    result, parameter error) of one path, every run counted (the counts
    are the same in each)."""
    runs = []
    counter = Counter(u.size)
    with path(**kw), counter.counting():
        t = median_time(lambda: runs.append(identify(u, y, plant.orders)),
                        repeat=repeat, warmup=0)
    res = runs[-1]
    err = sw.parameter_error(res.theta, plant.theta)
    return (t, counter.full // repeat, counter.samples / repeat / u.size,
            res, err)


def rows_of(label, u, y, plant, args, threshold=None):
    """The table rows of one record, a row per path asked for."""
    out = []
    for name, kw, repeat in (
            [('long-record', {}, args.repeat),
             ('long, any-order kernels', dict(generic=True),
              args.generic_repeat),
             ('long, one thread', dict(serial=True), args.serial_repeat),
             ('long, ARX baseline', dict(arx=True), args.arx_repeat),
             ('long, whole smoothed path', dict(whole_path=True),
              args.whole_path_repeat)]
            + [(f'long, head {h:,}', dict(head=h), args.repeat)
               for h in args.heads]
            + [('exhaustive', dict(long=False), args.old_repeat)]):
        if not repeat:
            continue
        t, full, lengths, res, err = measure(
            u, y, plant, repeat, **{'long': True, 'threshold': threshold,
                                    **kw})
        taken = res.long_record is not None
        out.append([label, f'{u.size:,}', name, 'yes' if taken else 'no',
                    repeat, f'{t:.2f} s', full, f'{lengths:.1f}',
                    f'{res.fit:.4f}', f'{res.linear["fit"]:.4f}',
                    f'{err:.3e}', 'yes' if res.success else 'no'])
    return out


HEADERS = ['case', 'N', 'path', 'long path taken', 'repeats',
           'median time', 'whole-record sims', 'record lengths simulated',
           'fit %', 'linear fit %', 'parameter error', 'success']


def paper(args):
    plant = sw.examples.paper_plant()
    rows = []
    for seed in range(args.seeds):
        u = sw.examples.paper_input(1_000_000, seed=seed)
        y = sw.examples.add_noise(plant.simulate(u).outputs, 100,
                                  seed=seed + 1000)
        rows += rows_of(f'paper, seed {seed}', u, y, plant, args)
    print(f"(a) the paper's plant, N = 1e6, SNR 100: the long-record path "
          f"against the exhaustive search (target <= {TARGET:g} s)\n")
    print_table(HEADERS, rows)
    times = [float(r[5].split()[0]) for r in rows if r[2] == 'long-record']
    print(f"\nlong-record path: worst median {max(times):.2f} s, target "
          f"met: {'yes' if max(times) <= TARGET else 'no'}")


def random_plants(args):
    rows = []
    threshold = min(args.n_random // 2, _long.LONG_RECORD)
    for seed in args.random_seeds:
        case = sw.data.random_case(seed, n=args.n_random, snr=100)
        rows += rows_of(f'random_case({seed})', case.u, case.y, case.plant,
                        args, threshold=threshold)
    print(f"\n(b) seeded random plants (SNR 100), the long-record path "
          f"above {threshold:,} samples (the threshold lowered to N / 2 "
          f"where that is below the library's)\n")
    print_table(HEADERS, rows)


def baseline_starts(seeds, n=1_000_000):
    """Table (c): the whole record's linear baseline from either start."""
    from sandwichctl.identification._linear import fit_oe
    from sandwichctl.identification._search import step1_units, Task
    from sandwichctl.identification._options import OEOptions
    rows, head = [], _long.LONG_HEAD
    for seed in seeds:
        case = sw.data.random_case(seed, n=n, snr=100)
        o = case.plant.orders
        task = Task([case.u], [case.y], o, OEOptions())
        scaled = step1_units(task)
        u, y = scaled.u[0], scaled.y[0]
        kw = dict(max_iter=task.opt.max_iter, tol=task.opt.tol)
        t = time.perf_counter()
        fa = fit_oe(u, y, task.shape, 0, **kw)
        ta = time.perf_counter() - t
        short = fit_oe(u[:head], y[:head], task.shape, 0, **kw)
        t = time.perf_counter()
        fh = fit_oe(u, y, task.shape, 0, start=(short['B'], short['Ff']),
                    **kw)
        th = time.perf_counter() - t
        rows.append([f'random_case({seed})', f'{n:,}', fa['nit'],
                     f'{ta:.2f} s', f'{fa["cost"]:.8g}', short['nit'],
                     fh['nit'], f'{th:.2f} s', f'{fh["cost"]:.8g}',
                     f'{(fh["cost"] - fa["cost"]) / fa["cost"]:+.1e}'])
    print(f"\n(c) the linear baseline of the whole record (no integrator, "
          f"scaled data): Levenberg-Marquardt from the ARX start against "
          f"from the fit of the leading {head:,} samples (its own "
          f"iterations on those apart)\n")
    print_table(['case', 'N', 'ARX start: iterations', 'time', 'cost',
                 'head fit: iterations on the head', 'then on all', 'time',
                 'cost', 'cost change'], rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--seeds', type=int, default=3)
    ap.add_argument('--repeat', type=int, default=3)
    ap.add_argument('--old-repeat', type=int, default=1)
    ap.add_argument('--random-seeds', type=int, nargs='*', default=[0, 1])
    ap.add_argument('--n-random', type=int, default=100_000)
    ap.add_argument('--baseline-seeds', type=int, nargs='*', default=[])
    ap.add_argument('--arx-repeat', type=int, default=0,
                    help="also run the long-record path with the baseline "
                    "of all the samples from the ARX start (before)")
    ap.add_argument('--generic-repeat', type=int, default=0,
                    help="also run the long-record path with the "
                    "simulation kernels for any orders (before)")
    ap.add_argument('--serial-repeat', type=int, default=0,
                    help="also run the long-record path on one thread "
                    "(_long.WORKERS = 1)")
    ap.add_argument('--whole-path-repeat', type=int, default=0,
                    help="also run the long-record path with stage 1's "
                    "smoothed path on all its samples (before)")
    ap.add_argument('--heads', type=int, nargs='*', default=[],
                    help="also run the long-record path with its search "
                    "on these many leading samples (_long.LONG_HEAD)")
    args = ap.parse_args()
    print(f"Long records; {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.2f} at the start; medians of repeated runs "
          f"(the exhaustive search once by default: it takes 20 s and more "
          f"per run)\n")
    if args.seeds:
        paper(args)
    if args.random_seeds:
        random_plants(args)
    if args.baseline_seeds:
        baseline_starts(args.baseline_seeds)


if __name__ == '__main__':
    main()
