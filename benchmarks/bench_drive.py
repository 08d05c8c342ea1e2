"""Sandwich against linear output error on the simulated servo drive.

The drive (`sandwichctl.data.drive`) is simulated physically, not as a
sandwich: a motor in a digital speed or position loop, a ball screw whose
nut drives the platform through a dead-zone spring (the play), Coulomb and
viscous friction, a 1 um encoder. For each loop, play and seed this fits

- ``sw.identify(u, y, na=2, nb=1, nc=2, nd=1, q1=1, q2=0)`` (integrators
  'auto': the speed loop's position output integrates), and
- ``sw.identify_linear`` of the same total orders (nb = 3, nf = 4, nk = 1,
  with the integrators the sandwich's baseline found),

and prints both fits on the separate validation record (free run from
rest), the sandwich's margin over linear (it must never be more than 0.5
points below), and how much of what the play costs the linear model (the
linear fit of the same seed without play minus with play) the sandwich wins
back.

Run: python benchmarks/bench_drive.py [--seeds 3]
"""

import argparse
import os
import statistics
import sys
import time
import warnings

import control as ct

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import print_table                            # noqa: E402

ORDERS = dict(na=2, nb=1, nc=2, nd=1, q1=1, q2=0)


def _fits(case):
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        start = time.perf_counter()
        res = sw.identify(case.u, case.y, **ORDERS, dt=case.dt)
        elapsed = time.perf_counter() - start
        lin = sw.identify_linear(
            case.u, case.y, nb=ORDERS['nb'] + ORDERS['nd'] + 1,
            nf=ORDERS['na'] + ORDERS['nc'], nk=ORDERS['q1'] + ORDERS['q2'],
            dt=case.dt, integrators=res.linear['integrators'])
    y_sw = res.model.simulate(case.u_val).outputs
    y_lin = ct.forced_response(lin.model, inputs=case.u_val).outputs
    return (sw.fit_percent(case.y_val, y_sw),
            sw.fit_percent(case.y_val, y_lin), res, elapsed)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--seeds', type=int, default=3)
    args = ap.parse_args()
    rows, margins = [], []
    for loop in ('position', 'speed'):
        for seed in range(args.seeds):
            base = None
            for play in (0.0, 12e-6, 200e-6):
                case = sw.data.drive_case(seed, loop=loop, play=play)
                f_sw, f_lin, res, elapsed = _fits(case)
                if play == 0.0:
                    base = f_lin
                cost = base - f_lin
                won = ((f_sw - f_lin) / cost if play and cost > 0.5
                       else float('nan'))
                margins.append(f_sw - f_lin)
                rows.append([loop, seed, f"{play * 1e6:g}", f"{f_lin:.2f}",
                             f"{f_sw:.2f}", f"{f_sw - f_lin:+.2f}",
                             f"{cost:.2f}", f"{won:.0%}" if won == won
                             else '-', res.integrators['L1'],
                             res.success, f"{elapsed:.1f}"])
    print("Servo drive, validation fit (%) of free-run simulation; "
          "orders na=2, nb=1, nc=2, nd=1, q1=1, q2=0 (linear: nb=3, nf=4, "
          "nk=1)\n")
    print_table(['loop', 'seed', 'play um', 'linear', 'sandwich',
                 'sandwich - linear', 'play costs linear', 'won back',
                 'integrators', 'res.success', 'time s'], rows)
    print(f"\nworst sandwich - linear: {min(margins):+.2f} points "
          f"(target >= -0.5); median {statistics.median(margins):+.2f}")


if __name__ == '__main__':
    main()
