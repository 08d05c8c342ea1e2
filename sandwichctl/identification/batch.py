r"""Batch output-error refinement over a whole record.

`refine` minimises the paper's objective (2.6),

.. math:: Q(\theta) = \tfrac12 \sum_k \bigl(y(k) - \hat y(k, \theta)\bigr)^2,

with :math:`\hat y` *simulated* by the model from the input alone (output
error). Unlike a predictor that feeds measured past outputs into L2,
this is unbiased under white output noise.

Method, and why it copes with the nonsmoothness
-----------------------------------------------
Q is piecewise smooth in theta. Its pieces are the zone sequences of
eq. (2.2), and inside a piece the exact Jacobian J comes from the
recursive sensitivities (through L1, the backlash memory and L2; see
`simulate_with_sensitivities`). At a kink, the zone that eq. (2.2)
selects gives one of the limiting Jacobians, which is an element of
Clarke's generalised Jacobian.

Each iteration is a Levenberg-Marquardt step, solved with piqp as a
box-constrained QP,

.. math:: \min_d \tfrac12 d^T (J^T J + \mu\,\mathrm{diag}(J^T J)) d
          - (J^T r)^T d \quad\text{s.t.}\quad m_i + d \ge m_{min},\;
          D_i + d \ge 0,

and is accepted only if Q decreases and both denominators stay stable.
A step that crosses a kink without decreasing Q is refused, and mu
grows, so the next step is shorter and stays closer to the current
piece. This is the same safeguard a proximal bundle method gets from its
proximity term, and here it comes with the Gauss-Newton curvature, which
on this objective converges in tens of iterations, not thousands.
Multi-start guards against the local minima that a nonconvex output-error
cost has.
"""

import time
import warnings

import numpy as np

from ._predictor import (simulate_with_sensitivities, is_stable,
                         stable_and_finite)
from ._qp import box_qp, QPError
from .result import IdentificationResult
from ..model.sandwich import SandwichSystem
from .._checks import check_signal, check_int, check_positive

__all__ = ['refine']


def _admissible(theta, o, m_min):
    """Finite, stable (see `_predictor.stable_and_finite`), m >= m_min,
    D >= 0."""
    im = o[2] + o[0]
    return (stable_and_finite(theta, o)
            and np.all(theta[im:im + 2] >= m_min)
            and np.all(theta[im + 2:im + 4] >= 0))


def _lm(theta, o, u, y, max_iter, tol, m_min):
    """Levenberg-Marquardt with box constraints; returns a dict."""
    p = theta.size
    im = o[2] + o[0]
    lo = np.full(p, -np.inf)
    hi = np.full(p, np.inf)
    yhat, J, _ = simulate_with_sensitivities(theta, o, u)
    r = y - yhat
    cost = 0.5 * r @ r
    if not np.isfinite(cost):
        cost = np.inf
    mu = 1e-3
    history = [theta.copy()]
    message = f"reached max_iter = {max_iter}"
    it = 0
    for it in range(1, max_iter + 1):
        A = J.T @ J
        g = J.T @ r
        scale = np.maximum(np.diag(A), 1e-12 * max(np.max(np.diag(A)), 1e-300))
        accepted = False
        while mu < 1e12:
            lo[im:im + 2] = m_min - theta[im:im + 2]
            lo[im + 2:im + 4] = -theta[im + 2:im + 4]
            try:
                d = box_qp(A + mu * np.diag(scale), -g, lo, hi)
            except QPError:
                mu *= 10
                continue
            trial = theta + d
            trial[im:im + 2] = np.maximum(trial[im:im + 2], m_min)
            trial[im + 2:im + 4] = np.maximum(trial[im + 2:im + 4], 0.0)
            if not _admissible(trial, o, m_min):
                mu *= 10
                continue
            y_t, J_t, _ = simulate_with_sensitivities(trial, o, u)
            r_t = y - y_t
            cost_t = 0.5 * r_t @ r_t
            if np.isfinite(cost_t) and cost_t < cost:
                accepted = True
                break
            mu *= 10
        if not accepted:
            message = "converged: no decreasing step found (mu too large)"
            break
        decrease = ((cost - cost_t) / max(cost, 1e-300)
                    if np.isfinite(cost) else 1.0)
        step = np.linalg.norm(trial - theta)
        theta, yhat, J, r, cost = trial, y_t, J_t, r_t, cost_t
        history.append(theta.copy())
        mu = max(mu / 3, 1e-9)
        if decrease < tol or step < tol * (1 + np.linalg.norm(theta)):
            message = (f"converged: relative decrease {decrease:.1e} or "
                       f"step {step:.1e} below tol")
            break
    return dict(theta=theta, cost=cost, J=J, r=r, yhat=yhat, nit=it,
                history=np.array(history), message=message)


def _admissible_start(theta, o, m_min):
    """Move a start into the domain: slopes >= m_min, D >= 0, and unstable
    denominators pulled inside the unit circle (roots scaled by 0.9 until
    stable)."""
    theta = theta.copy()
    na, nb, nc, nd = o[:4]
    im = nc + na
    theta[~np.isfinite(theta)] = 0.0
    theta[im:im + 2] = np.maximum(theta[im:im + 2], max(m_min, 1e-3))
    theta[im + 2:im + 4] = np.maximum(theta[im + 2:im + 4], 0.0)
    for start, n in ((0, nc), (nc, na)):
        powers = 0.9 ** np.arange(1, n + 1)
        for _ in range(200):
            if is_stable(theta, start, n, 1e-3):
                break
            theta[start:start + n] *= powers
    return theta


