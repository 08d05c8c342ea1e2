"""Command line: ``python -m sandwichctl demo``.

The demo simulates the paper's Section 5 plant and writes its figures to
the output folder.
"""

import argparse
import os
import sys


def _demo(args):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    import numpy as np
    from . import examples

    os.makedirs(args.out, exist_ok=True)
    plant = examples.paper_plant()
    print(plant)
    u = examples.paper_input(args.samples, seed=args.seed)
    resp = plant.simulate(u, internal=True)
    y, x, v = resp.outputs
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    n = min(200, u.size)
    axes[0].plot(resp.time[:n], u[:n], label='u', lw=0.8)
    axes[0].plot(resp.time[:n], y[:n], label='y', lw=0.8)
    axes[0].set_xlabel('k')
    axes[0].legend()
    axes[0].set_title('Section 5 plant: input and output')
    axes[1].plot(x, v, lw=0.5)
    axes[1].set_xlabel('x (backlash input)')
    axes[1].set_ylabel('v (backlash output)')
    axes[1].set_title('Backlash loop, eq. (2.2)')
    fig.tight_layout()
    path = os.path.join(args.out, 'simulation.png')
    fig.savefig(path, dpi=120)
    print(f"simulated {u.size} samples; y range [{y.min():.3f}, "
          f"{y.max():.3f}]; figure written to {path}")
    return 0


def main(argv=None):
    """Entry point of the ``sandwichctl`` command."""
    parser = argparse.ArgumentParser(
        prog='python -m sandwichctl',
        description='sandwichctl: sandwich systems with backlash.')
    sub = parser.add_subparsers(dest='command', required=True)
    demo = sub.add_parser('demo', help="reproduce the paper's Section 5")
    demo.add_argument('--out', default='out', help='output folder')
    demo.add_argument('--samples', type=int, default=20000)
    demo.add_argument('--seed', type=int, default=0)
    args = parser.parse_args(argv)
    return {'demo': _demo}[args.command](args)


if __name__ == '__main__':
    sys.exit(main())
