"""Closed loops on the physically simulated servo drive: linear against
sandwich, both designed by `sw.servo_controller` with its defaults.

For each drive of the family (the default drive in position and speed
loops with play 0, 12 and 200 um over several seeds, and randomised drives
of `sw.data.random_drive`), this

1. records 5 s of `drive_reference` excitation and identifies, from that
   record only, a sandwich (`sw.identify`) and a linear output-error model
   of the same total orders (`sw.identify_linear`);
2. designs ``servo_controller(linear result)`` and
   ``servo_controller(sandwich result)`` with defaults;
3. runs both, with `sw.closed_loop_response`, against the drive
   (`sw.data.ServoDrive`, another disturbance seed) for
   `sw.servo_reference`: S-curve steps with reversals and holds, ramps and
   a sine; and runs the linear design on the same drive without play
   (the limit).

It prints, per case and design: RMS and maximum error, the RMS error in
the 100 ms after each reversal of the reference, the input's total
variation against the linear design's (chatter), the most reversals of y
in the second half of a hold (>= 3 is a limit cycle) and the share of
ticks at the motor's torque limit, and the hunting guard's scale on the
feedback's gains at the end of the run (1: it never fired). A design
with 3 or more reversals runs again on the drive without its white torque
disturbance, and the summary counts those that hunt there too: a limit
cycle persists without it, while the disturbance alone can turn y by a
few encoder counts in a hold (random drives 121 and 124: 10 and 17
reversals with it, none without). With
``--no-guard`` every design runs without the guard (``hunting=False``),
to compare. With ``--sweep`` it also scales the
linear feedback on the play-free drive to find the best linear design of
the sweep (the default's gains by 0.25, 0.5, 2 and 4, and those of the
design at the fixed crossover limit of a model without data by 1, 2 and
4, each designed with and without the raise past |T| <= 1 of
`RAISE_MOST`; a scale whose loop is unstable on the model is skipped,
and one with a limit cycle on the drive, 3 or more reversals in a hold
also without the torque disturbance, is not counted as the best unless
every design of the sweep has one). With
``--bands`` it runs the sandwich design of every drive at fixed band
shares too, and prints the RMS ratio to the linear design at
each: the best share per drive bounds what adapting the share online could
reach, the worst shows what a larger fixed default would risk. With
``--to-margin`` it scales the linear design's gains up until the model's
modulus margin is met with equality (when the crossover limit, not the
margin, is what bounds them) and runs that on the drive too. With
``--scales 1.25,1.5,2`` it runs the linear design with its gains scaled
by each factor on the drive and on the drives of ``--mismatch`` too, and
``--no-raise`` keeps every PID at |T| <= 1 (no gains raised where the
data vouch for the model; `RAISE_MOST`), to compare. With
``--sources``, where the default feedforward inverts the sandwich's own
linear part mbar L1 L2, it also runs the sandwich design with
``feedforward_from='model'`` and ``'baseline'`` (the linear baseline
inverted, the same feedback and band) and prints both ratios. With
``--mismatch`` it also runs both designs on drives that are not the one
identified (`MISMATCH`: a heavier load with less friction, a stiffer
inner loop, less and more play) and counts the hunting there;
``--play-factors 2,3`` runs them on drives with the play scaled by each
factor instead.
``--crossover X`` sets the PID's crossover limit of a model without data
(`CROSSOVER_LIMIT['pid']`), ``--fixed-crossover`` holds every design
at it (no extension from the residuals of the record), and ``--peak-t M``
bounds the PID's complementary sensitivity at M instead of 1
(`T_PEAK`), to compare.

Run: python benchmarks/bench_servo.py [--seeds 2] [--random 8] [--sweep]
     [--seed0 2 --random0 8] [--feedforward zpetc] [--bands]
     [--to-margin] [--sources] [--mismatch] [--play-factors 2,3]
     [--crossover 2] [--fixed-crossover] [--peak-t 1.15]
     [--scales 1.25,1.5,2]
     [--no-raise] [--no-guard]
"""

import argparse
import os
import sys
import time
import warnings

