"""Speed of SandwichSystem.simulate against a tight loop and python-control.

Measured side by side in this one process, in ns per sample (medians of
repeats; the tight loop and `simulate` are timed alternately so that a
busy machine slows both alike):

* the tight loop: a numba loop of the paper's Section 5 plant written as
  the difference equations (2.1) with its coefficients as literals, the
  backlash by `backlash_step` (eq. (2.2)), allocating its output like
  `simulate` does;
* ``plant.simulate`` on the same 1,000,000 samples (target: <= 1.5x the
  tight loop);
* ``ct.input_output_response`` on 10,000 samples;
* ``plant.simulate_batch`` on 64 signals x 10,000 samples, with 1 and 2
  numba threads (signals per second).

Run: python benchmarks/bench_simulate.py
"""

import os
import statistics
import sys
import time

import numba
import numpy as np
import control as ct

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from sandwichctl.model.backlash import backlash_step       # noqa: E402
from _timing import median_time, print_table               # noqa: E402


@numba.njit(cache=True)
def tight_loop(u):
    """The paper's plant as direct-form difference equations (2.1)."""
    y = np.empty(u.size)
    x1 = x2 = u1 = 0.0                    # x(k-1), x(k-2), u(k-1)
    v1 = v2 = y1 = y2 = 0.0               # v(k-1), v(k-2), y(k-1), y(k-2)
    for k in range(u.size):
        # x(k) = -0.1 x(k-1) - 0.2 x(k-2) + 1.5 u(k-1)
        x = -0.1 * x1 - 0.2 * x2 + 1.5 * u1
        v, _ = backlash_step(x, x1, v1, 1.0, 1.2, 0.5, 0.6)
        # y(k) = -1.2 y(k-1) - 0.32 y(k-2) + 2 v(k-1) - 0.1 v(k-2)
        yk = -1.2 * y1 - 0.32 * y2 + 2.0 * v1 - 0.1 * v2
        y[k] = yk
        x2, x1, u1 = x1, x, u[k]
        v2, v1 = v1, v
        y2, y1 = y1, yk
    return y


def alternate(funcs, repeat):
    """Median times of `funcs`, run in turn `repeat` times (after a warmup)."""
    times = [[] for _ in funcs]
    for f in funcs:
        f()
    for _ in range(repeat):
        for f, ts in zip(funcs, times):
            start = time.perf_counter()
            f()
            ts.append(time.perf_counter() - start)
    return [statistics.median(ts) for ts in times]


def main():
    plant = sw.examples.paper_plant()
    n_big, n_ct = 1_000_000, 10_000
    u_big = sw.examples.paper_input(n_big, seed=0)
    u_ct = u_big[:n_ct]
    t_tight, t_sim = alternate(
        [lambda: tight_loop(u_big), lambda: plant.simulate(u_big)], 15)
    t_ct = median_time(
        lambda: ct.input_output_response(plant, np.arange(n_ct), u_ct),
        repeat=3, warmup=0)
    y_ct = ct.input_output_response(plant, np.arange(n_ct), u_ct).outputs
    err = np.max(np.abs(plant.simulate(u_ct).outputs - y_ct))
    err_tight = np.max(np.abs(plant.simulate(u_big).outputs
                              - tight_loop(u_big)))

    # batch: 64 signals x 10,000 samples, 1 and 2 threads
    U = np.stack([sw.examples.paper_input(10_000, seed=s)
                  for s in range(64)])
    threads = numba.get_num_threads()
    t_batch, results = {}, {}
    for nt in sorted({1, min(2, numba.config.NUMBA_NUM_THREADS)}):
        numba.set_num_threads(nt)
        t_batch[nt] = median_time(lambda: plant.simulate_batch(U), repeat=9)
        results[nt] = plant.simulate_batch(U)
    numba.set_num_threads(threads)
    loop = np.stack([plant.simulate(u).outputs for u in U])
    same = all(np.array_equal(r, loop) for r in results.values())

    ns = 1e9
    print("Simulation of the paper's Section 5 plant (medians of repeats)\n")
    print_table(
        ['case', 'samples', 'time', 'per sample'],
        [['tight loop (numba, eq. (2.1))', f'{n_big:,}',
          f'{t_tight * 1e3:.2f} ms', f'{t_tight / n_big * ns:.2f} ns'],
         ['plant.simulate', f'{n_big:,}', f'{t_sim * 1e3:.2f} ms',
          f'{t_sim / n_big * ns:.2f} ns'],
         ['ct.input_output_response', f'{n_ct:,}', f'{t_ct * 1e3:.0f} ms',
          f'{t_ct / n_ct * ns:,.0f} ns']])
    print(f"\nsimulate / tight loop       = {t_sim / t_tight:.2f}x "
          f"(target <= 1.5x)")
    print(f"python-control / simulate   = "
          f"{(t_ct / n_ct) / (t_sim / n_big):,.0f}x (per sample)")
    print(f"max |y_simulate - y_python-control| = {err:.1e} "
          f"(target <= 1e-10)")
    print(f"max |y_simulate - y_tight|          = {err_tight:.1e}")
    print(f"\nsimulate_batch, {U.shape[0]} signals x {U.shape[1]:,} samples\n")
    print_table(
        ['threads', 'time', 'signals/s', 'per sample', 'speed-up'],
        [[str(nt), f'{t * 1e3:.2f} ms', f'{U.shape[0] / t:,.0f}',
          f'{t / U.size * ns:.2f} ns', f'{t_batch[1] / t:.2f}x']
         for nt, t in t_batch.items()])
    print(f"\nbatch rows equal a loop of simulate bit for bit "
          f"(every thread count): {same}")


if __name__ == '__main__':
    main()
