r"""Root relocation moves between local optima (private).

The output-error cost of a sandwich has local minima that differ from the
global one in a single root of L1: a real pole of L1 sitting on a copy of
one of L2's poles, a zero of L1 on the wrong side of the origin. Small
perturbations of all parameters (the hops of `identify`) fall back into
the same valley, and Levenberg-Marquardt cannot move one root across the
ridge alone, because L2 and the backlash have adapted to the wrong root.

A relocation takes one real root or one conjugate pair of L1's free
denominator or of its numerator and puts it somewhere else on a coarse
grid over the disk (and, for zeros, beyond it), keeps the spread of the
intermediate signal x = L1[u] (the backlash slopes and widths are scaled
so that v = B(x) keeps its size), and lets the caller re-fit L2 and run a
few iterations. The grid is generic: the same few points for every plant,
spread over the stable region a discrete-time root can occupy.
"""

import numpy as np
from scipy.signal import lfilter

from ._nested import _units

__all__ = []

#: Real roots a real pole of L1 is moved to.
POLES_REAL = (-0.8, -0.5, -0.2, 0.1, 0.4, 0.7, 0.9)
#: Conjugate pairs a complex pole pair of L1 is moved to: radius, angle.
POLES_PAIR = tuple((r, w) for r in (0.5, 0.85)
                   for w in (np.pi / 6, np.pi / 3, np.pi / 2,
                             2 * np.pi / 3))
#: Real roots a real zero of L1 is moved to (zeros may lie outside).
ZEROS_REAL = (-2.0, -0.9, -0.5, 0.0, 0.5, 0.9, 2.0)
#: Conjugate pairs a complex zero pair of L1 is moved to.
ZEROS_PAIR = tuple((r, w) for r in (0.5, 1.5)
                   for w in (np.pi / 4, np.pi / 2, 3 * np.pi / 4))


def l1_std(st, phi, u):
    """Standard deviation of x = L1[u] for phi (scaled data, one array or
    a list of experiments); 1 when it is not finite and positive."""
    if isinstance(u, list):
        u = np.concatenate(u)
    theta = st.theta(phi)
    na, nb, nc, nd, q1, q2 = st.o
    a = theta[nc:nc + na]
    b = theta[nc + na + 4:nc + na + 4 + nb]
    with np.errstate(all='ignore'):
        x = lfilter(np.r_[np.zeros(q1), 1.0, b], np.r_[1.0, a], u)
        s = float(np.std(x))
    return s if np.isfinite(s) and s > 0 else 1.0


def _poly(roots):
    return np.real(np.poly(roots))[1:] if len(roots) else np.zeros(0)


def _targets(unit, reals, pairs):
    if unit.size == 1:
        return [np.array([r + 0j]) for r in reals]
    return [np.array([r * np.exp(1j * w), r * np.exp(-1j * w)])
            for r, w in pairs]


def _moved(st, phi, u, lo, hi, reals, pairs):
    """Copies of phi with one root unit of the monic polynomial in
    phi[lo:hi] moved to each grid target (x's spread kept)."""
    coeffs = phi[lo:hi]
    if coeffs.size == 0:
        return []
    with np.errstate(all='ignore'):
        roots = np.roots(np.r_[1.0, coeffs])
    if not np.all(np.isfinite(roots)):
        return []
    units = _units(roots)
    s0 = l1_std(st, phi, u)
    out = []
    for i, unit in enumerate(units):
        rest = [units[j] for j in range(len(units)) if j != i]
        for new in _targets(unit, reals, pairs):
            cand = phi.copy()
            cand[lo:hi] = _poly(np.concatenate(rest + [new]))
            ratio = l1_std(st, cand, u) / s0
            cand[st.im:st.im + 2] /= ratio
            cand[st.im + 2:st.im + 4] *= ratio
            if np.all(np.isfinite(cand)):
                out.append(cand)
    return out


def relocations(st, phi, u):
    """Candidate starts: phi with one real root or conjugate pair of L1's
    free poles or of its zeros moved to a grid point.

    Parameters
    ----------
    st : Structure
    phi : ndarray
        The current reduced vector (offsets and initial conditions are
        carried along unchanged).
    u : list of ndarray
        The scaled inputs.

    Returns
    -------
    list of ndarray
        The moved vectors (not yet checked for admissibility).
    """
    ib = st.im + 4
    return (_moved(st, phi, u, st.nc_free, st.im, POLES_REAL, POLES_PAIR)
            + _moved(st, phi, u, ib, ib + st.o[1], ZEROS_REAL, ZEROS_PAIR))
