"""Section 6 claim on the simulated X-Y stage axis (issues 6 and 14).

The paper reports a maximum relative modelling error below 11 % for its
bundle method on the X-Y stage, without saying whether it scores the
model's free-run simulation or its one-step-ahead prediction. This script
identifies the simulated axis `sw.examples.xy_stage` (encoder-quantised,
noisy speed measurement) with the paper's method and Section 6 settings
(eta0 = 0.00116, theta0 = [0, 0, 0, 0, 1, 1, 0.001, 0.001, 0]) and with
the library's default method ``'oe'``, and validates each model on a
fresh record (new input, new noise) of 4000 samples. For each record
length, method and scoring (free run: ``sw.compare(model, u, y)``; one
step ahead: ``sw.compare(model, u, y, horizon=1)``) it prints, per seed,
the maximum relative error ``sw.max_relative_error`` (a model with
unstable L1 or L2 counts as inf in free run), then the medians over the
seeds. 6700 samples is the length after which Section 6 reports
convergence.

Run: python benchmarks/bench_xy_stage.py [--seeds 5] [--samples 6700 20000]
(1-3 minutes, most of it 'oe' on 20,000 samples).
"""

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import print_table                            # noqa: E402


def fmt_err(value):
    return 'unstable' if not np.isfinite(value) else f"{value:.2%}"


def fmt_fit(value):
    return '-' if not np.isfinite(value) else f"{value:.1f}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--seeds', type=int, default=5)
    ap.add_argument('--samples', type=int, nargs='+', default=[6700, 20000])
    ap.add_argument('--validation', type=int, default=4000)
    args = ap.parse_args()
    seeds = list(range(args.seeds))
    rows = []
    scorings = (('free run', ''), ('one step', 'one_step_'))
    for n in args.samples:
        per = {(label, score): {'err': [], 'fit': [], 'time': []}
               for label in sw.paper.section6.METHODS
               for score, _ in scorings}
        for seed in seeds:
            run = sw.paper.section6.section6_run(n_samples=n,
                                                 n_validation=args.validation,
                                                 seed=seed)
            for label, val in run['validation'].items():
                for score, key in scorings:
                    d = per[(label, score)]
                    d['err'].append(val[key + 'max_relative_error'])
                    d['fit'].append(val[key + 'fit'])
                    d['time'].append(run['results'][label].elapsed)
        for (label, score), d in per.items():
            err, fit = np.array(d['err']), np.array(d['fit'])
            rows.append([n, label, score] + [fmt_err(e) for e in err]
                        + [fmt_err(np.median(err)), fmt_fit(np.median(fit)),
                           f"{int(np.sum(err < 0.11))}/{err.size}",
                           f"{int(np.sum(err < 0.03))}/{err.size}",
                           f"{np.median(d['time']):.2f}"])
    print("X-Y stage axis (Section 6): maximum relative modelling error "
          "max|y - yhat| / max|y| on fresh validation data "
          f"({args.validation} samples, dt = 0.5 ms), of the free-run "
          "simulation and of the one-step-ahead prediction\n")
    print_table(['N', 'method', 'scored as']
                + [f"seed {s}" for s in seeds]
                + ['median', 'median fit %', '< 11%', '< 3%', 'time s'],
                rows)


if __name__ == '__main__':
    main()
