r"""Continuation through a smoothed backlash (private).

Where the slope lines of the backlash cross (m1 != m2 and x beyond
`Backlash.crossing`), eq. (2.2) follows the rising line while x rises and
the falling line while it falls, and the two differ there by a finite
amount. A small change of the parameters that flips the sign of a tiny
step x(k) - x(k-1) (near a turning point of x, or in the decaying tail of
a step response) moves v(k), and through the memory zone the samples after
it, by a finite amount: the output-error cost jumps. On random plants
whose x spends more than a tenth of the time beyond the crossing the cost
is riddled with such jumps, and Levenberg-Marquardt stops on a piece of it
that is a few percent above a neighbouring one.

`smooth_refine` follows a path of smoothed costs (`_predictor.smooth_output`: the
rising and falling lines blended over |x(k) - x(k-1)| < eps), continuous
in the parameters, with eps decreasing from a third of the spread of
x(k) - x(k-1) to a thousandth, then refines the exact cost from where the
path ends. The smoothed problems are solved by `scipy.optimize.
least_squares` (trust-region reflective, bounds m >= 0, D >= 0, forward
difference Jacobian): they are only a way to a start, the exact
refinement (`_lm.lm`) decides.
"""

import contextlib
import inspect
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy.optimize import least_squares

from ._lm import lm
from ._predictor import oe_signals

__all__ = []

#: Smoothing widths, relative to the spread (standard deviation) of the
#: model's x(k) - x(k-1), from the first smoothed problem to the last.
EPS_PATH = (0.3, 0.1, 0.03, 0.01, 0.003, 0.001)
#: Function evaluations (not counting the Jacobian's) per smoothed problem.
SMOOTH_NFEV = 20
_TAKES_WORKERS = 'workers' in inspect.signature(least_squares).parameters


def _step_spread(st, phi, u):
    """Spread of x(k) - x(k-1) over the experiments (1 if degenerate)."""
    theta = st.theta(phi)
    steps = [np.diff(oe_signals(theta, st.o, uu, st.init(phi, e))[1])
             for e, uu in enumerate(u)]
    with np.errstate(all='ignore'):
        s = float(np.std(np.concatenate(steps)))
    return s if np.isfinite(s) and s > 0 else 1.0


@contextlib.contextmanager
def _pool(workers):
    """least_squares' keywords for `workers` threads: a thread pool's map
    as ``workers`` where scipy takes it, else none."""
    if workers <= 1 or not _TAKES_WORKERS:
        yield {}
        return
    with ThreadPoolExecutor(max_workers=workers) as pool:
        yield {'workers': pool.map}


def smooth_refine(st, phi, u, y, max_iter=200, tol=1e-10, *, workers=1,
                  path=None):
    """The continuation from phi, then `lm` on the exact cost.

    Parameters
    ----------
    st : Parametrisation
    phi : ndarray
        An admissible start (model parameters, then output offsets and
        initial conditions as `st` lays them out; the initial conditions
        are held).
    u, y : list of ndarray
        The scaled experiments.
    workers : int
        Threads for the finite differences of the smoothed problems'
        Jacobians (the same evaluations, side by side; with scipy >= 1.16,
        whose ``least_squares`` takes ``workers``).
    path : tuple of list of ndarray, optional
        (u, y) of the smoothed problems, when they run on fewer samples
        than the exact refinement (a long record's leading part, each
        experiment from its start); by default `u` and `y`.

    Returns
    -------
    dict or None
        The `lm` output from where the path ends, or None when the path
        leaves the admissible set (a free denominator not strictly stable)
        or gives no finite values.
    """
    exact = (u, y)
    if path is not None:
        u, y = path
    free = st.q + st.n_off
    lo = np.full(free, -np.inf)
    lo[st.im:st.im + 4] = 0.0
    spread = _step_spread(st, phi, u)
    fallback = np.full(sum(part.size for part in u), 1e3)

    def residuals(p, eps):
        trial = phi.copy()
        trial[:free] = p
        if not st.poles_stable(trial):
            return fallback
        r = st.residuals(trial, u, y, eps=eps)
        return r if np.all(np.isfinite(r)) else fallback

    p = np.maximum(phi[:free], lo + 1e-12)
    with _pool(workers) as kw:
        for rel in EPS_PATH:
            try:
                fit = least_squares(residuals, p, bounds=(lo, np.inf),
                                    args=(rel * spread,),
                                    max_nfev=SMOOTH_NFEV, x_scale='jac',
                                    **kw)
            except (ValueError, np.linalg.LinAlgError):
                return None
            p = fit.x
    start = phi.copy()
    start[:free] = p
    start = st.clip(start, 1e-9)
    if not st.stable(start):
        return None
    return lm(st, start, *exact, max_iter, tol)
