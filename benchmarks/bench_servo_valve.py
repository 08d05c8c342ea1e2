"""Closed loops around an integrator after the play: `servo_controller`
on identified valve plants, run on the plant itself.

A valve whose linkage has play drives a hydraulic cylinder (L2 has a pole
at z = 1; see bench_valve.py). Each case is
``sw.data.random_case(seed, integrating='L2', snr=1e4, n=N)``, identified
by ``sw.identify`` with the plant's true orders and defaults. Three
designs are run in closed loop on the true plant (noise-free, from rest)
for ``sw.servo_reference`` with the output's spread as its travel (the
plant's samples read as 10 ms, so a hold lasts 100 samples):

- ``servo_controller(result)``, the default (``feedback_from='auto'``:
  with L2 integrating, the feedback and the feedforward are designed on
  the sandwich's mbar L1 L2);
- ``servo_controller(result, feedback_from='baseline')``: the feedback on
  the result's linear baseline, as every identified sandwich had before
  (its feedforward is checked on the model as the default's is, which
  the old default did not do);
- ``servo_controller(case.plant)``: the plant itself known (the limit).

With ``--integrator L1`` the cases are
``random_case(seed, integrating=True, ...)`` instead: the integrator
before the play, as in a speed-in, position-out drive; with unequal
slopes the play puts a drift on their output too.

It prints the RMS error over the travel, the largest, the reversals of y
by more than 0.1 % of the travel in a hold's second half (hunting: 3 or
more) and the design's closed-loop pole
radius on its own design plant; a loop whose error passes 10 travels is
"diverged".

Run: python benchmarks/bench_servo_valve.py [--cases 24] [--seed0 0]
                                            [--n 4000] [--integrator L1]
"""

import argparse
import os
import statistics
import sys
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import print_table                            # noqa: E402

#: Variance ratio of the output noise: 1 % of the output's spread.
SNR = 1e4
#: the plant's sample read as this many seconds by servo_reference
DT = 0.01
DESIGNS = {'default': {}, 'on baseline': dict(feedback_from='baseline'),
           'plant known': None}


def loop(case, ctrl, travel):
    """(RMS / travel, max / travel, hunting) on the true plant."""
    r = sw.servo_reference(DT, travel, hold=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        out = sw.closed_loop_response(case.plant, r, ctrl)
    y, u = out.outputs[0], out.outputs[1]
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(u))):
        return np.inf, np.inf, 0
    m = sw.servo_metrics(r, y, u, DT, deadband=1e-3 * travel)
    return m['rms'] / travel, m['max'] / travel, m['hunting']


def run(seed, n, block='L2'):
    case = sw.data.random_case(
        seed, integrating='L2' if block == 'L2' else True, snr=SNR, n=n)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        res = sw.identify(case.u, case.y, **case.orders)
    travel = float(np.std(case.y))
    got = {}
    for name, kw in DESIGNS.items():
        try:
            with warnings.catch_warnings():     # a failed result's warning:
                # the table's success column says it
                warnings.simplefilter('ignore', sw.IdentificationWarning)
                ctrl = (sw.servo_controller(case.plant) if kw is None else
                        sw.servo_controller(res, **kw))
        except ValueError as exc:
            got[name] = (None, str(exc))
            continue
        got[name] = (loop(case, ctrl, travel), ctrl.margins['pole_radius'])
    return case, res, got


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--cases', type=int, default=24)
    ap.add_argument('--seed0', type=int, default=0)
    ap.add_argument('--n', type=int, default=4000)
    ap.add_argument('--integrator', choices=['L2', 'L1'], default='L2')
    args = ap.parse_args(argv)
    rows, ratio, worse = [], {k: [] for k in DESIGNS}, []
    diverged, hunting = ({k: 0 for k in DESIGNS} for _ in range(2))
    for seed in range(args.seed0, args.seed0 + args.cases):
        case, res, got = run(seed, args.n, args.integrator)
        o = case.orders
        row = [seed, f"{o['na']}{o['nb']}{o['nc']}{o['nd']}{o['q1']}{o['q2']}",
               res.success,
               '+'.join(b for b, i in res.integrators.items() if i) or 'none']
        for name in DESIGNS:
            metrics, radius = got[name]
            if metrics is None:
                row += ['refused', '', '', '']
                continue
            rms, top, hunt = metrics
            diverged[name] += top >= 10
            hunting[name] += hunt >= 3
            row += ([f"{rms:.3f}", f"{top:.2f}", hunt, f"{radius:.4f}"]
                    if top < 10 else ['diverged', '', hunt, f"{radius:.4f}"])
        rows.append(row)
        limit = got['plant known'][0]
        for name in DESIGNS:
            if got[name][0] is not None and limit is not None:
                ratio[name].append(got[name][0][0] / limit[0])
        if got['default'][0] is not None and got['on baseline'][0] is not None:
            worse.append(got['default'][0][0] > got['on baseline'][0][0])
    print(("Integrator after the play" if args.integrator == 'L2' else
           "Integrator before the play") + ": closed loop on the plant, "
          f"servo_reference (travel = std(y), holds of 100 samples, hunting "
          f"counted beyond 0.1 % of it); "
          f"N = {args.n}, 1 % output noise in the identification record\n")
    head = ['seed', 'orders', 'success', 'integrator']
    for name in DESIGNS:
        head += [f"{name} RMS", 'max', 'hunt', 'radius']
    print_table(head, rows)
    for name in ('default', 'on baseline'):
        x = ratio[name]
        print(f"{name}: RMS over the plant-known design's: median "
              f"{statistics.median(x):.2f}, within 2 times in "
              f"{sum(v <= 2 for v in x)} of {len(x)}")
    print("diverged (error beyond 10 travels) / hunting: " + ", ".join(
        f"{name} {diverged[name]} / {hunting[name]}" for name in DESIGNS)
          + f" of {len(rows)}")
    print(f"default worse than on the baseline in {sum(worse)} of "
          f"{len(worse)}")


if __name__ == '__main__':
    main()
