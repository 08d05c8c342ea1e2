r"""Batch output-error refinement over a whole record.

`refine` minimises the paper's objective (2.6),

.. math:: Q(\theta) = \tfrac12 \sum_k \bigl(y(k) - \hat y(k, \theta)\bigr)^2,

with :math:`\hat y` *simulated* by the model from the input alone (output
error). Unlike a predictor that feeds measured past outputs into L2,
this is unbiased under white output noise.

Units, sign and integrators
---------------------------
The fit does not depend on the data's units: u and y are divided by their
standard deviations before the fit, and the model is mapped back (the
slopes scale by sy/su, the thresholds by su). The sign of the overall
gain is taken out of the output, so the backlash slopes stay positive and
a negative gain is carried by d0 = -1 (`SandwichSystem.normalized`).
Poles of the model at z = 1 (integrators) are fixed, and only the other
poles are kept stable.

Method, and why it copes with the nonsmoothness
-----------------------------------------------
Q is piecewise smooth in theta. Its pieces are the zone sequences of
eq. (2.2), and inside a piece the exact Jacobian J comes from the
recursive sensitivities (through L1, the backlash memory and L2). At a
kink, the zone that eq. (2.2) selects gives one of the limiting
Jacobians, which is an element of Clarke's generalised Jacobian.

Each iteration is a Levenberg-Marquardt step, solved as a
box-constrained QP (piqp when a bound binds),

.. math:: \min_d \tfrac12 d^T (J^T J + \mu\,\mathrm{diag}(J^T J)) d
          - (J^T r)^T d \quad\text{s.t.}\quad m_i + d \ge m_{min},\;
          D_i + d \ge 0,

and is accepted only if Q decreases and the free poles stay stable. A
step that crosses a kink without decreasing Q is refused, and mu grows,
so the next step is shorter and stays closer to the current piece. This
is the same safeguard a proximal bundle method gets from its proximity
term, and here it comes with the Gauss-Newton curvature, which on this
objective converges in tens of iterations, not thousands. Multi-start
guards against the local minima that a nonconvex output-error cost has.
"""

import time

import numpy as np

from ._data import prepare, with_shift
from ._lm import lm
from ._problem import Problem, unit_poles
from ._starts import admissible, perturb
from ..model.sandwich import SandwichSystem
from .._checks import (MOST_ROUNDS, MOST_STARTS, check_bool,
                       check_data_scale, check_int, check_positive, check_rng,
                       check_tolerance, progress_bar, serial_blas)

__all__ = ['refine']


@serial_blas
def refine(model, u, y=None, max_iter=100, tol=1e-10, n_starts=1,
           spread=0.3, seed=None, m_min=1e-9, progress=False,
           offsets='none'):
    r"""Refine a sandwich model on a whole record by output-error LM.

    Parameters
    ----------
    model : SandwichSystem
        Initial model (e.g. ``identify(...).model``); its orders, delays,
        integrators (poles exactly at z = 1) and the sign of its gain are
        kept.
    u, y : array_like, shape (N,)
        Input and measured output, from zero initial state; or, in `u`
        alone, a ``control.TimeResponseData`` or a list of experiments
        (see `identify`).
    max_iter : int, optional
        Maximum Levenberg-Marquardt iterations per start (default 100).
    tol : float, optional
        Stop when the relative decrease of the cost, or the relative
        step, falls below tol (0 < tol < 1).
    n_starts : int, optional
        Number of starts: the model itself plus ``n_starts - 1`` random
        perturbations of it (default 1). The best final cost wins.
    spread : float, optional
        Relative size of the multi-start perturbations of the model's
        parameters (at least 0.05 absolute; default 0.3).
    seed : int or numpy.random.Generator, optional
        Seed of the perturbations.
    m_min : float, optional
        Lower bound on the slopes m1, m2 that keeps them positive, in
        (0, 1) (default 1e-9). It applies to the slopes on the scaled
        data (u and y divided by their standard deviations, see the module
        notes), not to those in the data's units.
    progress : bool, optional
        Show a progress bar over the starts.
    offsets : {'none', 'mean', 'estimate'}, optional
        As in `identify` (default 'none').

    Returns
    -------
    IdentificationResult
        ``model`` (in the data's units), ``theta``, ``errors`` (final
        residuals), ``std`` (standard errors from sigma^2 (J'J)^-1),
        ``fit`` (percent, as MATLAB's ``compare``), ``cost``, ``success``
        and ``message``.

    Examples
    --------
    >>> import numpy as np, sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> u = sw.examples.paper_input(3000, seed=0)
    >>> y = plant.simulate(u).outputs
    >>> start = sw.SandwichSystem.from_theta(plant.theta * 1.05,
    ...                                      **plant.orders)
    >>> res = sw.refine(start, u, y)
    >>> bool(sw.parameter_error(res.theta, plant.theta) < 1e-6)
    True
    """
    if not isinstance(model, SandwichSystem):
        raise TypeError(f"model must be a SandwichSystem; got "
                        f"{type(model).__name__}")
    us, ys, _, offset_info, estimate = prepare(u, y, model.dt, offsets)
    check_data_scale('u', us), check_data_scale('y', ys)
    max_iter = check_int('max_iter', max_iter, 1, MOST_ROUNDS)
    progress = check_bool('progress', progress)
    n_starts = check_int('n_starts', n_starts, 1, MOST_STARTS)
    tol = check_tolerance('tol', tol)
    spread = check_positive('spread', spread)
    m_min = check_positive('m_min', m_min)
    if not m_min < 1:
        raise ValueError(
            f"m_min must be in (0, 1); got {m_min!r}. It keeps the slopes "
            f"positive on the scaled data (u and y divided by their "
            f"standard deviations), not in the data's units; a bound of 1 "
            f"or more there would override the data rather than guard "
            f"the slopes")
    norm = model.normalized()
    co = norm.coefficients
    prob = Problem(us, ys, norm.orders, i1=unit_poles(co['a']),
                   i2=unit_poles(co['c']), sign=norm.gain_sign, dt=model.dt,
                   name=model.name, offsets=estimate)
    st = prob.st
    if prob.n_samples <= 2 * st.size:
        raise ValueError(f"the data have {prob.n_samples} samples, too few "
                         f"for {st.size} parameters")
    phi0 = admissible(st, prob.phi_of_model(norm), m_min)
    st.widen_zero_radius(phi0)
    rng = check_rng('seed', seed)
    start = time.perf_counter()
    best = None
    for i in _progress_range(n_starts, progress, 'refine'):
        phi = phi0 if i == 0 else perturb(st, phi0, rng, spread, m_min,
                                          tries=100)
        if phi is None:
            phi = phi0.copy()
        out = lm(st, phi, prob.u, prob.y, max_iter, tol, m_min=m_min)
        if best is None or out['cost'] < best['cost']:
            best = out
    res = prob.result(best, 'refine', extra={
        'theta0': st.theta(phi0) * prob.unit,
        'elapsed': time.perf_counter() - start,
        'options': dict(max_iter=max_iter, tol=tol, n_starts=n_starts,
                        spread=spread, m_min=m_min)})
    res.counts['starts'] = n_starts
    estimated = (res.get('offsets') or {}).get('y')
    res.offsets = with_shift(offset_info, estimated)
    return res


def _progress_range(n, progress, desc, step=1):
    """range(0, n, step), with a tqdm bar (notebook widget in Jupyter,
    text in a terminal) when asked for."""
    steps = range(0, n, step)
    if not progress:
        return steps
    return progress_bar(True, iterable=steps, desc=desc, leave=False)
