"""Levenberg-Marquardt on the output-error cost of a `Parametrisation`
(private).

`lm` takes steps of the damped Gauss-Newton model, solved as box QPs
(m1, m2 >= m_min, D1, D2 >= 0; piqp when a bound binds), and accepts a
step only if it lowers the cost and keeps the free denominators stable,
which copes with the kinks of the cost (see `refine`). It returns a
`scipy.optimize.OptimizeResult`.
"""

import numpy as np
from scipy.optimize import OptimizeResult

from ._qp import box_qp, QPError

__all__ = []

#: A run stopped at max_iter counts as converged when its last decrease
#: and the Gauss-Newton prediction of what is left are both below this
#: share of the output's energy (the fit would change in its sixth digit).
CONVERGED = 1e-6


def _step(A, g, lo, hi):
    """Minimise 0.5 d'A d - g'd over lo <= d <= hi (None if it fails).

    The unconstrained minimiser is tried first (the bounds rarely bind);
    piqp solves the box QP otherwise.
    """
    try:
        d = np.linalg.solve(A, g)
        if np.all(np.isfinite(d)) and np.all(d >= lo) and np.all(d <= hi):
            return d
    except np.linalg.LinAlgError:
        pass
    try:
        return box_qp(A, -g, lo, hi)
    except QPError:
        return None


def lm(st, phi, u, y, max_iter=100, tol=1e-10, *, m_min=1e-9, sp=False,
       fixed=None):
    """Levenberg-Marquardt on the output-error cost, from an admissible phi.

    Every accepted step lowers the cost and keeps the structure stable, so
    the final cost is at most the starting cost (of the start with L1's
    zeros reflected inside, for a minimum-phase L1:
    `Parametrisation.minimum_phase_start`). With ``sp`` the
    series-parallel prediction error is minimised instead (a smoother
    cost, biased under noise: a way to a start). ``fixed`` (a boolean
    mask) holds some parameters at their values.

    Returns
    -------
    scipy.optimize.OptimizeResult
        ``phi``, ``cost``, ``J``, ``r``, ``nit``, ``converged`` and
        ``message``.
    """
    free = slice(None) if fixed is None else ~np.asarray(fixed)
    phi = st.minimum_phase_start(phi)
    r, J, _ = st.jacobian(phi, u, y, sp)
    with np.errstate(over='ignore'):        # a start that overflows: inf
        cost = 0.5 * float(r @ r)
    if not (np.isfinite(cost) and np.all(np.isfinite(J))):
        return OptimizeResult(
            phi=phi, cost=np.inf if not np.isfinite(cost) else cost, J=J,
            r=r, nit=0, converged=False,
            message="the start does not give a finite output and Jacobian")
    mu = 1e-3
    message, converged = f"stopped at max_iter = {max_iter}", False
    last_decrease = np.inf
    it = 0
    for it in range(1, max_iter + 1):
        trial, cost_t, mu = _damped_step(st, phi, J[:, free], r, mu,
                                         cost=cost, free=free, m_min=m_min,
                                         data=(u, y, sp))
        if trial is None:
            message = ("converged: no step decreases the cost (a minimum, "
                       "possibly at a kink)")
            converged = True
            break
        last_decrease = (cost - cost_t) / max(cost, 1e-300)
        step = np.linalg.norm(trial - phi)
        phi = trial
        r, J, _ = st.jacobian(phi, u, y, sp)
        cost = 0.5 * float(r @ r)
        mu = max(mu / 3, 1e-9)
        if not np.all(np.isfinite(J)):
            message = "stopped: the Jacobian is not finite"
            break
        if last_decrease < tol or step < tol * (1 + np.linalg.norm(phi)):
            message = (f"converged: relative decrease {last_decrease:.1e} "
                       f"or step {step:.1e} below tol")
            converged = True
            break
    if not converged and np.isfinite(cost) and np.all(np.isfinite(J)):
        converged, text = _left_over(J[:, free], r, cost, y, last_decrease)
        message += text
    return OptimizeResult(phi=phi, cost=cost, J=J, r=r, nit=it,
                          converged=converged, message=message)


def _damped_step(st, phi, Jf, r, mu, *, cost, free, m_min, data):
    """The first admissible step that lowers the cost, the damping mu
    growing tenfold from `mu` until it does (below 1e12, and while the
    damped matrix is finite: a Jacobian near an unstable candidate can
    have columns of 1e150): (trial, its cost, mu), or (None, None, mu) if
    none does."""
    u, y, sp = data
    A = Jf.T @ Jf
    g = Jf.T @ r
    diag = np.diag(A).copy()
    scale = np.maximum(diag, 1e-12 * max(float(np.max(diag, initial=0)),
                                         1e-300))
    lo, hi = st.bounds(phi, m_min)
    lo, hi = lo[free], hi[free]
    while mu < 1e12:
        with np.errstate(over='ignore'):
            damped = A + mu * np.diag(scale)
        if not np.all(np.isfinite(damped)):
            break                   # a larger mu overflows too
        d = _step(damped, g, lo, hi)
        if d is None:
            mu *= 10
            continue
        full = np.zeros(phi.size)
        full[free] = d
        trial = st.clip(phi + full, m_min)
        if not st.stable(trial):
            mu *= 10
            continue
        cost_t = st.cost(trial, u, y, sp)
        if cost_t < cost:
            return trial, cost_t, mu
        mu *= 10
    return None, None, mu


def _left_over(Jf, r, cost, y, last_decrease):
    """A run stopped at max_iter: (converged, text for the message). It
    converged if what is left is negligible, by the last step and by the
    Gauss-Newton model of the cost, relative to the output's energy (a
    change of the fit in the sixth digit is not worth more iterations)."""
    g = Jf.T @ r
    A = Jf.T @ Jf
    with np.errstate(all='ignore'):
        d = np.linalg.lstsq(A, g, rcond=1e-12)[0]
    predicted = 0.5 * float(g @ d) / max(cost, 1e-300)
    yc = np.concatenate(y)
    energy = 0.5 * float(np.sum((yc - np.mean(yc)) ** 2))
    share = cost / max(energy, 1e-300)
    converged = max(last_decrease, predicted) * share < CONVERGED
    return converged, (f" (last relative decrease {last_decrease:.1e}, "
                       f"predicted {predicted:.1e}"
                       + (": converged)" if converged else ")"))
