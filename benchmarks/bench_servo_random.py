"""servo_controller on identified random plants (issue 23, "no silent
failures").

For each seed, four variants of ``sw.data.random_case(seed, n=2000,
snr=100)``: as drawn, with a negative gain, with an integrator in L1 (a
drive's nut) and with one in L2 (a valve's cylinder). Each is identified
with ``sw.identify`` (its true orders, defaults); each success gets

- the default design, ``sw.servo_controller(res)``;
- the same with ``feedback_from='baseline'``, the feedback on the linear
  baseline, as every design whose baseline the default chose got before
  the check of `_servo_checks.feedback_checked` (where the default's
  feedback is the baseline's, the two are the same design);
- the linear design, ``sw.servo_controller(res.linear['model'])``;

and each design runs in closed loop on the true plant for
``sw.servo_reference(0.01, travel, hold=1.0)`` (the plant's sample read as
10 ms), with the output's spread as the travel. It prints a row per
design whose feedback the check moved to the sandwich's mbar L1 L2, a
row per design that the check of `_servo_checks.bounded_checked` moved
(its first loop ran away around the identified model, or tracked it worse
than leaving it at rest), a row per default design whose RMS error
exceeds one travel, and counts the designs refused (with their reasons)
and those whose RMS error exceeds one travel. For a default design that
check refused, it prints what the design it refused does on the true
plant (made without the check).

Run: python benchmarks/bench_servo_random.py [--seeds 50] [--seed0 0]
"""

import argparse
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from sandwichctl.design import _servo_checks as sc         # noqa: E402
from _timing import print_table                            # noqa: E402

VARIANTS = (('plain', {}), ('negative gain', dict(negative_gain=True)),
            ('integrator in L1', dict(integrating='L1')),
            ('integrator in L2', dict(integrating='L2')))
MOVED = "left the loop around the sandwich's mbar L1 L2 unstable"
RAN = "with the feedback chosen first"
#: the start of `bounded_checked`'s reason
AROUND = "the loop around the identified model"


def rms_travels(plant, ctrl, r, travel):
    """RMS error of `ctrl` around `plant` for r, in travels (inf if the
    loop blows up)."""
    with np.errstate(all='ignore'), warnings.catch_warnings():
        warnings.simplefilter('ignore')
        y = sw.closed_loop_response(plant, r, ctrl).outputs[0]
        err = float(np.sqrt(np.mean((r - y) ** 2))) / travel
    return err if np.isfinite(err) else np.inf


def design(model, **kw):
    """servo_controller(model, **kw), or the reason it refused."""
    try:
        return sw.servo_controller(model, **kw), None
    except ValueError as exc:
        return None, str(exc)


def _source(ctrl, res):
    """What the design's feedback was designed on: the baseline where its
    gains are those of the design forced onto it."""
    base, _ = design(res, feedback_from='baseline')
    same = base is not None and (base.kp, base.ki, base.kd) == (
        ctrl.kp, ctrl.ki, ctrl.kd)
    return 'baseline' if same else 'mbar L1 L2'


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--seeds', type=int, default=50)
    ap.add_argument('--seed0', type=int, default=0)
    args = ap.parse_args()
    start = time.perf_counter()
    rows, poor, refused, ran, checked = [], [], [], [], []
    count = dict(cases=0, successes=0)
    worse = dict(default=0, before=0, linear=0)
    for seed in range(args.seed0, args.seed0 + args.seeds):
        for label, kw in VARIANTS:
            case = sw.data.random_case(seed, n=2000, snr=100, **kw)
            count['cases'] += 1
            with warnings.catch_warnings():
                warnings.simplefilter('ignore')
                res = sw.identify(case.u, case.y, **case.plant.orders)
            if not res.success:
                continue
            count['successes'] += 1
            travel = float(np.std(case.y))
            r = sw.servo_reference(0.01, travel, hold=1.0)
            ctrl, why = design(res)
            lin, why_lin = design(res.linear['model'])
            for name, reason in (('sandwich', why), ('linear', why_lin)):
                if reason is not None:
                    refused.append(f"seed {seed}, {label}, {name}: {reason}")
            if why is not None and AROUND in why:
                with sc.inner():        # the design the check refused
                    unchecked, _ = design(res)
                e_unchecked = rms_travels(case.plant, unchecked, r, travel)
                checked.append([seed, label, f"{res.fit:.1f}",
                                f"{res.linear['fit']:.1f}",
                                f"{e_unchecked:.3g}"])
            if ctrl is not None:
                e = rms_travels(case.plant, ctrl, r, travel)
                moved = any(MOVED in note for note in ctrl.notes)
                ran.extend([seed, label, note.split('; ')[-1], f"{e:.3g}"]
                           for note in ctrl.notes if RAN in note)
                e_before = e
                if moved:
                    before, _ = design(res, feedback_from='baseline')
                    # refused where its loop runs away around the model
                    e_before = (np.inf if before is None else
                                rms_travels(case.plant, before, r, travel))
                    rows.append([seed, label, f"{res.fit:.1f}",
                                 f"{res.linear['fit']:.1f}",
                                 'refused' if before is None else
                                 f"{e_before:.3g}", f"{e:.3g}"])
                worse['default'] += e > 1
                worse['before'] += e_before > 1
            e_lin = (np.nan if lin is None else
                     rms_travels(case.plant, lin, r, travel))
            worse['linear'] += e_lin > 1
            if ctrl is not None and e > 1:
                poor.append([seed, label, f"{res.fit:.1f}",
                             f"{res.linear['fit']:.1f}", f"{e:.3g}",
                             f"{e_lin:.3g}", _source(ctrl, res)])
    print(f"servo_controller on identified random plants (n = 2000, SNR "
          f"100), seeds {args.seed0} to {args.seed0 + args.seeds - 1}; "
          f"RMS error on the true plant in travels\n")
    print("designs whose feedback the default moved to the sandwich's "
          "mbar L1 L2 (the baseline's loop diverged around the sandwich):")
    print_table(['seed', 'variant', 'sandwich fit %', 'baseline fit %',
                 'feedback on baseline', 'default'], rows)
    print("\ndesigns moved because the first ran away around the "
          "identified model or tracked it worse than at rest "
          "(`_servo_checks.bounded_checked`):")
    print_table(['seed', 'variant', 'redesigned', 'default'], ran)
    print("\ndefault designs refused by that check, and what they do on "
          "the true plant:")
    print_table(['seed', 'variant', 'sandwich fit %', 'baseline fit %',
                 'refused design'], checked)
    print("\ndefault designs worse than one travel:")
    print_table(['seed', 'variant', 'sandwich fit %', 'baseline fit %',
                 'default', 'linear design', 'feedback on'], poor)
    print(f"\n{count['successes']} successes of {count['cases']} cases in "
          f"{time.perf_counter() - start:.0f} s; moved: {len(rows)}")
    print(f"RMS error above one travel: default {worse['default']}, with "
          f"the feedback on the baseline {worse['before']}, linear design "
          f"{worse['linear']} (of the designs made)")
    print(f"refused: {len(refused)}")
    for line in refused:
        print(f"  {line[:200]}")


if __name__ == '__main__':
    main()
