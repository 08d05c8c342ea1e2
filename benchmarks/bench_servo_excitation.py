"""Servo loops designed from records of other excitations: the drive of
``sw.data.servo_drive`` identified from what a user may log, then
`servo_controller`'s defaults run in closed loop on the drive.

`bench_servo.py` identifies every drive from ``sw.data.drive_reference``
(a staircase plus a multisine): its steps excite the drive up to the
Nyquist frequency. A drive is often commissioned with a swept sine, a
pseudo-random binary signal or a band-limited multisine instead, and the
identified model is then not pinned down above the band the input
excites. For each excitation, loop (position and speed), play (12 and
200 um) and seed, the script identifies the sandwich (the orders of
`bench_servo.py`) and the linear model of the same data, designs both
with the defaults and runs them on the drive for ``sw.servo_reference``
(1 mm of travel). Excitations (5 s unless said):

- ``reference``: ``drive_reference``, and its 2 s and 20 s records;
- ``small``: ``drive_reference`` at a tenth of its amplitude (the play
  then dominates the record);
- ``binary``: a random binary signal (+-1 rad, +-10 rad/s for the speed
  loop, switching after random holds of 50 to 300 ms);
- ``multisine``: 25 cosines at random frequencies in 0.2 to 15 Hz (RMS
  1 rad, 8 rad/s);
- ``sweep``: a swept sine (exponential, 0.2 to 12 Hz; amplitude 1 rad,
  10 rad/s).

It prints both designs' RMS errors, the sandwich's over the linear
design's (overall, near reversals, input activity), the reversals in a
hold's second half (hunting: 3 or more) and, with ``--raw``, two designs
as the code before 2026-11-28 made them: the sandwich with its checks
run around the raw identified model (`_servo_data.checked_model` off),
and both designs with no zero cancelled beside a pole in their inverses
(`_servo_inverse.COINCIDENT` = 0).

Run: python benchmarks/bench_servo_excitation.py [--seeds 2] [--raw]
                                                 [--kinds sweep,binary]
"""

import argparse
import os
import statistics
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from sandwichctl.design import _servo_data as sdata        # noqa: E402
from sandwichctl.design import _servo_inverse as si        # noqa: E402
from _timing import print_table                            # noqa: E402
from bench_servo import LINEAR, ORDERS, run                # noqa: E402

DT = sw.data.DRIVE_DT
#: (kind, seconds) of the estimation records
RECORDS = (('reference', 2), ('reference', 5), ('reference', 20),
           ('small', 5), ('binary', 5), ('multisine', 5), ('sweep', 5))


def _amplitude(loop, position, speed):
    return position if loop == 'position' else speed


def binary(n, rng, loop):
    """A random binary signal switching after holds of 50 to 300 ms."""
    out, k, s = np.empty(n), 0, 1.0
    while k < n:
        hold = int(rng.integers(int(0.05 / DT), int(0.3 / DT)))
        out[k:k + hold], s, k = s, -s, k + hold
    if loop == 'speed':
        out -= out.mean()
    return _amplitude(loop, 1.0, 10.0) * out


def multisine(n, rng, loop):
    """25 cosines at random frequencies in 0.2 to 15 Hz, unit RMS scaled."""
    t = np.arange(n) * DT
    f = np.exp(rng.uniform(np.log(0.2), np.log(15.0), 25))
    phase = rng.uniform(0, 2 * np.pi, 25)
    s = np.sum(np.cos(2 * np.pi * f[:, None] * t + phase[:, None]), 0)
    return _amplitude(loop, 1.0, 8.0) * s / s.std()


def sweep(n, rng, loop):
    """An exponential swept sine from 0.2 to 12 Hz over the record."""
    t = np.arange(n) * DT
    f0, f1, span = 0.2, 12.0, t[-1]
    phase = (2 * np.pi * f0 * span / np.log(f1 / f0)
             * (np.exp(t / span * np.log(f1 / f0)) - 1))
    return _amplitude(loop, 1.0, 10.0) * np.sin(phase)


def reference(n, rng, loop):
    return sw.data.drive_reference(n, loop, rng=rng, dt=DT)


def small(n, rng, loop):
    return 0.1 * reference(n, rng, loop)


KINDS = dict(reference=reference, small=small, binary=binary,
             multisine=multisine, sweep=sweep)


def raw_design(res):
    """The sandwich's default design with its checks around the raw
    identified model."""
    keep = sdata.checked_model
    sdata.checked_model = lambda model, response, notes: model
    try:
        return sw.servo_controller(res)
    finally:
        sdata.checked_model = keep