import numpy as np
import control as ct

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import print_table                            # noqa: E402
from sandwichctl.design import _servo_design as sd         # noqa: E402
from sandwichctl.design import _servo_data as sdata        # noqa: E402

ORDERS = dict(na=2, nb=1, nc=2, nd=1, q1=1, q2=0)
LINEAR = dict(nb=3, nf=4, nk=1)
#: fixed band shares tried with --bands
BAND_SHARES = (0.0, 0.1, 0.25, 0.5, 0.75, 1.0)


def identify(loop, play, dt, params, seed):
    """Sandwich and linear results from one 5 s estimation record."""
    n = int(round(5.0 / dt))
    u = sw.data.drive_reference(n, loop, rng=seed, dt=dt)
    y = sw.data.servo_drive(u, loop, play, dt, seed=seed + 1000, **params)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        res = sw.identify(u, y, **ORDERS, dt=dt)
        lin = sw.identify_linear(u, y, **LINEAR, dt=dt,
                                 integrators=res.linear['integrators'])
    return res, lin


def run(ctrl, r, loop, play, dt, params, seed):
    """Closed loop on the drive; the metrics of `sw.servo_metrics`."""
    drive = sw.data.ServoDrive(loop, play, dt, seed=seed, n=r.size,
                               **params)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        out = sw.closed_loop_response(drive, r, ctrl)
    res = params.get('resolution', sw.data.DRIVE_PARAMETERS['resolution'][0])
    m = sw.servo_metrics(r, out.outputs[0], out.outputs[1], dt,
                         deadband=1.5 * res)
    m['saturation'] = drive.saturated / r.size
    m['guard'] = ctrl.feedback_gain     # the hunting guard's scale at the end
    return m


def quiet_hunting(ctrl, m, r, loop, play, dt, params, seed):
    """The reversals of a design that hunts (`m`, its metrics on the
    drive) run again without the drive's torque disturbance: a limit cycle
    hunts there too, the disturbance's jitter of a few encoder counts does
    not. 0 where it did not hunt (not run again)."""
    if m['hunting'] < 3:
        return 0
    return run(ctrl, r, loop, play, dt, {**params, 'torque_noise': 0.0},
               seed)['hunting']


def cases(seeds, randoms, loops, seed0=0, random0=0):
    for loop in loops:
        for seed in range(seed0, seed0 + seeds):
            for play in (0.0, 12e-6, 200e-6):
                yield (f"{loop[:3]} s{seed}", loop, play, sw.data.DRIVE_DT,
                       {}, seed)
    for seed in range(random0, random0 + randoms):
        d = sw.data.random_drive(seed)
        yield (f"rnd{seed} {d['loop'][:3]}", d['loop'], d['play'], d['dt'],
               d['params'], 100 + seed)


#: drives that differ from the one identified, for --mismatch: a load
#: twice as heavy with a third of the friction (it coasts further into
#: the gap), an inner loop 1.25 times stiffer, and half or 1.5 times the
#: play
MISMATCH = (('heavier', 1.0, dict(M=2.0, Fc=1 / 3)),
            ('stiffer', 1.0, dict(Kp=1.25, Kv=1.25)),
            ('play x0.5', 0.5, {}),
            ('play x1.5', 1.5, {}))


def mismatched(play, params):
    """(label, play, params) of the drives of `MISMATCH`."""
    base = {k: v[0] for k, v in sw.data.DRIVE_PARAMETERS.items()}
    base.update(params)
    for label, f_play, scale in MISMATCH:
        if f_play != 1.0 and play == 0.0:
            continue
        yield label, f_play * play, dict(
            params, **{k: base[k] * f for k, f in scale.items()})


