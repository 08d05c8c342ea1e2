"""Speed of SandwichSystem.simulate against ct.input_output_response.

Targets (issue 2): 1,000,000 samples of the paper's example in <= 50 ms,
and >= 1000x faster than python-control on the same 10,000-sample input.
Every figure is the median of repeated runs in this one process.

Run: python benchmarks/bench_simulate.py
"""

import os
import sys

import numpy as np
import control as ct

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import median_time, print_table               # noqa: E402


def main():
    plant = sw.examples.paper_plant()
    u_big = sw.examples.paper_input(1_000_000, seed=0)
    u_10k = u_big[:10_000]
    t_big = median_time(lambda: plant.simulate(u_big), repeat=11)
    t_fast = median_time(lambda: plant.simulate(u_10k), repeat=21)
    t_ct = median_time(
        lambda: ct.input_output_response(plant, np.arange(u_10k.size), u_10k),
        repeat=3, warmup=0)
    err = np.max(np.abs(
        plant.simulate(u_10k).outputs
        - ct.input_output_response(plant, np.arange(10_000), u_10k).outputs))
    print("Simulation of the paper's Section 5 plant (median of repeats)\n")
    print_table(
        ['case', 'samples', 'time', 'per sample', 'target'],
        [['simulate (numba kernel)', '1,000,000', f'{t_big * 1e3:.1f} ms',
          f'{t_big / 1e6 * 1e9:.1f} ns', '<= 50 ms'],
         ['simulate (numba kernel)', '10,000', f'{t_fast * 1e3:.2f} ms',
          f'{t_fast / 1e4 * 1e9:.1f} ns', ''],
         ['ct.input_output_response', '10,000', f'{t_ct * 1e3:.0f} ms',
          f'{t_ct / 1e4 * 1e6:.0f} us', '']])
    print(f"\nspeed-up on 10,000 samples: {t_ct / t_fast:,.0f}x "
          f"(target >= 1000x)")
    print(f"max |y_fast - y_python-control| = {err:.1e} (target <= 1e-10)")


if __name__ == '__main__':
    main()