def unpaired_design(res):
    """The default design with no zero cancelled beside a pole in its
    inverses."""
    keep = si.COINCIDENT
    si.COINCIDENT = 0.0
    try:
        return sw.servo_controller(res)
    finally:
        si.COINCIDENT = keep


def case(kind, seconds, loop, play, seed, raw):
    n = int(round(seconds / DT))
    u = KINDS[kind](n, np.random.default_rng(seed), loop)
    y = sw.data.servo_drive(u, loop, play, DT, seed=seed + 1000)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        res = sw.identify(u, y, **ORDERS, dt=DT)
        lin = sw.identify_linear(u, y, **LINEAR, dt=DT,
                                 integrators=res.linear['integrators'])
        designs = {'linear': lambda: sw.servo_controller(lin),
                   'sandwich': lambda: sw.servo_controller(res)}
        if raw:
            designs['raw checks'] = lambda: raw_design(res)
            designs['linear unpaired'] = lambda: unpaired_design(lin)
            designs['sandwich unpaired'] = lambda: unpaired_design(res)
        r = sw.servo_reference(DT, 1e-3)
        got = {}
        for name, make in designs.items():
            try:
                ctrl = make()
            except ValueError as exc:
                got[name] = f"refused: {exc}"[:80]
                continue
            got[name] = run(ctrl, r, loop, play, DT, {}, seed + 500)
            got[name]['damped'] = any('damped to radius' in note
                                      for note in ctrl.notes)
    return res, got


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument('--seeds', type=int, default=2)
    ap.add_argument('--seed0', type=int, default=0)
    ap.add_argument('--raw', action='store_true')
    ap.add_argument('--kinds', default=','.join(KINDS))
    args = ap.parse_args(argv)
    kinds = args.kinds.split(',')
    rows, ratios, start = [], [], time.perf_counter()
    for loop in ('position', 'speed'):
        for seed in range(args.seed0, args.seed0 + args.seeds):
            for kind, seconds in (rec for rec in RECORDS
                                  if rec[0] in kinds):
                for play in (12e-6, 200e-6):
                    res, got = case(kind, seconds, loop, play, seed,
                                    args.raw)
                    lin, sand = got['linear'], got['sandwich']
                    row = [loop[:3], seed, kind, f"{seconds} s",
                           f"{play * 1e6:.0f}", f"{res.fit:.2f}",
                           'yes' if res.success else 'no']
                    if isinstance(lin, str) or isinstance(sand, str):
                        print(f"{' '.join(map(str, row))}: linear {lin}; "
                              f"sandwich {sand}")
                        continue
                    ratio = sand['rms'] / lin['rms']
                    near = sand['near_reversals'] / lin['near_reversals']
                    ratios.append((kind, ratio))
                    row += [f"{lin['rms'] * 1e6:.1f}", lin['hunting'],
                            f"{sand['rms'] * 1e6:.1f}", sand['hunting'],
                            f"{ratio:.2f}", f"{near:.2f}",
                            f"{sand['activity'] / lin['activity']:.2f}",
                            'yes' if sand['damped'] else '']
                    if args.raw:
                        for name in ('raw checks', 'sandwich unpaired'):
                            raw = got[name]
                            row.append(raw if isinstance(raw, str) else
                                       f"{raw['rms'] / lin['rms']:.2f}")
                        raw = got['linear unpaired']
                        row.append(raw if isinstance(raw, str) else
                                   f"{raw['rms'] * 1e6:.1f}")
                    rows.append(row)
    print("Servo loops on the drive, designed from records of other "
          "excitations; servo_controller defaults, errors in um\n")
    head = ['loop', 'seed', 'excitation', 'record', 'play', 'fit %',
            'success', 'linear', 'hunt', 'sandwich', 'hunt', 'RMS/lin',
            'near rev./lin', 'TV/lin', 'mode damped']
    if args.raw:
        head += ['raw checks RMS/lin', 'unpaired RMS/lin',
                 'linear unpaired']
    print_table(head, rows)
    print(f"\n{len(rows)} loops in {time.perf_counter() - start:.0f} s")
    for kind in dict.fromkeys(k for k, _ in ratios):
        got = [x for k, x in ratios if k == kind]
        print(f"{kind}: sandwich RMS / linear median "
              f"{statistics.median(got):.2f}, worst {max(got):.2f} "
              f"(target <= 1.05)")


if __name__ == '__main__':
    main()