def to_margin(ctrl, target=0.6, most=4.0):
    """The largest factor (at most `most`) on the design's PID gains that
    keeps the model's modulus margin at `target` (servo_controller's
    default)."""
    P = ctrl.design_plant
    num, den = np.trim_zeros(P.num[0][0], 'f'), P.den[0][0]

    def margin(f):
        C = sd.pid_tf(f * ctrl.kp, f * ctrl.ki, f * ctrl.kd,
                      ctrl.derivative_pole, ctrl.dt)
        mm, _, _, radius = sd.loop_margins(num, den, C)
        return mm if radius < 1 else 0.0

    lo, hi = 1.0, most
    if margin(hi) >= target:
        return hi
    for _ in range(12):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if margin(mid) >= target else (lo, mid)
    return lo


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--seeds', type=int, default=2)
    ap.add_argument('--seed0', type=int, default=0,
                    help='first seed (0-1 and random 0-7 are the tuning '
                    'drives; take 2 and 8 for held-out ones)')
    ap.add_argument('--random0', type=int, default=0)
    ap.add_argument('--random', type=int, default=6)
    ap.add_argument('--sweep', action='store_true')
    ap.add_argument('--loops', default='position,speed')
    ap.add_argument('--bands', action='store_true',
                    help='also run the sandwich design at fixed band shares')
    ap.add_argument('--to-margin', action='store_true',
                    help='also run the linear design scaled up to its '
                    'modulus margin')
    ap.add_argument('--sources', action='store_true',
                    help="also run the sandwich design with its feedforward "
                    "inverting the model's mbar L1 L2 and the linear "
                    "baseline, where the default picks the model's")
    ap.add_argument('--mismatch', action='store_true',
                    help='also run both designs on drives that differ from '
                    'the one identified (MISMATCH)')
    ap.add_argument('--play-factors', default=None,
                    help='comma-separated factors: --mismatch on drives '
                    'with the play scaled by each, instead of MISMATCH')
    ap.add_argument('--crossover', type=float, default=None,
                    help="the PID's crossover limit in plant bandwidths "
                    "(CROSSOVER_LIMIT['pid'] of sandwichctl.design."
                    "_servo_design), to compare with the default")
    ap.add_argument('--feedforward', default='preview',
                    choices=['preview', 'zpetc'],
                    help='how both designs invert zeros outside the unit '
                    'circle')
    ap.add_argument('--peak-t', type=float, default=None,
                    help="the bound on |T| of the PID's design (T_PEAK of "
                    "sandwichctl.design._servo_design, 1 by default), to "
                    "compare")
    ap.add_argument('--scales', default=None,
                    help="comma-separated factors: also run the linear "
                    "design with its gains scaled by each (feedback_scale) "
                    "on the drive and on the drives of MISMATCH")
    ap.add_argument('--no-raise', action='store_true',
                    help="no PID raised past |T| <= 1 where the data vouch "
                    "for the model (RAISE_MOST of sandwichctl.design."
                    "_servo_design set to 1), to compare with the default")
    ap.add_argument('--no-guard', action='store_true',
                    help="no hunting guard (hunting=False for every "
                    "design), to compare with the default")
    ap.add_argument('--fixed-crossover', action='store_true',
                    help="hold the PID's crossover limit at "
                    "CROSSOVER_LIMIT['pid'] (no extension from the "
                    "residuals of the data, and no PID raised past it), "
                    "to compare with the default")
    args = ap.parse_args()
    if args.play_factors:
        global MISMATCH
        MISMATCH = tuple((f"play x{f:g}", f, {}) for f in
                         map(float, args.play_factors.split(',')))
        args.mismatch = True
    if args.crossover is not None:
        sd.CROSSOVER_LIMIT['pid'] = args.crossover
    if args.peak_t is not None:
        sd.T_PEAK = args.peak_t
    if args.fixed_crossover:
        sdata.CROSSOVER_MOST = sd.CROSSOVER_LIMIT['pid']
        sd.RAISE_MOST = 1.0             # nor a raised PID past it
    if args.no_raise:
        sd.RAISE_MOST = 1.0
    scales = ([float(f) for f in args.scales.split(',')] if args.scales
              else [])
    if args.no_guard:
        design = sw.servo_controller

        def unguarded(model, **kw):
            return design(model, **{'hunting': False, **kw})
        sw.servo_controller = unguarded
    rows, checks, bands, margin, sources, swept = [], [], [], [], [], []
    mism, scaled_rows = [], []
    start = time.perf_counter()
    for label, loop, play, dt, params, seed in cases(
            args.seeds, args.random, args.loops.split(','), args.seed0,
            args.random0):
        res, lin = identify(loop, play, dt, params, seed)
        r = sw.servo_reference(dt, 1e-3)
        try:
            c_lin = sw.servo_controller(lin, feedforward=args.feedforward)
            c_sw = sw.servo_controller(res, feedforward=args.feedforward)
        except ValueError as exc:
            print(f"{label} play {play * 1e6:.0f}: design refused: {exc}")
            continue
        m_lin = run(c_lin, r, loop, play, dt, params, seed + 500)
        m_sw = run(c_sw, r, loop, play, dt, params, seed + 500)
        m_0 = run(c_lin, r, loop, 0.0, dt, params, seed + 500)
        best = ''
        if args.sweep and play == 0.0:
            # (RMS, reversals without the torque disturbance) of each
            # design; one with a limit cycle is not a best to compare with
            sweep = [(m_0['rms'], quiet_hunting(c_lin, m_0, r, loop, 0.0, dt,
                                                params, seed + 500))]
            # the default's gains scaled, and those of the design at the
            # fixed crossover limit (whose larger scales the default's
            # model refuses)
            # (f, kw, RAISE_MOST): each with and without the raise, so
            # that the sweep does not depend on the default's raise
            most = sd.RAISE_MOST
            for f, kw, raise_most in [
                    (f, kw, m) for m in sorted({most, 1.0}) for f, kw in
                    [(f, {}) for f in (0.25, 0.5, 2.0, 4.0)]
                    + [(f, dict(crossover_limit=sd.CROSSOVER_LIMIT['pid']))
                       for f in (1.0, 2.0, 4.0)]]:
                sd.RAISE_MOST = raise_most
                try:
                    scaled = sw.servo_controller(lin, feedback_scale=f, **kw)
                except ValueError:      # unstable on the model: not swept
                    continue
                finally:
                    sd.RAISE_MOST = most
                m_s = run(scaled, r, loop, 0.0, dt, params, seed + 500)
                sweep.append((m_s['rms'], quiet_hunting(
                    scaled, m_s, r, loop, 0.0, dt, params, seed + 500)))
            calm = [x for x, rev in sweep if rev < 3] or [x for x, _ in sweep]
            best = f"{min(calm) * 1e6:.1f}"
            swept.append((loop, m_0['rms'] / min(calm)))
        for name, m in (('linear', m_lin), ('sandwich', m_sw)):
            rows.append([label, f"{play * 1e6:.0f}", name,
                         f"{m['rms'] * 1e6:.1f}", f"{m['max'] * 1e6:.0f}",
                         f"{m['near_reversals'] * 1e6:.1f}",
                         f"{m['activity'] / m_lin['activity']:.2f}",
                         m['hunting'], f"{m['saturation']:.1%}",
                         f"{m['guard']:.2g}",
                         f"{m_0['rms'] * 1e6:.1f}" if name == 'linear'
                         else '', best if name == 'linear' else '',
                         f"{m['rms'] / m_lin['rms']:.2f}"])
        if args.bands:
            ratios = [run(sw.servo_controller(res, band_fraction=b), r, loop,
                          play, dt, params, seed + 500)['rms'] / m_lin['rms']
                      for b in BAND_SHARES]
            bands.append([label, f"{play * 1e6:.0f}",
                          f"{c_sw.band_fraction:.2f}",
                          f"{m_sw['rms'] / m_lin['rms']:.2f}",
                          *(f"{x:.2f}" for x in ratios),
                          f"{BAND_SHARES[int(np.argmin(ratios))]:.2f}"])
        if args.sources and "inverts the sandwich's" in repr(c_sw):
            got = [run(sw.servo_controller(res, feedforward_from=f), r, loop,
                       play, dt, params, seed + 500) for f in
                   ('model', 'baseline')]
            near = m_lin['near_reversals']
            sources.append([label, f"{play * 1e6:.0f}",
                            f"{res.fit - res.linear['fit']:.1f}"]
                           + [f"{m['rms'] / m_lin['rms']:.2f}" for m in got]
                           + [f"{m['near_reversals'] / near:.2f}"
                              for m in got])
        if args.to_margin:
            factor = to_margin(c_lin)
            m_up = run(sw.servo_controller(lin, feedback_scale=factor), r,
                       loop, play, dt, params, seed + 500)
            margin.append([label, f"{play * 1e6:.0f}",
                           f"{c_lin.margins['modulus']:.2f}",
                           f"{factor:.2f}", f"{m_lin['rms'] * 1e6:.1f}",
                           m_lin['hunting'], f"{m_up['rms'] * 1e6:.1f}",
                           m_up['hunting']])
        if args.mismatch:
            for what, p_play, p_params in mismatched(play, params):
                a = run(c_lin, r, loop, p_play, dt, p_params, seed + 500)
                b = run(c_sw, r, loop, p_play, dt, p_params, seed + 500)
                quiet = [quiet_hunting(c, m, r, loop, p_play, dt, p_params,
                                       seed + 500)
                         for c, m in ((c_lin, a), (c_sw, b))]
                mism.append([label, f"{play * 1e6:.0f}", what,
                             f"{a['rms'] * 1e6:.1f}", a['hunting'],
                             f"{a['guard']:.2g}",
                             f"{b['rms'] * 1e6:.1f}", b['hunting'],
                             f"{b['guard']:.2g}",
                             f"{b['rms'] / a['rms']:.2f}",
                             b['rms'] / a['rms'], quiet])
        if scales:
            row = [label, f"{play * 1e6:.0f}",
                   'yes' if 'raised together' in c_lin.notes[0] else 'no']
            for f in scales:
                try:
                    c_f = sw.servo_controller(lin, feedback_scale=f)
                except ValueError:
                    row.append('refused')
                    continue
                got = [run(c_f, r, loop, play, dt, params, seed + 500)] + [
                    run(c_f, r, loop, p_play, dt, p_params, seed + 500)
                    for _, p_play, p_params in mismatched(play, params)]
                row.append(f"{got[0]['rms'] * 1e6:.2f} / {got[0]['hunting']}"
                           f" / {max(m['hunting'] for m in got[1:])}")
            scaled_rows.append(row)
        quiet = {name: quiet_hunting(c, m, r, loop, play, dt, params,
                                     seed + 500)
                 for name, c, m in (('lin', c_lin, m_lin), ('sw', c_sw, m_sw))
                 if m['hunting'] >= 3}
        checks.append(dict(label=label, loop=loop, play=play, lin=m_lin,
                           sw=m_sw, res=res, quiet=quiet))
    print("Servo loops on the simulated drive, servo_controller defaults; "
          "errors in um\n")
    print_table(['case', 'play', 'design', 'RMS', 'max', 'near rev.',
                 'TV/lin', 'hunt', 'sat.', 'guard', 'no play', 'best swept',
                 'RMS/lin'], rows)
    big = [c for c in checks if c['play'] >= 100e-6]
    ratio = [c['sw']['rms'] / c['lin']['rms'] for c in checks]
    print(f"\n{len(checks)} drives in {time.perf_counter() - start:.0f} s")
    print(f"sandwich RMS / linear: median {np.median(ratio):.2f}, worst "
          f"{max(ratio):.2f} (target <= 1.05)")
    near = [c['sw']['near_reversals'] / c['lin']['near_reversals']
            for c in checks]
    print(f"sandwich near-reversal error / linear: median "
          f"{np.median(near):.2f}, worst {max(near):.2f} (target <= 1)")
    print(f"hunting (>= 3 reversals in a hold): linear "
          f"{sum(c['lin']['hunting'] >= 3 for c in checks)}, sandwich "
          f"{sum(c['sw']['hunting'] >= 3 for c in checks)} of {len(checks)}")
    for name, design in (('lin', 'linear'), ('sw', 'sandwich')):
        got = [f"{c['label']} ({c[name]['hunting']} -> {c['quiet'][name]})"
               for c in checks if name in c['quiet']]
        print(f"  {design} without the drive's torque disturbance (a limit "
              f"cycle, not the disturbance's jitter): "
              f"{sum(c['quiet'].get(name, 0) >= 3 for c in checks)}"
              + (f"; reversals with -> without: {', '.join(got)}" if got
                 else ""))
    print(f"hunting guard fired (gains scaled down): linear "
          f"{sum(c['lin']['guard'] < 1 for c in checks)}, sandwich "
          f"{sum(c['sw']['guard'] < 1 for c in checks)} of {len(checks)}")
    act = [c['sw']['activity'] / c['lin']['activity'] for c in checks]
    print(f"input activity / linear: worst {max(act):.2f} (target <= 3); "
          f"saturation worst {max(c['sw']['saturation'] for c in checks):.1%}"
          f" (target <= 1 %)")
    if big:
        rb = [c['sw']['rms'] / c['lin']['rms'] for c in big]
        pos = [c['sw']['rms'] / c['lin']['rms'] for c in big
               if c['loop'] == 'position']
        print(f"large play (>= 100 um), {len(big)} drives: RMS ratio median "
              f"{np.median(rb):.2f}" + (f"; position loops ({len(pos)}): "
                                        f"median {np.median(pos):.2f}, worst "
                                        f"{max(pos):.2f}" if pos else "")
              + " (goal <= 0.75 on position drives)")
    for kind in ('all', 'position', 'speed'):
        got = [x for loop, x in swept if kind in ('all', loop)]
        if got and (kind == 'all' or len(got) < len(swept)):
            print(f"play-free linear design / best swept"
                  f"{'' if kind == 'all' else f', {kind} loops'}: median "
                  f"{np.median(got):.2f}, worst {max(got):.2f}, within 2 "
                  f"times on {sum(x <= 2 for x in got)} of {len(got)}"
                  f"{' (target <= 2)' if kind == 'all' else ''}")
    if mism:
        print("\nOn drives that differ from the one identified (RMS um / "
              "hunt / the hunting guard's scale on the gains at the end):\n")
        print_table(['case', 'play', 'drive', 'linear', 'hunt', 'guard',
                     'sandwich', 'hunt', 'guard', 'RMS/lin'],
                    [row[:10] for row in mism])
        ratio = [row[10] for row in mism]
        print(f"hunting (>= 3 reversals in a hold): linear "
              f"{sum(row[4] >= 3 for row in mism)}, sandwich "
              f"{sum(row[7] >= 3 for row in mism)} of {len(mism)}; "
              f"sandwich RMS / linear: median {np.median(ratio):.2f}, "
              f"worst {max(ratio):.2f}")
        quiet = [(f"{row[0]} {row[2]}", row[11]) for row in mism
                 if max(row[11]) >= 3]
        print(f"  without the drives' torque disturbance (a limit cycle): "
              f"linear {sum(row[11][0] >= 3 for row in mism)}, sandwich "
              f"{sum(row[11][1] >= 3 for row in mism)}"
              + ("; reversals without, linear / sandwich: " + ", ".join(
                  f"{name} ({q[0]} / {q[1]})" for name, q in quiet)
                 if quiet else ""))
    if bands:
        print("\nSandwich RMS / linear at fixed band shares:\n")
        print_table(['case', 'play', 'default', 'RMS/lin',
                     *(f"{b:g}" for b in BAND_SHARES), 'best'], bands)
    if sources:
        print("\nSandwich / linear where the default feedforward inverts the "
              "model's mbar L1 L2 (gap: the sandwich's fit over its "
              "baseline's, points):\n")
        print_table(['case', 'play', 'gap', 'RMS model', 'RMS baseline',
                     'near rev. model', 'near rev. baseline'], sources)
    if scaled_rows:
        print("\nThe linear design with its gains scaled (RMS um / hunt on "
              "the drive / most hunt on the drives of MISMATCH); raised: "
              "whether the default design was raised past |T| <= 1\n")
        print_table(['case', 'play', 'raised', *(f"x{f:g}" for f in scales)],
                    scaled_rows)
    if margin:
        print("\nLinear design scaled up to its modulus margin (RMS um / "
              "hunt):\n")
        print_table(['case', 'play', 'margin', 'scale', 'RMS', 'hunt',
                     'scaled RMS', 'hunt'], margin)


if __name__ == '__main__':
    main()
