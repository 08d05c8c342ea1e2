"""The one wrapper around piqp (private module).

Two problems are solved with piqp:

* the dual of the bundle direction problem (3.4) over the unit simplex,
  ``min 0.5 lam' P lam + c' lam  s.t.  sum(lam) = 1, lam >= 0``, in
  `simplex_qp`;
* box-constrained least-squares steps ``min 0.5 d' P d + c' d  s.t.
  lo <= d <= hi`` in `box_qp` (used by the batch refinement).

piqp >= 0.6 takes ``setup(P, c, A, b, G, h_l, h_u, x_l, x_u)``; we always
call it with keywords and check the status, because positional calls
written for older versions silently mean something else.
"""

import numpy as np
import piqp

__all__ = []


class QPError(RuntimeError):
    """piqp did not solve a quadratic program."""


def _solve(P, c, A=None, b=None, x_l=None, x_u=None, accept_max_iter=False):
    solver = piqp.DenseSolver()
    solver.settings.verbose = False
    solver.setup(P=P, c=c, A=A, b=b, G=None, h_l=None, h_u=None,
                 x_l=x_l, x_u=x_u)
    status = solver.solve()
    x = np.asarray(solver.result.x, dtype=float)
    if status == piqp.PIQP_SOLVED or (
            accept_max_iter and status == piqp.PIQP_MAX_ITER_REACHED
            and np.all(np.isfinite(x))):
        return x
    raise QPError(f"piqp returned status {status}")


def simplex_qp(P, c):
    """Minimise 0.5 lam' P lam + c' lam over the unit simplex.

    P (n x n, positive semidefinite) and c are scaled together by the
    largest diagonal entry of P before the solve, which leaves the
    minimiser unchanged and keeps piqp's absolute tolerances meaningful
    when the subgradients are tiny. The result is clipped to >= 0 and
    renormalised to sum to one (it is feasible to piqp's tolerance). If
    piqp stops at its iteration limit (it can on nearly collinear bundles)
    its last iterate, projected the same way, is used: any point of the
    simplex gives a valid convex combination of subgradients.
    """
    n = c.size
    if n == 1:
        return np.ones(1)
    scale = max(float(np.max(np.diag(P))), float(np.max(np.abs(c))), 1e-300)
    lam = _solve(P / scale, c / scale, A=np.ones((1, n)), b=np.ones(1),
                 x_l=np.zeros(n), accept_max_iter=True)
    lam = np.clip(lam, 0.0, None)
    if not lam.sum() > 0:
        raise QPError("piqp returned no point of the simplex")
    return lam / lam.sum()


def box_qp(P, c, lo, hi):
    """Minimise 0.5 d' P d + c' d subject to lo <= d <= hi."""
    return _solve(P, c, x_l=lo, x_u=hi)
