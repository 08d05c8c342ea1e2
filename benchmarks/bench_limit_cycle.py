"""Limit cycle of a backlash loop: describing function against simulation.

The paper's plant under u = C(z)(r - y) with r = 0, where C is an integral
controller with a first-order low-pass, C(z) = k (1 - p) z / ((z - 1)(z - p)).
The loop is linearly stable with the backlash replaced by its mean slope,
but the backlash sustains a limit cycle. The describing function of the
IDENTIFIED backlash (`sw.backlash_nonlinearity`, centred on a zero output
mean, which the integrator enforces) with the identified L1 and L2 predicts
its amplitude (of x, the backlash input) and frequency; simulations of the
TRUE plant and of the identified model check the prediction.
Target: prediction within 10 % of the simulation.

Amplitudes are in the units of the normalised model (b0 = 1), so the true
plant is simulated in its normalised (input/output-equivalent) form.

Run: python benchmarks/bench_limit_cycle.py
"""

import os
import sys
import warnings

import numpy as np
import control as ct

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import print_table                            # noqa: E402
from bench_compensation import _identified_model           # noqa: E402


def lowpass_integrator(k, p):
    """C(z) = k (1 - p) z / ((z - 1)(z - p))."""
    return ct.tf([k * (1 - p), 0], np.polymul([1, -1], [1, -p]), 1)


def _predict(model, C):
    """Largest-amplitude (stable) describing-function cycle, or None."""
    with warnings.catch_warnings():
        # python-control warns when it cannot refine the small, unstable
        # cycle at the band edge; the stable one is what we compare
        warnings.filterwarnings('ignore', 'not able to refine')
        cycles = sorted(sw.sandwich_limit_cycles(model, C).intersections)
    return (cycles[-1], cycles[:-1]) if cycles else (None, [])


def _pct(pred, ref):
    return f"{100 * (pred - ref) / ref:+.1f} %"


def main():
    plant = sw.examples.paper_plant()
    truth = plant.normalized()
    models = {s: _identified_model(plant, seed=s) for s in range(5)}
    model = models[0]
    bl = model.backlash
    print("Identified backlash (seed 0): "
          f"m1 = {bl.m1:.4f}, m2 = {bl.m2:.4f}, D1 = {bl.D1:.4f}, "
          f"D2 = {bl.D2:.4f}  (true 3, 3.6, 0.3333, 0.4)\n")
    rows, errors = [], []
    for k, p in ((0.3, 0.95), (0.4, 0.95), (0.5, 0.9)):
        C = lowpass_integrator(k, p)
        lin = np.max(np.abs(ct.feedback(
            C * model.L2 * model.L1 * 0.5 * (bl.m1 + bl.m2), 1).poles()))
        stable, unstable = _predict(model, C)
        a_true, w_true, _ = sw.simulate_limit_cycle(truth, C)
        a_id, w_id, _ = sw.simulate_limit_cycle(model, C)
        a_df, w_df = stable
        errors += [abs(a_df - a_true) / a_true, abs(w_df - w_true) / w_true]
        rows.append([f"k={k}, p={p}", f"{lin:.3f}",
                     ', '.join(f"{a:.3f} @ {w:.4f}" for a, w in unstable),
                     f"{a_df:.4f} @ {w_df:.4f}",
                     f"{a_id:.4f} @ {w_id:.4f}",
                     f"{a_true:.4f} @ {w_true:.4f}",
                     f"{_pct(a_df, a_id)}, {_pct(w_df, w_id)}",
                     f"{_pct(a_df, a_true)}, {_pct(w_df, w_true)}"])
    print("1. Prediction from the identified model (seed 0); amplitude of x "
          "@ omega (rad/sample)\n")
    print_table(['controller', 'linear radius', 'unstable DF cycle',
                 'DF stable cycle', 'sim. identified', 'sim. true plant',
                 'DF vs sim. identified', 'DF vs sim. true'], rows)

    k, p = 0.3, 0.95
    C = lowpass_integrator(k, p)
    a_true, w_true, _ = sw.simulate_limit_cycle(truth, C)
    rows = []
    for label, m in [('true model', truth)] + [
            (f'identified, seed {s}', models[s]) for s in models]:
        (a_df, w_df), _ = _predict(m, C)
        errors += [abs(a_df - a_true) / a_true, abs(w_df - w_true) / w_true]
        rows.append([label, f"{a_df:.4f}", f"{w_df:.4f}",
                     _pct(a_df, a_true), _pct(w_df, w_true)])
    print(f"\n2. Controller k={k}, p={p}: predictions from several models "
          f"against the true plant\n   (simulated: amplitude {a_true:.4f}, "
          f"omega {w_true:.4f} rad/sample, period "
          f"{2 * np.pi / w_true:.1f} samples)\n")
    print_table(['model', 'DF amplitude', 'DF omega', 'amplitude error',
                 'omega error'], rows)
    print("\nlinear radius: largest closed-loop pole modulus with the "
          "backlash replaced by its mean slope\n(< 1: linearly stable). "
          "DF: sw.sandwich_limit_cycles (python-control's\n"
          "describing_function_response on the unit-circle FRD of L1 C L2). "
          "sim.: sw.simulate_limit_cycle,\n8000 samples after a reference "
          "pulse, first harmonic of x over the last 4000.")
    print(f"\nlargest prediction error against the true plant: "
          f"{100 * max(errors):.1f} % (target <= 10 %)")


if __name__ == '__main__':
    main()
