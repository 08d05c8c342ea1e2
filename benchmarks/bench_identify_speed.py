"""Speed of identification (issue 16, item 3).

Prints, in one run, the medians of repeated runs of

(a) ``sw.identify`` (method 'oe') on the paper's example, N = 5,000,
    noise-free and at SNR 46.5 (target <= 0.4 s);
(b) ``sw.identify`` against N = 1k ... 1M (paper plant, SNR 100), with
    the time per sample, which stays flat if the time grows linearly
    (above 200,000 samples the long-record path, which
    ``bench_long_records.py`` compares with the exhaustive search);
(c) the paper's bundle recursion, ``method='bundle'`` (eta0 = 0.015,
    k1 = 6), in microseconds per sample (target <= 25 us), and the whole
    call, which also fits the linear baseline of the verdict;
(d) ``sw.refine`` from one start (the true theta + 5 %) on 10,000 samples;
(e) the output-error Jacobian (simulation with sensitivities, the inner
    loop of every refinement) as computed, with rings of past rows for
    the sensitivities of x and v, against whole-record arrays for them,
    side by side (the same numbers, bit for bit).

Timings on a shared machine are noisy; each figure is a median, and the
header says how many BLAS threads numpy may use (OPENBLAS_NUM_THREADS etc.
as set in the environment).

Run: python benchmarks/bench_identify_speed.py
"""

import os
import sys
import warnings

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import median_time, print_table               # noqa: E402

PLANT = sw.examples.paper_plant()
ORDERS = PLANT.orders


def data(n, snr=None, seed=0):
    """The paper's input and the plant's output, with noise at `snr`."""
    u = sw.examples.paper_input(n, seed=seed)
    y = PLANT.simulate(u).outputs
    if snr is not None:
        y = sw.examples.add_noise(y, snr, seed=seed + 1000)
    return u, y


def identify(u, y, **kwargs):
    with warnings.catch_warnings():     # speed only: the verdicts elsewhere
        warnings.simplefilter('ignore')
        return sw.identify(u, y, **ORDERS, **kwargs)


def paper_example():
    rows = []
    for label, snr in (('noise-free', None), ('SNR 46.5', 46.5)):
        u, y = data(5000, snr, seed=1)
        t = median_time(lambda: identify(u, y), repeat=7)
        err = sw.parameter_error(identify(u, y).theta, PLANT.theta)
        rows.append([label, '5,000', f'{t:.3f} s', '<= 0.4 s',
                     'yes' if t <= 0.4 else 'no', f'{err:.1e}'])
    print("(a) sw.identify on the paper's example (method 'oe')\n")
    print_table(['data', 'N', 'median time', 'target', 'met',
                 'parameter error'], rows)


def against_n():
    sizes = (1_000, 2_000, 5_000, 10_000, 20_000, 50_000, 100_000,
             200_000, 500_000, 1_000_000)
    rows, first = [], None
    for n in sizes:
        u, y = data(n, snr=100, seed=2)
        repeat = 5 if n <= 10_000 else 3
        runs = []
        t = median_time(lambda: runs.append(identify(u, y)), repeat=repeat)
        per = t / n * 1e6
        first = first or per
        rows.append([f'{n:,}', f'{t:.3f} s', f'{per:.1f} us',
                     f'{per / first:.2f}', repeat,
                     'yes' if runs[-1].long_record else 'no'])
    print("\n(b) sw.identify against N (paper plant, SNR 100); at most "
          "linear growth: time/N flat or falling (the screening runs on "
          "2,000 samples; above 200,000 samples the search runs on the "
          "leading 50,000, the refinement on all)\n")
    print_table(['N', 'median time', 'time / N', 'relative to 1k',
                 'repeats', 'long record'], rows)


BUNDLE_TARGET = 25.0          # microseconds per sample


