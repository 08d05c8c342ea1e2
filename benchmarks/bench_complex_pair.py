"""Structures that cannot hold the linear fit: a complex pair in two
first-order blocks (issue 24, item 1).

Each case of a seeded family is a sandwich whose L1 has a complex pole
pair r exp(+-j w) (r in 0.75..0.9, w in 0.12..0.35 rad) and whose L2 is a
fast real pole, with a small backlash and output noise; it is identified
with ``na = 1, nb = 0, nc = 1, nd = 0``: the linear output-error fit of
two poles has the complex pair, which two first-order blocks cannot hold.
A second family has two real poles (the structure holds its linear fit;
the search must be unchanged there). The table gives, on fresh
validation data from the same plant (percent fit, as MATLAB's
``compare``):

- ``linear``: the unrestricted linear fit (``res.linear['model']``);
- ``held``: the best linear model the structure holds
  (``res.linear['held']['model']``; '-' when the structure holds the
  linear fit);
- ``sandwich``: the identified model, and ``success``.

Run: python benchmarks/bench_complex_pair.py [--cases 8] [--n 3000]
"""

import os

for _var in ('OMP_NUM_THREADS', 'OPENBLAS_NUM_THREADS', 'MKL_NUM_THREADS',
             'NUMBA_NUM_THREADS'):
    os.environ.setdefault(_var, '1')

import argparse                                            # noqa: E402
import sys                                                 # noqa: E402
import warnings                                            # noqa: E402

import numpy as np                                         # noqa: E402

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import print_table                            # noqa: E402

ORDERS = dict(na=1, nb=0, nc=1, nd=0, q1=1, q2=0)


def plant(seed, complex_pair=True):
    """A seeded sandwich: L1 with a complex pair (or two real poles), L2
    a fast real pole, a small backlash."""
    rng = np.random.default_rng(seed)
    r, w = rng.uniform(0.75, 0.9), rng.uniform(0.12, 0.35)
    if complex_pair:
        a = [-2 * r * np.cos(w), r * r]
    else:
        p1, p2 = rng.uniform(0.5, 0.9), rng.uniform(0.1, 0.4)
        a = [-(p1 + p2), p1 * p2]
    c = [-rng.uniform(0.0, 0.4)]
    gain = (1 + sum(a)) / 1.0                  # L1 of unit static gain
    return sw.SandwichSystem.from_coefficients(
        a=a, b=[gain], c=c, d=[1 + c[0]], m1=1.0, m2=rng.uniform(0.9, 1.1),
        D1=rng.uniform(0.02, 0.06), D2=rng.uniform(0.02, 0.06), q1=1, q2=0)


def data(sys_, n, seed, snr=40.0):
    """A lowpass input of unit spread and the noisy output."""
    u = sw.data.excitation('lowpass', n, rng=np.random.default_rng(seed))
    y = sys_.simulate(u).outputs
    return u, sw.examples.add_noise(y, snr, seed=seed + 7)


def fit_on(model, u, y):
    """Validation fit (percent) of a model (sandwich or linear); -inf
    for one whose output is not finite."""
    try:
        return float(sw.compare(model, u, y, plot=False).fit)
    except ValueError:
        return -np.inf


def run(seed, n, complex_pair):
    sys_ = plant(seed, complex_pair)
    u, y = data(sys_, n, 1000 + seed)
    uv, yv = data(sys_, n, 2000 + seed)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        res = sw.identify(u, y, **ORDERS)
        held = res.linear.get('held')
        return dict(
            case=f"{'pair' if complex_pair else 'real'} {seed}",
            linear=fit_on(res.linear['model'], uv, yv),
            held=None if held is None else fit_on(held['model'], uv, yv),
            sandwich=fit_on(res.model, uv, yv), success=res.success,
            message=res.message)


def _pct(value, fmt='.2f'):
    """A fit in the table: '-' for none, '< -1e4' for a diverged one."""
    if value is None:
        return '-'
    return format(value, fmt) if value > -1e4 else '< -1e4'


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--cases', type=int, default=8)
    ap.add_argument('--n', type=int, default=3000)
    ap.add_argument('--messages', action='store_true')
    args = ap.parse_args()
    rows = [run(seed, args.n, pair) for pair in (True, False)
            for seed in range(args.cases)]
    print_table(
        ['case', 'linear %', 'held %', 'sandwich %', 'sw - held',
         'success'],
        [[r['case'], _pct(r['linear']), _pct(r['held']),
          _pct(r['sandwich']),
          '-' if r['held'] is None else _pct(r['sandwich'] - r['held'],
                                             '+.2f'),
          str(r['success'])] for r in rows])
    if args.messages:
        for r in rows:
            print(f"{r['case']}: {r['message']}")


if __name__ == '__main__':
    main()
