"""Command line: ``python -m sandwichctl demo``.

The demo first does the library's main job on a physically simulated
ball-screw axis (`sw.data.ServoDrive`, a position loop with 200 um of
play; not a sandwich system): it identifies a sandwich model and its
linear baseline from one 5 s record, designs a servo controller from each
with `servo_controller`'s defaults, runs both against the drive one
sample at a time, and the linear one against the same drive without play
(the limit); it prints their errors, exports the sandwich controller as
C and draws the loops.

It then reproduces the paper's Section 5 study: the bundle method
against the gradient baseline under both of its readings, noise-free and
noisy. The paper's "SNR equal to 46.5" is run under its three readings
(variance ratio, amplitude ratio, dB; see ``docs/reproduction.md``). It
prints a parameter table with an ``error`` line per case and writes
Fig. 2 and the three versions of Fig. 3 to the output folder.
"""

import argparse
import math
import os
import sys


def _servo(out, plt):
    """The main job: the play compensated in closed loop on the drive."""
    import warnings
    import sandwichctl as sw

    print("== servo loop on a simulated ball-screw axis ==")
    print("sw.data.ServoDrive: DC motor in a digital speed and position "
          "loop, ball screw, 200 um of play to a 20 kg platform with "
          "friction, 1 um encoder; u = motor angle reference, y = platform "
          "position (a physical simulation, not the model)")
    case = sw.data.drive_case(0, loop='position', play=200e-6)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        res = sw.identify(case.u, case.y, na=2, nb=1, nc=2, nd=1, q1=1,
                          q2=0, dt=case.dt)
        lin = sw.identify_linear(case.u, case.y, nb=3, nf=4, nk=1,
                                 dt=case.dt, max_iter=400)
    print(f"identified from one 5 s record: sandwich fit {res.fit:.2f} % "
          f"(success {res.success}), linear output-error fit "
          f"{lin.fit:.2f} %")
    designs = {'linear': sw.servo_controller(lin),
               'sandwich': sw.servo_controller(res)}
    r = sw.servo_reference(case.dt, 1e-3)
    runs = [(name, ctrl, 200e-6) for name, ctrl in designs.items()]
    runs.append(('linear, no play', designs['linear'], 0.0))
    print(f"{'design':<16} {'RMS um':>7} {'max um':>7} {'near rev. um':>12}"
          f" {'hunting':>7} {'saturated':>9}")
    loops = {}
    for name, ctrl, play in runs:
        drive = sw.data.ServoDrive('position', play, case.dt, seed=500,
                                   n=r.size)
        loops[name] = sw.closed_loop_response(drive, r, ctrl)
        m = sw.servo_metrics(r, *loops[name].outputs, case.dt,
                             deadband=1.5e-6)
        print(f"{name:<16} {m['rms'] * 1e6:7.1f} {m['max'] * 1e6:7.0f} "
              f"{m['near_reversals'] * 1e6:12.1f} {m['hunting']:7d} "
              f"{drive.saturated / r.size:9.1%}")
        loops[name].rms = m['rms']
    print(f"sandwich RMS / linear RMS: "
          f"{loops['sandwich'].rms / loops['linear'].rms:.2f}")
    header, source = sw.export_c(designs['sandwich'], out, name='axis')
    print(f"sandwich controller exported as plain C99: {header}, {source}")
    t = loops['linear'].time
    fig, axs = plt.subplots(2, 1, sharex=True, figsize=(9, 6))
    axs[0].plot(t, r * 1e3, 'k--', lw=1, label='reference')
    for name, color in (('linear', 'tab:red'), ('sandwich', 'tab:blue'),
                        ('linear, no play', '0.6')):
        y = loops[name].outputs[0]
        if name != 'linear, no play':
            axs[0].plot(t, y * 1e3, color=color, lw=1, label=name)
        axs[1].plot(t, (r - y) * 1e6, color=color, lw=1, label=name)
    axs[0].set_ylabel('position [mm]')
    axs[1].set_ylabel('error [um]')
    axs[1].set_xlabel('time [s]')
    for ax in axs:
        ax.legend(loc='upper right', fontsize='small')
    axs[0].set_title('Position loop on the simulated drive with 200 um of '
                     'play: servo_controller defaults')
    path = os.path.join(out, 'servo_loop.png')
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"figure written to {path}\n")


def _demo(args):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from .paper import section5

    os.makedirs(args.out, exist_ok=True)
    if not args.no_servo:
        _servo(args.out, plt)
    print("Reproducing Section 5 of the paper: the sandwich plant (5.1)-(5.2)"
          f" identified from {args.samples} samples of Gaussian input with "
          "variance 0.49")
    print("Methods: the paper's bundle method; the gradient baseline with "
          "the nonsmooth samples skipped (gradient/skip, the default "
          "reading) and updated with a Clarke subgradient "
          "(gradient/subgradient)")
    cases = [(None, 'variance', 'fig2_noise_free.png')]
    cases += [(args.snr, kind, f"fig3_noisy_{kind}.png")
              for kind in ('variance', 'amplitude', 'db')]
    for snr, kind, fname in cases:
        title = section5.snr_label(snr, kind)
        if snr is not None:
            title = f"noisy, {title}"
        print(f"\n== {title} ==", flush=True)
        run = section5.section5_run(args.samples, seed=args.seed, snr=snr,
                                    snr_kind=kind, progress=True)
        print(section5.section5_table(run))
        for label, res in run['results'].items():
            print(f"{label}: {res.message}; steps {res.counts}; "
                  f"{res.elapsed / max(res.nit, 1) * 1e6:.1f} us/sample")
        fig = section5.plot_section5(
            run, title=f"Section 5, {title}: parameter estimates "
                       f"(dashed: equivalent true values)")
        path = os.path.join(args.out, fname)
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print(f"figure written to {path}")
    return 0


def _number(kind, low, above=False):
    """An argparse type: a finite `kind` >= `low` (> `low` with `above`),
    checked before the demo spends a minute on a value it refuses."""
    def read(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected {'an integer' if kind is int else 'a number'}; "
                f"got {text!r}") from None
        if not math.isfinite(value) or value < low or (above and
                                                       value == low):
            raise argparse.ArgumentTypeError(
                f"expected a finite number {'>' if above else '>='} {low}; "
                f"got {text}")
        return value
    return read


def main(argv=None):
    """Entry point of the ``sandwichctl`` command."""
    parser = argparse.ArgumentParser(
        prog='python -m sandwichctl',
        description='sandwichctl: sandwich systems with backlash.')
    sub = parser.add_subparsers(dest='command', required=True)
    demo = sub.add_parser('demo', help="a servo loop on a simulated axis, "
                          "then the paper's Section 5")
    demo.add_argument('--out', default='out', help='output folder')
    demo.add_argument('--samples', type=_number(int, 100), default=20000,
                      help='samples of each Section 5 run (at least 100)')
    demo.add_argument('--seed', type=_number(int, 0), default=0)
    demo.add_argument('--no-servo', action='store_true',
                      help='skip the servo loop on the simulated axis')
    demo.add_argument('--snr', type=_number(float, 0, above=True),
                      default=46.5,
                      help='SNR of the noisy runs, read in turn as a '
                           'variance ratio, an amplitude ratio and in dB')
    args = parser.parse_args(argv)
    if os.path.exists(args.out) and not os.path.isdir(args.out):
        parser.error(f"--out {args.out!r} is a file, not a folder")
    return {'demo': _demo}[args.command](args)


if __name__ == '__main__':
    sys.exit(main())
