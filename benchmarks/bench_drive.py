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

With ``--random N`` it also runs N randomised drives
(`sw.data.random_drive`: mechanics, loop, play 0-300 um and sampling
drawn per seed); their play-free twin gives what the play costs.

Run: python benchmarks/bench_drive.py [--seeds 3] [--random 8 --random0 0]
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


def random_case(seed, play=None):
    """Estimation (5 s) and validation records of `sw.data.random_drive`
    (its own play unless `play` is given)."""
    d = sw.data.random_drive(seed)
    play = d['play'] if play is None else play
    n = int(round(5.0 / d['dt']))
    u, u_val = (sw.data.drive_reference(n, d['loop'], rng=[seed, k],
                                        dt=d['dt']) for k in (1, 2))
    y, y_val = (sw.data.servo_drive(x, d['loop'], play, d['dt'],
                                    seed=[seed, k], **d['params'])
                for x, k in ((u, 3), (u_val, 4)))
    return sw.data.DriveCase(u=u, y=y, u_val=u_val, y_val=y_val,
                             dt=d['dt'], loop=d['loop'], play=play,
                             seed=seed, params=d['params'])


def cases(seeds, randoms, random0):
    """(label, play-free case, case) of the default drive's seeds (plays
    0, 12 and 200 um) and of the randomised drives (their own play)."""
    for loop in ('position', 'speed'):
        for seed in range(seeds):
            free = sw.data.drive_case(seed, loop=loop, play=0.0)
            for play in (0.0, 12e-6, 200e-6):
                yield (loop, str(seed), free,
                       sw.data.drive_case(seed, loop=loop, play=play))
    for seed in range(random0, random0 + randoms):
        case = random_case(seed)
        yield (case.loop, f"rnd{seed}", random_case(seed, 0.0), case)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--seeds', type=int, default=3)
    ap.add_argument('--random', type=int, default=0,
                    help='also this many randomised drives')
    ap.add_argument('--random0', type=int, default=0,
                    help='first randomised drive')
    args = ap.parse_args()
    rows, margins = [], []
    base = {}
    for loop, seed, free, case in cases(args.seeds, args.random,
                                        args.random0):
        play = case.play
        f_sw, f_lin, res, elapsed = _fits(case)
        if play == 0.0:
            base[loop, seed] = f_lin
        elif (loop, seed) not in base:
            base[loop, seed] = _fits(free)[1]
        cost = base[loop, seed] - f_lin
        won = ((f_sw - f_lin) / cost if play and cost > 0.5
               else float('nan'))
        margins.append(f_sw - f_lin)
        rows.append([loop, seed, f"{play * 1e6:.0f}", f"{f_lin:.2f}",
                     f"{f_sw:.2f}", f"{f_sw - f_lin:+.2f}", f"{cost:.2f}",
                     f"{won:.0%}" if won == won else '-',
                     res.integrators['L1'], res.success, f"{elapsed:.1f}"])
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
