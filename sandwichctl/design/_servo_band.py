"""The band jump's pieces of `servo_controller`: the static inverses the
band offset takes through L1 and the reference through L2, and how many
samples a band jump is spread over so that L1's inverse does not turn it
into a spike."""

import numpy as np
import control as ct

from ._servo_design import (at_one, low_frequency_gain, preview_inverse,
                            tf_arrays)
from .._checks import warn

#: the exact inverse of a known model notes where its slope lines cross
#: within this many bands of backlash output from zero (the travel of the
#: design's own reference, `design_reference(model, 20, dt)`), and warns
#: where they cross within one band (m1 != m2 with no band: at zero)
CROSSING_BANDS = 20.0

__all__ = []


def static_inverse(num, den):
    """The inverse of a block's DC gain, or of its integrator's gain g
    (u = (z - 1)/(g z) x) when it integrates, after the block's delay:
    numerator, denominator and delay (descending powers of z).

    The band offset takes this way through L1, and the reference this way
    through L2 to the inverse: a full inverse of an identified block
    would turn the offset's jump into whatever the block's fitted fast
    dynamics invert to, and its slow modes would make the backlash
    output wanted wiggle in a hold, each wiggle a jump across the band."""
    q = den.size - num.size
    n, d, integrating = low_frequency_gain(num, den)
    if integrating:
        # (z - 1) / (g z) when the block has no delay: still proper
        q = max(q, 1)
        return np.array([1.0, -1.0]) / (n / d), np.r_[1.0, np.zeros(q)], q
    return np.array([d / n]), np.r_[1.0, np.zeros(q)], q


def jump_samples(L1_num, L1_den, band_x, dt, cap=2.0, longest=50):
    """Samples to spread a band jump over: the fewest for which L1's
    inverse turns a ramp across the band into at most `cap` times the
    input that holds the far side (for an integrating L1: that moves x
    across the band within L1's own response time)."""
    inv_num, inv_den, _, _ = preview_inverse(L1_num, L1_den)
    poles = np.roots(L1_den) if L1_den.size > 1 else np.zeros(0)
    integ = np.any(at_one(poles))
    t = np.arange(4 * longest)
    for n in range(1, longest + 1):
        ramp = band_x * np.minimum(t / n, 1.0)
        u = ct.forced_response(ct.tf(inv_num, inv_den, dt), T=t * dt,
                               U=ramp).outputs
        peak = np.max(np.abs(u))
        if integ:
            # x crosses the band in n samples: at most cap times the input
            # whose integral does it in L1's settling time
            rest = poles[~at_one(poles)]
            slow = max([1.0] + [1 / max(1e-9, 1 - abs(p)) for p in rest])
            hold = np.sum(np.abs(u)) / slow
        else:
            hold = abs(u[-1])
        if peak <= cap * hold:
            return n
    return longest


def crossing_note(model, notes):
    """Where a known model's slope lines cross (m1 != m2, see
    `Backlash.crossing`) within `CROSSING_BANDS` bands of backlash output
    from zero: a note; within one band, a warning too. Beyond the
    crossing eq. (2.2) has no band, and a rising x jumps v up to the
    rising line (a falling one down to the falling line): the outputs
    between the lines cannot be reached, so the exact inverse holds x
    there and the loop tracks such a reference only to within the lines'
    gap."""
    co = model.coefficients
    x = model.backlash.crossing
    if x is None:
        return
    x, v = x + 0.0, co['m1'] * (x - co['D1']) + 0.0    # no -0
    band = 0.5 * (co['m1'] + co['m2']) * (co['D1'] + co['D2'])
    if abs(v) > CROSSING_BANDS * band:
        return
    n, d, integrating = low_frequency_gain(*tf_arrays(model.L2))
    at_y = (f", y = {v * n / d:.4g} at rest" if not integrating else "")
    text = (f"the backlash's slope lines cross at x = {x:.4g} (backlash "
            f"output v = {v:.4g}{at_y}; m1 = {co['m1']:.4g}, m2 = "
            f"{co['m2']:.4g}): beyond it a reversal of x jumps v between "
            f"the lines, so no inverse reaches the outputs between them, "
            f"and the loop tracks there only to within their gap")
    notes.append(text)
    if abs(v) <= band:
        warn(f"servo_controller: {text}; give the model m1 = m2 if it is "
             f"meant to hold there")