def bundle(repeat=5):
    """The paper's recursion (``res.elapsed``), median time per sample
    against the target; and the whole call, with the linear baseline its
    verdict compares with."""
    import statistics
    rows = []
    for n in (2_000, 5_000, 10_000):
        u, y = data(n, snr=None, seed=3)
        runs = []                       # the warm-up run first
        t = median_time(lambda: runs.append(identify(
            u, y, method='bundle', eta0=0.015, k1=6)), repeat=repeat)
        per = statistics.median(r.elapsed for r in runs[1:]) / n * 1e6
        rows.append([f'{n:,}', repeat, f'{per * n * 1e-6:.3f} s',
                     f'{per:.1f} us', f'<= {BUNDLE_TARGET:g} us',
                     f'{per / BUNDLE_TARGET:.2f}',
                     'yes' if per <= BUNDLE_TARGET else 'no', f'{t:.3f} s'])
    print("\n(c) the bundle recursion, sw.identify(method='bundle', "
          "eta0=0.015, k1=6), noise-free; medians of repeated runs; the "
          "whole call also fits the linear baseline of its verdict\n")
    print_table(['N', 'repeats', 'recursion', 'per sample', 'target',
                 'ratio to target', 'met', 'whole call'], rows)


def refine_one_start():
    u, y = data(10_000, snr=100, seed=4)
    start = sw.SandwichSystem.from_theta(PLANT.theta * 1.05, **ORDERS)
    t = median_time(lambda: sw.refine(start, u, y), repeat=5)
    res = sw.refine(start, u, y)
    print("\n(d) sw.refine from one start (true theta + 5 %), N = 10,000, "
          "SNR 100\n")
    print_table(['N', 'median time', 'iterations', 'per iteration',
                 'parameter error'],
                [['10,000', f'{t:.3f} s', res.nit,
                  f'{t / max(res.nit, 1) * 1e3:.1f} ms',
                  f'{sw.parameter_error(res.theta, PLANT.theta):.1e}']])


def jacobian_rings(repeat=7, calls=100):
    import numpy as np
    from sandwichctl.identification import _predictor as pr
    rows = []
    for label, plant, n in (('paper plant', PLANT, 10_000),
                            ('na=nb=nc=nd=3, delays 2', None, 10_000)):
        if plant is None:
            o = (3, 3, 3, 3, 2, 2)
            rng = np.random.default_rng(0)
            theta = np.concatenate([rng.uniform(-0.3, 0.3, 6),
                                    [1.2, 0.9, 0.2, 0.3],
                                    rng.uniform(-0.3, 0.3, 6)])
        else:
            o = tuple(ORDERS[k] for k in ('na', 'nb', 'nc', 'nd', 'q1',
                                          'q2'))
            theta = np.asarray(PLANT.theta, dtype=float)
        u = np.random.default_rng(1).standard_normal(n)
        pad, p = pr.padding(o), theta.size

        def rings():
            for _ in range(calls):
                pr.simulate_with_sensitivities(theta, o, u)

        def whole():
            for _ in range(calls):
                up = np.zeros(pad + n)
                up[pad:] = u
                xs, vs, ys = (np.zeros(pad + n) for _ in range(3))
                zs = np.zeros(pad + n, dtype=np.int64)
                Sx, Sv, Sy = (np.zeros((pad + n, p)) for _ in range(3))
                pr.oe_simulate(theta, o, up, pad, xs, vs, zs, ys, Sx, Sv,
                               Sy)
        t_r = median_time(rings, repeat=repeat) / calls
        t_w = median_time(whole, repeat=repeat) / calls
        rows.append([label, f'{n:,}', p, f'{t_r * 1e3:.3f} ms',
                     f'{t_w * 1e3:.3f} ms', f'{t_w / t_r:.2f}'])
    print("\n(e) the output-error Jacobian, rings against whole-record "
          "sensitivity arrays (medians)\n")
    print_table(['plant', 'N', 'parameters', 'rings', 'whole records',
                 'speed-up'], rows)


def main():
    threads = {k: os.environ.get(k, 'unset') for k in
               ('OPENBLAS_NUM_THREADS', 'OMP_NUM_THREADS', 'MKL_NUM_THREADS')}
    print(f"Identification speed, medians of repeated runs; {os.cpu_count()} "
          f"cores; " + ', '.join(f"{k}={v}" for k, v in threads.items())
          + "\n")
    paper_example()
    against_n()
    bundle()
    refine_one_start()
    jacobian_rings()


if __name__ == '__main__':
    main()
