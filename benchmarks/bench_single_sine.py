"""Inputs that do not determine L1: one sinusoid, two, a multisine.

Each case is a seeded random plant (``sw.data.random_case``, its true
orders) identified from an input of its own: one sinusoid (a period of
20-200 samples), two, or eight, at the spread of the case's own input,
with 1 % output noise (N = 3000). With ``--bits 16`` the input is
rounded to a grid of 2^16 steps over its range first, as a DAC or a
logger rounds it: the recurrence then holds only up to the rounding
(`sandwichctl.identification._data.quantum`). The table gives:

- ``need``: the coefficients of L1 (na + nb + 1 less its integrators),
  and ``order``: how many the input can determine, the taps of the
  shortest recurrence it satisfies
  (`sandwichctl.identification._data.excitation_order`; a sinusoid
  satisfies one of two);
- ``fit``: the fit on the estimation data;
- ``fresh``: the model's fit on fresh broadband data from the same plant
  (the case's own input, noise-free), which the data given could not
  tell;
- ``success``, ``before``: what it was before the check on the input's
  order (that check is the last of ``verdict``'s list, so a failure
  whose message starts with it failed on it alone), and the first
  reason of a failure.

Run: python benchmarks/bench_single_sine.py [--cases 8] [--n 3000]
                                           [--bits 16]
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
from sandwichctl.identification._data import (             # noqa: E402
    excitation_order)
from _timing import print_table                            # noqa: E402


def sines(count, n, spread, rng):
    """`count` sinusoids of periods 20-200 samples and random phases,
    scaled to the standard deviation `spread`."""
    t = np.arange(n)
    u = sum(np.sin(2 * np.pi * t / rng.uniform(20, 200)
                   + rng.uniform(0, 2 * np.pi)) for _ in range(count))
    return u * spread / np.std(u)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--cases', type=int, default=8)
    ap.add_argument('--n', type=int, default=3000)
    ap.add_argument('--bits', type=int, default=0,
                    help='round the input to this many bits (0: not)')
    args = ap.parse_args()
    rows, told = [], {}
    for seed in range(args.cases):
        case = sw.data.random_case(seed, n=args.n, snr=100)
        plant, rng = case.plant, np.random.default_rng([seed, 0x5153])
        fresh = plant.simulate(case.u).outputs
        for count in (1, 2, 8):
            u = sines(count, args.n, 1.4 * np.std(case.u), rng)
            if args.bits:
                step = np.ptp(u) / 2 ** args.bits
                u = step * np.round(u / step)
            y = plant.simulate(u).outputs
            y = y + 0.01 * np.std(y) * rng.standard_normal(args.n)
            with warnings.catch_warnings():
                warnings.simplefilter('ignore')
                res = sw.identify(u, y, **plant.orders)
                check = sw.compare(res.model, case.u, fresh, plot=False)
            i1 = res.integrators['L1']
            o = plant.orders
            need = o['na'] - i1 + o['nb'] + 1
            reason = ('' if res.success else
                      res.message.split(' (')[0].split(':')[0][:48])
            before = res.success or reason.startswith('the input satisfies')
            told.setdefault(count, []).append((before, res.success,
                                               float(check.fit)))
            rows.append([seed, count, need, excitation_order([u], need),
                         f"{res.fit:.1f}", f"{float(check.fit):.1f}",
                         res.success, before, reason])
    print(f"Random plants identified from sinusoids (N = {args.n}, 1 % "
          f"output noise" + (f", the input rounded to {args.bits} bits"
                              if args.bits else "") + "); fits in %\n")
    print_table(['seed', 'sines', 'need', 'order', 'fit', 'fresh',
                 'success', 'before', 'first reason of a failure'], rows)
    print("\nsuccess=True (before the check -> now), and the fresh fits "
          "of the models it was True for before:")
    for count, got in told.items():
        fits = [f for b, _, f in got if b]
        print(f"  {count} sinusoid(s): {sum(b for b, _, _ in got)} -> "
              f"{sum(s for _, s, _ in got)} of {len(got)}; fresh fit "
              + (f"median {np.median(fits):.1f}, worst {min(fits):.1f}"
                 if fits else "-"))


if __name__ == '__main__':
    main()
