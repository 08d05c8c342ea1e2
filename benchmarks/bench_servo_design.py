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
(c) `ServoController.step` from Python for a design whose band jump is
    spread over 500 samples (an integrating L1, `jump_samples=500`, so
    250 samples of lead): its linear feedforward reads r_ahead 250 samples
    late from the reference delay line, against the same design with the
    delay inside the block (zeros of its denominator, as until
    2026-11-29: as many states more, and their square in operations a
    sample). Median of 5 runs of 20,000 steps; the two give the same u.

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


def long_lead():
    """(c): the two controllers of a design with a 250-sample lead."""
    import types
    import control as ct
    from sandwichctl.design.loop import ss_arrays
    from sandwichctl.design.servo import ServoController
    from sandwichctl.design._servo_kernel import IX
    plant = sw.SandwichSystem.from_coefficients(
        a=[-1.0], b=[0.05], c=[-0.8], d=[0.2], m1=1.0, m2=1.0, D1=0.2,
        D2=0.2, dt=1e-3)
    result = types.SimpleNamespace(model=plant, success=True, fit=95.0,
                                   linear=dict(model=plant.L1 * plant.L2,
                                               fit=90.0))
    ctrl = sw.servo_controller(result, jump_samples=500)
    late = dict(zip(IX, ctrl._ix))['d_lin']
    A, B, C, D = ctrl._design['_linear']
    block = ct.ss(A, B.reshape(-1, 1), C.reshape(1, -1), D.reshape(1, 1),
                  ctrl.dt)
    delayed = ss_arrays(ct.tf(block) * ct.tf(
        [1.0], np.r_[1.0, np.zeros(late)], ctrl.dt))
    inside = ServoController(dict(ctrl._design, _linear=delayed,
                                  _delays=(0, 0)))
    r = np.sin(np.arange(20_000) / 300.0)
    rows, us = [], []
    for name, c in (('delay line', ctrl), ('delay in the block', inside)):
        def run():
            c.reset()
            for rk in r:
                c.step(rk, 0.0)
        t = median_time(run, repeat=5) / r.size
        c.reset()
        us.append([c.step(rk, 0.0) for rk in r[:2000]])
        rows.append([name, dict(zip(IX, c._ix))['n_lin'], f"{t * 1e6:.2f}"])
    same = np.allclose(us[0], us[1], rtol=0, atol=1e-9 * np.max(
        np.abs(us[1])))
    return rows, same


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
    rows, same = long_lead()
    print(f"\n(c) ctrl.step with a lead of 250 samples (median of 5 runs "
          f"of 20,000 steps; the same u: {'yes' if same else 'NO'})\n")
    print_table(['linear feedforward', 'its states', 'us per step'], rows)
    print(f"\nin the block / delay line = "
          f"{float(rows[1][2]) / float(rows[0][2]):.1f}x")


if __name__ == '__main__':
    main()