def _perturb(theta, o, rng, spread, m_min):
    """A random admissible start near theta (multi-start)."""
    na, nb, nc, nd = o[:4]
    im = nc + na
    for _ in range(100):
        trial = theta.copy()
        lin = np.r_[0:im, im + 4:theta.size]
        trial[lin] += spread * rng.standard_normal(lin.size) * (
            np.abs(theta[lin]) + 0.1)
        trial[im:im + 4] *= np.exp(spread * rng.standard_normal(4))
        trial[im + 2:im + 4] += 1e-3
        if _admissible(trial, o, m_min):
            return trial
    return theta.copy()


def refine(model, u, y, max_iter=100, tol=1e-10, n_starts=1, spread=0.3,
           seed=None, m_min=1e-6, progress=False):
    r"""Refine a sandwich model on a whole record by output-error LM.

    Parameters
    ----------
    model : SandwichSystem
        Initial model (e.g. ``identify(...).model``); its orders and
        delays are kept. It is normalised (b0 = d0 = 1) first.
    u, y : array_like, shape (N,)
        Input and measured output, from zero initial state.
    max_iter : int, optional
        Maximum Levenberg-Marquardt iterations per start (default 100).
    tol : float, optional
        Stop when the relative decrease of the cost, or the relative
        step, falls below tol.
    n_starts : int, optional
        Number of starts: the model itself plus ``n_starts - 1`` random
        perturbations of it (default 1). The best final cost wins.
    spread : float, optional
        Relative size of the multi-start perturbations (default 0.3).
    seed : int or numpy.random.Generator, optional
        Seed of the perturbations.
    m_min : float, optional
        Lower bound on the slopes m1, m2.
    progress : bool, optional
        Print one line per start.

    Returns
    -------
    IdentificationResult
        ``model``, ``theta``, ``history`` (one row per iteration of the
        best start), ``errors`` (final residuals), ``std`` (standard
        errors from sigma^2 (J'J)^-1), ``fit`` (percent, as MATLAB's
        ``compare``), ``cost``, ``success`` and ``message``.

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
    u = check_signal('u', u)
    y = check_signal('y', y)
    if u.size != y.size:
        raise ValueError(f"u and y must have the same length; got "
                         f"{u.size} and {y.size} samples")
    max_iter = check_int('max_iter', max_iter, minimum=1)
    n_starts = check_int('n_starts', n_starts, minimum=1)
    tol = check_positive('tol', tol)
    spread = check_positive('spread', spread)
    m_min = check_positive('m_min', m_min)
    orders = model.orders
    o = tuple(orders[k] for k in ('na', 'nb', 'nc', 'nd', 'q1', 'q2'))
    theta0 = _admissible_start(model.theta, o, m_min)
    p = theta0.size
    if u.size <= 2 * p:
        raise ValueError(f"u and y have {u.size} samples, too few for {p} "
                         f"parameters")
    rng = np.random.default_rng(seed)
    start = time.perf_counter()
    best = None
    for i in range(n_starts):
        th = theta0.copy() if i == 0 else _perturb(theta0, o, rng, spread,
                                                   m_min)
        th = _admissible_start(th, o, m_min)
        out = _lm(th, o, u, y, max_iter, tol, m_min)
        if progress:
            print(f"refine start {i + 1}/{n_starts}: cost {out['cost']:.6g} "
                  f"after {out['nit']} iterations", flush=True)
        if best is None or out['cost'] < best['cost']:
            best = out
    theta = best['theta']
    r = best['r']
    dof = max(u.size - p, 1)
    sigma2 = 2 * best['cost'] / dof
    with np.errstate(all='ignore'):
        try:
            cov = sigma2 * np.linalg.inv(best['J'].T @ best['J'])
            std = np.sqrt(np.clip(np.diag(cov), 0, None))
        except np.linalg.LinAlgError:
            std = np.full(p, np.inf)
    denom = np.linalg.norm(y - y.mean())
    fit = 100 * (1 - np.linalg.norm(r) / denom) if denom > 0 else -np.inf
    success = bool(np.all(np.isfinite(theta)))
    ill = ~np.isfinite(std) | (std > 0.5 * np.maximum(np.abs(theta), 1e-3))
    message = best['message']
    if np.any(ill):
        names = [n for n, bad in zip(model.theta_labels, ill) if bad]
        message += (f"; parameters poorly determined by these data "
                    f"(standard error > 50%): {names}")
        warnings.warn(f"refine: {names} are poorly determined by the data "
                      f"(excitation too small or orders too high?)",
                      RuntimeWarning, stacklevel=2)
    return IdentificationResult(
        model=SandwichSystem.from_theta(theta, **orders, dt=model.dt),
        theta=theta.copy(), history=best['history'], errors=r,
        counts={'iterations': best['nit'], 'starts': n_starts},
        success=success, message=message, method='refine',
        options=dict(max_iter=max_iter, tol=tol, n_starts=n_starts,
                     spread=spread, m_min=m_min),
        orders=dict(orders), theta_labels=model.theta_labels,
        theta0=theta0, nit=best['nit'], elapsed=time.perf_counter() - start,
        std=std, fit=fit, cost=best['cost'])
