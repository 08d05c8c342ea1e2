"""Section 5 claims, measured over 10 seeds (issue 3).

For the paper's bundle method and the traditional gradient baseline, with
the Section 5 settings, noise-free and at SNR 46.5 (variance ratio), this
prints the normalised parameter error ||theta_hat - theta|| / ||theta|| at
2k, 5k, 10k and 20k samples, the number of samples after which the error
stays under 5%, and the cost per sample (median over seeds). The gradient
baseline is shown both with the nonsmooth samples skipped (the paper's
description) and without skipping.

Run: python benchmarks/bench_section5.py [--seeds 10] [--samples 20000]
"""

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import print_table                            # noqa: E402

CHECKPOINTS = (2000, 5000, 10000, 20000)


def settle(err, level=0.05):
    """Samples after which err stays below level (None if it never does)."""
    above = np.flatnonzero(~(err < level))
    if above.size == 0:
        return 0
    return None if above[-1] == err.size - 1 else int(above[-1] + 1)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--seeds', type=int, default=10)
    ap.add_argument('--samples', type=int, default=20000)
    args = ap.parse_args()
    methods = {
        'bundle': ('bundle', sw.paper.section5.PAPER_SETTINGS['bundle']),
        'gradient': ('gradient', sw.paper.section5.PAPER_SETTINGS['gradient']),
        'gradient, no skip': ('gradient', dict(
            sw.paper.section5.PAPER_SETTINGS['gradient'], skip_nonsmooth=False)),
    }
    rows = []
    for case, snr in (('noise-free', None), ('SNR 46.5', 46.5)):
        per = {m: {'err': [], 'settle': [], 'us': [], 'finite': True,
                   'fail': 0} for m in methods}
        for seed in range(args.seeds):
            import warnings
            with warnings.catch_warnings():
                warnings.simplefilter('ignore', RuntimeWarning)
                run = sw.paper.section5.section5_run(args.samples, seed=seed, snr=snr,
                                            methods=methods)
            for m, res in run['results'].items():
                err = res.parameter_error(run['theta_true'])
                full = np.full(args.samples, np.nan)
                full[:err.size] = err
                per[m]['err'].append(full)
                per[m]['settle'].append(settle(full))
                per[m]['us'].append(res.elapsed / res.nit * 1e6)
                per[m]['finite'] &= bool(np.all(np.isfinite(res.history)))
                per[m]['fail'] += not res.success
        for m in methods:
            E = np.array(per[m]['err'])
            # a diverged run counts as infinite error from then on
            E = np.where(np.isnan(E), np.inf, E)
            cps = [np.median(E[:, c - 1]) if c <= args.samples else np.nan
                   for c in CHECKPOINTS]
            st = per[m]['settle']
            reached = [s for s in st if s is not None]
            rows.append([
                case, m,
                *(f"{v:.2%}" for v in cps),
                f"{np.max(E[:, -1]):.2%}",
                f"{len(reached)}/{len(st)}",
                f"{int(np.median(reached))}" if reached else 'never',
                f"{np.median(per[m]['us']):.1f}",
                'yes' if per[m]['finite'] else 'NO',
                per[m]['fail']])
    print(f"Section 5 over {args.seeds} seeds, {args.samples} samples each; "
          f"errors are medians over seeds of ||theta_hat - theta||/||theta||"
          f" (inf: diverged)\n")
    print_table(['case', 'method', 'err@2k', 'err@5k', 'err@10k', 'err@20k',
                 'worst@20k', 'reach 5%', 'median settle', 'us/sample',
                 'finite', 'diverged'], rows)


if __name__ == '__main__':
    main()
