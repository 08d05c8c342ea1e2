"""An integrator after the play: the default `identify` against the block
chosen by hand, on fresh data.

A valve whose linkage has play drives a hydraulic cylinder: the spool (L1)
moves the flow through the play, and the cylinder's position integrates
the flow (L2 has a pole at z = 1). Each case is
``sw.data.random_case(seed, integrating='L2', snr=1e4, n=N)`` (random
orders, poles, zeros, asymmetric backlash and units; 1 % output noise;
a DC-blocked input), identified with the plant's true orders by

- ``identify`` as it is called by default (``integrator_block='auto'``),
- ``identify(..., integrators=1, integrator_block='L2')`` (the block by
  hand),
- ``identify(..., integrator_block='L1')`` (the block of the default
  before ``'auto'``),

and the linear output-error model of the same total orders (with the
integrators of the default's baseline). Every model is scored by its fit
(percent, free run from rest) on a fresh record of the same plant: a new
input of the same kind, DC-blocked the same way, with new noise. The
table gives the fits, where the default put the integrator, whether it
said success, and the default's cost on the identification record over
that of ``sw.refine`` started at the plant itself (near 1: the search
found the plant's basin). The fresh record's fit is a noisy score for an
integrating plant: the integrator accumulates small errors of the gain,
so models of the same cost can validate a few points apart (the plant's
own refined model too).

Run: python benchmarks/bench_valve.py [--cases 12] [--seed0 0] [--n 4000]
"""

import argparse
import os
import statistics
import sys
import warnings

import numpy as np
from scipy.signal import lfilter
import control as ct

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import print_table                            # noqa: E402

#: Variance ratio of the output noise: 1 % of the output's spread.
SNR = 1e4


def fresh_record(case, seed):
    """A validation record of the case's plant: a new input of its kind,
    DC-blocked (1 - z^-1) / (1 - r z^-1) and scaled as the case's, its
    output with new noise of the same level."""
    rng = np.random.default_rng([seed, 0x7a1e])
    e = sw.data.excitation(case.input_kind, case.n, rng)
    e = lfilter([1.0, -1.0], [1.0, -rng.uniform(0.98, 0.995)], e)
    u = case.scale_u * (e - e.mean()) / np.std(e)
    y = case.plant.simulate(u).outputs
    return u, y + rng.standard_normal(u.size) * np.std(y) / np.sqrt(SNR)


def run(seed, n):
    case = sw.data.random_case(seed, integrating='L2', snr=SNR, n=n)
    u_val, y_val = fresh_record(case, seed)
    o = case.orders
    runs = {'default': {}, 'L2 by hand': dict(integrators=1,
                                              integrator_block='L2'),
            'L1 (before)': dict(integrator_block='L1')}
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        for name, kw in runs.items():
            res = sw.identify(case.u, case.y, **o, **kw)
            y_hat = res.model.simulate(u_val).outputs
            out[name] = (sw.fit_percent(y_val, y_hat), res)
        lin = sw.identify_linear(case.u, case.y, nb=o['nb'] + o['nd'] + 1,
                                 nf=o['na'] + o['nc'], nk=o['q1'] + o['q2'],
                                 dt=1, integrators=out['default'][1].linear[
                                     'integrators'])
        y_lin = ct.forced_response(lin.model, inputs=u_val).outputs
        truth = sw.refine(case.plant, case.u, case.y)
    ratio = out['default'][1].cost / truth.cost
    return case, sw.fit_percent(y_val, y_lin), out, ratio


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--cases', type=int, default=12)
    ap.add_argument('--seed0', type=int, default=0)
    ap.add_argument('--n', type=int, default=4000)
    args = ap.parse_args(argv)
    rows, gaps, times = [], {'default': [], 'L1 (before)': []}, []
    for seed in range(args.seed0, args.seed0 + args.cases):
        case, lin, out, ratio = run(seed, args.n)
        o = case.orders
        default = out['default'][1]
        times.append(default.elapsed)
        where = '+'.join(b for b, i in default.integrators.items() if i) \
            or 'none'
        rows.append([seed, f"{o['na']}{o['nb']}{o['nc']}{o['nd']}"
                     f"{o['q1']}{o['q2']}", f"{lin:.2f}"]
                    + [f"{out[k][0]:.2f}" for k in out]
                    + [where, default.success, f"{ratio:.3f}"])
        for k in gaps:
            gaps[k].append(out[k][0] - out['L2 by hand'][0])
    print(f"Integrator after the play: fit (%) on a fresh record, "
          f"N = {args.n}, 1 % output noise")
    print_table(['seed', 'orders', 'linear', 'default', 'L2 by hand',
                 'L1 (before)', 'default put it in', 'default success',
                 'default cost / truth-start'],
                rows)
    for k, g in gaps.items():
        print(f"{k} - L2 by hand: median {statistics.median(g):+.2f}, "
              f"worst {min(g):+.2f} points; within 0.5 points in "
              f"{sum(x >= -0.5 for x in g)} of {len(g)}")
    ratios = [float(r[-1]) for r in rows]
    print(f"default cost / truth-start: median "
          f"{statistics.median(ratios):.3f}, above 1.05 in "
          f"{sum(r > 1.05 for r in ratios)} of {len(ratios)}; the "
          f"default's time: median {statistics.median(times):.2f} s, worst "
          f"{max(times):.2f} s")


if __name__ == '__main__':
    main()
