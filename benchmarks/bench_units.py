"""Units invariance of `sw.identify` on random plants.

Issue 12's target: the validation fit must not move by more than 0.2
points when u and y are rescaled, independently, by factors from 1e-4 to
1e4. For each case of the robustness family (`sandwichctl.data`, the
same cases as `bench_robustness.py --seed S`) this identifies the model
from (su * u, sy * y) for the scalings below, simulates each model on a
common validation input (white noise, 3,000 samples, the estimation
input's spread) mapped into its units, and compares the fits against the
true plant's output there, back in the original units.

It reports the spread (largest minus smallest validation fit) per case:
its distribution, how many cases exceed 0.2 points, and the worst ones.
With ``--unrounded`` the scaled data are not rounded to 2**-30 (the
search then sees the units in the last bits of its data: this is what
the rounding in `sandwichctl.identification._data.scaled` fixed).

Run: python benchmarks/bench_units.py [--cases 40] [--seed 0]
                                      [--processes 2] [--unrounded]
"""

import os

for _var in ('OMP_NUM_THREADS', 'OPENBLAS_NUM_THREADS', 'MKL_NUM_THREADS',
             'NUMBA_NUM_THREADS'):
    os.environ.setdefault(_var, '1')       # one core per worker process

import argparse                                            # noqa: E402
import multiprocessing                                     # noqa: E402
import sys                                                 # noqa: E402
import time                                                # noqa: E402
import warnings                                            # noqa: E402

import numpy as np                                         # noqa: E402

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from sandwichctl.data import random_case, family_specs     # noqa: E402
from _timing import print_table                            # noqa: E402

#: (scale of u, scale of y); the first is the data as generated.
SCALINGS = ((1.0, 1.0), (1e-4, 1e-4), (1e4, 1e-4), (1e-4, 1e4), (1e4, 1e4))
#: The target: largest change of the validation fit, in points.
TARGET = 0.2


def _unrounded():
    """Scale without rounding (the behaviour before the rounding)."""
    from sandwichctl.identification import batch, linear
    batch.scaled = linear.scaled = lambda x, s: np.asarray(x, float) / s


def _case(args):
    spec, unrounded = args
    if unrounded:
        _unrounded()
    warnings.simplefilter('ignore')
    case = random_case(**spec)
    rng = np.random.default_rng(spec['seed'] % 2 ** 32)
    u_val = np.std(case.u) * rng.standard_normal(3000)
    y_val = case.plant.simulate(u_val).outputs
    fits, start = [], time.perf_counter()
    for su, sy in SCALINGS:
        res = sw.identify(case.u * su, case.y * sy, **case.orders)
        y_hat = res.model.simulate(u_val * su).outputs / sy
        fits.append(float(sw.fit_percent(y_val, y_hat)))
    return dict(seed=spec['seed'], kind=spec['input_kind'],
                snr=case.snr, n=case.n, fits=fits,
                spread=max(fits) - min(fits),
                time=time.perf_counter() - start)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--cases', type=int, default=40)
    ap.add_argument('--seed', type=int, default=0)
    ap.add_argument('--processes', type=int, default=2)
    ap.add_argument('--unrounded', action='store_true')
    a = ap.parse_args()
    specs = family_specs(a.cases, seed=a.seed)
    start = time.perf_counter()
    with multiprocessing.Pool(a.processes) as pool:
        rows = pool.map(_case, [(s, a.unrounded) for s in specs],
                        chunksize=1)
    wall = time.perf_counter() - start
    spreads = np.array([r['spread'] for r in rows])
    print(f"bench_units: {len(rows)} cases (family seed {a.seed}), "
          f"scalings (su, sy) {list(SCALINGS)}, "
          f"{'unrounded' if a.unrounded else 'rounded'} scaled data, "
          f"wall time {wall:.0f} s\n")
    print_table(
        ['cases', f'spread > {TARGET}', 'median spread', '90th pct',
         'max spread'],
        [[len(rows), int(np.sum(spreads > TARGET)),
          f"{np.median(spreads):.2g}", f"{np.quantile(spreads, 0.9):.2g}",
          f"{spreads.max():.3g}"]])
    worst = sorted(rows, key=lambda r: -r['spread'])[:5]
    print('\nLargest spreads (validation fit % under each scaling)')
    print_table(['seed', 'input', 'snr', 'N', 'spread']
                + [f"{su:g},{sy:g}" for su, sy in SCALINGS],
                [[r['seed'], r['kind'], r['snr'], r['n'],
                  f"{r['spread']:.3g}"] + [f"{f:.3f}" for f in r['fits']]
                 for r in worst])


if __name__ == '__main__':
    main()
