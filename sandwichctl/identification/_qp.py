"""The one wrapper around piqp (private module).

Two problems are solved with piqp:

* the dual of the bundle direction problem (3.4) over the unit simplex,
  ``min 0.5 lam' P lam + c' lam  s.t.  sum(lam) = 1, lam >= 0``, in
  `simplex_solve` (scaled and projected by the bundle recursion's
  compiled `_recursive.direction_weights`);
* box-constrained least-squares steps ``min 0.5 d' P d + c' d  s.t.
  lo <= d <= hi`` in `box_qp` (used by the batch refinement).

piqp >= 0.6 takes ``setup(P, c, A, b, G, h_l, h_u, x_l, x_u)`` and
``update(P=..., c=..., ...)``; we always call them with keywords and check
the status, because positional calls written for older versions silently
mean something else.

The simplex problems of one size n share A = ones(1, n), b = 1 and
x_l = 0, so `simplex_solve` keeps one set-up solver per n (per
thread) and only updates P and c between calls. piqp recomputes its
preconditioner on every update (``preconditioner_reuse_on_update`` off)
and starts each solve afresh, so an updated solver returns bit for bit
what a new one set up with the same data returns; if an update raises or
does not end in PIQP_SOLVED, the problem is set up again in a new solver.
"""

import threading

import numpy as np
import piqp

__all__ = []

#: Keep and update one simplex solver per size (False: a new setup at
#: every call, the reference the tests compare the reuse against).
_REUSE = True

_local = threading.local()


class QPError(RuntimeError):
    """piqp did not solve a quadratic program."""


def _new_solver():
    solver = piqp.DenseSolver()
    solver.settings.verbose = False
    solver.settings.preconditioner_reuse_on_update = False
    return solver


def _accept(solver, status, accept_max_iter):
    x = np.array(solver.result.x, dtype=float)
    if status == piqp.PIQP_SOLVED or (
            accept_max_iter and status == piqp.PIQP_MAX_ITER_REACHED
            and np.all(np.isfinite(x))):
        return x
    raise QPError(f"piqp returned status {status}")


def _solve(P, c, *, A=None, b=None, x_l=None, x_u=None,
           accept_max_iter=False):
    solver = _new_solver()
    solver.setup(P=P, c=c, A=A, b=b, G=None, h_l=None, h_u=None,
                 x_l=x_l, x_u=x_u)
    return _accept(solver, solver.solve(), accept_max_iter)


def simplex_solve(P, c):
    """piqp's minimiser of 0.5 x' P x + c' x over the unit simplex.

    The bare solve (no scaling, no projection: `direction_weights` does
    those), with this thread's solver for size n = c.size updated to
    (P, c). Returns x as
    piqp gives it; raises `QPError` unless piqp solved the problem or
    stopped at its iteration limit with a finite iterate.
    """
    n = c.size
    solvers = getattr(_local, 'simplex', None)
    if solvers is None:
        solvers = _local.simplex = {}
    solver = solvers.get(n) if _REUSE else None
    if solver is not None:
        try:
            solver.update(P=P, c=c)
            status = solver.solve()
        except (ValueError, TypeError, RuntimeError):
            status = None
        if status == piqp.PIQP_SOLVED:
            return np.array(solver.result.x, dtype=float)
    solver = _new_solver()
    solver.setup(P=P, c=c, A=np.ones((1, n)), b=np.ones(1), G=None,
                 h_l=None, h_u=None, x_l=np.zeros(n), x_u=None)
    status = solver.solve()
    if _REUSE:
        solvers[n] = solver
    return _accept(solver, status, accept_max_iter=True)


def box_qp(P, c, lo, hi):
    """Minimise 0.5 d' P d + c' d subject to lo <= d <= hi."""
    return _solve(P, c, x_l=lo, x_u=hi)
