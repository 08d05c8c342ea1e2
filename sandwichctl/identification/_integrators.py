"""The integrator decision of step 3 of ``identify(method='oe')``
(`_search.step3_integrators`): where the integrators may go, which fits
are evidence for one, and the floor the choice must keep. Private."""

import numpy as np

from ._linear import wants_integrator

__all__ = []


def integrator_split(k, orders, block):
    """(i1, i2): k integrators in `block` ('L1', 'L2', or 'auto' as L1)
    first, the rest in the other block."""
    na, nc = orders['na'], orders['nc']
    first = nc if block == 'L2' else na
    if k > na + nc:
        raise ValueError(f"integrators = {k} exceed the na + nc = "
                         f"{na + nc} poles of the structure")
    i_first = min(k, first)
    i_second = k - i_first
    return (i_second, i_first) if block == 'L2' else (i_first, i_second)


def integrator_splits(k, orders, block):
    """The (i1, i2) the search tries for k integrators: the one of
    `integrator_split` for a `block` 'L1' or 'L2'; for 'auto' every way
    of placing them in blocks with poles enough (na for L1, nc for L2),
    L1's fullest first."""
    if block != 'auto' or k == 0:
        return [integrator_split(k, orders, block)]
    na, nc = orders['na'], orders['nc']
    return [(i1, k - i1) for i1 in range(min(k, na), -1, -1)
            if k - i1 <= nc]


def split_label(split):
    """'1 in L1', '1 in L2', '1 in L1 + 1 in L2' or '0' for (i1, i2)."""
    parts = [f"{i} in {blk}" for i, blk in zip(split, ('L1', 'L2')) if i]
    return ' + '.join(parts) or '0'


#: a zero of the model this close to z = 1 cancels its integrator: the
#: fit carries a drift term, and is no evidence for an integrator
DRIFT_ZERO = 1e-4


def drift(fit):
    """The zero of an integrating fit (problem, best, linear) that cancels
    its pole at z = 1 (within `DRIFT_ZERO`), or None."""
    model = _model(fit)
    with np.errstate(all='ignore'):
        zeros = np.r_[model.L1.zeros(), model.L2.zeros()]
    near = zeros[np.abs(zeros - 1) < DRIFT_ZERO]
    return float(np.real(near[0])) if near.size else None


def integrator_floor(fits, chosen):
    """The never-worse-than-linear floor across the integrator decision:
    an integrating sandwich `chosen` (an (i1, i2) of `fits`, in either
    block) is kept only if it is cheaper than the integrator-free linear
    fit it must beat (a search without an integrator that diverged or
    stalled is no evidence for one)."""
    free = (0, 0)
    if sum(chosen) and free in fits and not fits[chosen][1]['cost'] < \
            fits[free][2].get('held', fits[free][2])['cost_scaled']:
        return free
    return chosen


def slow_pole(fit):
    """Whether the sandwich fit (problem, best, linear) without an
    integrator has a real pole above 0.9 in L1 or L2 (`wants_integrator`):
    a reason to try one where the linear fit, which the backlash may
    dominate, gave none."""
    model = _model(fit)
    return any(wants_integrator(block.den[0][0])
               for block in (model.L1, model.L2))


def worth_integrating(fit, flat=True):
    """Whether integrators='auto' runs the integrating searches after the
    sandwich fit (problem, best, linear) without an integrator, where the
    linear fit gave no reason to: a slow real pole (`slow_pole`), or a
    parameter the data leave poorly determined. A flat cost has other
    basins, and a search with an integrator reaches some: the fit without
    one restarts from it when it ends cheaper (`_search._unintegrated`).
    On robustness families 6 and 8 that fixed four local optima, one at
    2.63 times the optimum's cost, for about half as much time again
    (the benchmarks page). `flat`: whether poorly determined parameters
    count (not on the leading samples of a long record, where they cost
    3 to 5 times the path's time and changed no model of the
    benchmark)."""
    prob, out, _ = fit
    return slow_pole(fit) or (flat and prob.poorly_determined(out))


def _model(fit):
    """The sandwich of a fit (problem, best, linear)."""
    prob, out, _ = fit
    with np.errstate(all='ignore'):
        return prob.model(out['phi'])
