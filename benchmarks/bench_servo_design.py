"""How long `sw.servo_controller` takes to design, and the compiled
margin test of its PID grid against the same formulas in numpy.

(a) The design (median of --repeat calls, after one warm-up) from the
    project's drives (`sw.data.servo_drive`, seed 0, 200 um of play, a
    5 s estimation record as in bench_servo.py), from the sandwich result
    and from the linear one. An integrating plant (the speed loop) gets a
    PD, whose grid needs no integral limits; a position loop a PID.
(b) `_servo_design._outside`, the largest integral gain of each grid
    point that keeps the modulus margin at every frequency (about 1,300
    PD designs by 1,500 to 3,000 frequencies), compiled (numba, one pass)
    against the same formulas as numpy array expressions
    (`_servo_design._roots`, which the crossover test still uses on the
    few high frequencies), on the grid of the position loop's linear
    design; the two agree to 1e-9 (the root formula cancels where
    B^2 >> 4AC, so the last bits of either sum move a limit by ~1e-12).

Run: python benchmarks/bench_servo_design.py [--repeat 3]
"""

import argparse
import os
import sys
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import median_time, print_table               # noqa: E402
from sandwichctl.design import _servo_design as sd         # noqa: E402
from bench_servo import identify                           # noqa: E402


def numpy_outside(a, b, level):
    """`_outside` written as numpy array expressions."""
    r1, _, c = sd._roots(a, b, level)
    lim = np.where(np.isfinite(r1) & (r1 > 0), r1, np.inf).min(axis=1)
    return lim, np.all(c >= 0, axis=1)


def grid_of(ctrl):
    """The (a, b) arrays of the PID grid of `ctrl`'s design plant, as
    design_pid builds them for its pole at 0."""
    P = ctrl.design_plant
    num, den = np.trim_zeros(P.num[0][0], 'f'), P.den[0][0]
    w = sd.frequency_grid(den)
    z = np.exp(1j * w)
    Pw = np.polyval(num, z) / np.polyval(den, z)
    k0 = 1.0 / np.max(np.abs(Pw))
    KP, KD = (g.ravel() for g in np.meshgrid(
        k0 * np.logspace(-4, 1, 60), k0 * np.r_[0.0, np.logspace(-4, 1, 21)]))
    D = (z - 1) / z
    a = 1 + (KP[:, None] + KD[:, None] * D[None, :]) * Pw[None, :]
    return a, (z / (z - 1) * Pw)[None, :]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--repeat', type=int, default=3)
    args = ap.parse_args()
    rows, grid = [], None
    for loop in ('speed', 'position'):
        res, lin = identify(loop, 200e-6, sw.data.DRIVE_DT, {}, 0)
        for name, result in (('sandwich', res), ('linear', lin)):
            with warnings.catch_warnings():
                warnings.simplefilter('ignore')
                ctrl = sw.servo_controller(result)
                t = median_time(lambda: sw.servo_controller(result),
                                repeat=args.repeat)
            rows.append([loop, name, 'PD' if ctrl.ki == 0 else 'PID',
                         f"{t:.2f}"])
            if loop == 'position' and name == 'linear':
                grid = grid_of(ctrl)
    print("(a) sw.servo_controller on the drives (seed 0, 200 um), median "
          f"of {args.repeat} calls\n")
    print_table(['loop', 'result', 'feedback', 'design s'], rows)
    a, b = grid
    level = 1.005 * 0.6
    fast = sd._outside(a, b, level)
    slow = numpy_outside(a, b, level)
    agree = (np.array_equal(fast[1], slow[1]) and np.allclose(
        fast[0], slow[0], rtol=1e-9, atol=0.0))
    t_fast = median_time(lambda: sd._outside(a, b, level), repeat=7)
    t_slow = median_time(lambda: numpy_outside(a, b, level), repeat=7)
    print(f"\n(b) the margin's integral limits of {a.shape[0]} grid points "
          f"at {a.shape[1]} frequencies (median of 7)\n")
    print_table(['numpy ms', 'compiled ms', 'numpy / compiled',
                 'agree to 1e-9'],
                [[f"{t_slow * 1e3:.1f}", f"{t_fast * 1e3:.1f}",
                  f"{t_slow / t_fast:.1f}", 'yes' if agree else 'NO']])


if __name__ == '__main__':
    main()
