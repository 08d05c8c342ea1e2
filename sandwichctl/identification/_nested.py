r"""Sandwich starts nested in a linear output-error fit (private).

With D1 = D2 = 0 and m1 = m2 = m the sandwich *is* the linear model
``L2 m L1`` of the total orders. So a linear fit B/F, factored into poles
and zeros, gives one exact sandwich for every assignment of its poles and
zeros to L1 and L2 (complex pairs kept together), each with the linear
fit's cost. `splits` enumerates these assignments as reduced parameter
vectors phi of a `Structure` (see `_oe`), with the backlash closed; the
caller opens the backlash from there.
"""

import itertools

import numpy as np

from ._oe import integrator_poly
from ._predictor import oe_signals
from .linear import _fit_oe

__all__ = []

#: Most assignments enumerated per block; beyond this the assignments
#: closest to the slowest-poles-first heuristic are kept.
MAX_SPLITS = 40


def _units(roots, tol=1e-8):
    """Group roots into real singles and conjugate pairs: a list of arrays."""
    roots = np.asarray(roots, dtype=complex)
    units, used = [], np.zeros(roots.size, bool)
    for i, r in enumerate(roots):
        if used[i]:
            continue
        used[i] = True
        if abs(r.imag) <= tol * max(1.0, abs(r)):
            units.append(np.array([r.real + 0j]))
            continue
        rest = [j for j in range(roots.size)
                if not used[j] and abs(roots[j] - np.conj(r))
                <= 1e-6 * max(1.0, abs(r))]
        if rest:
            used[rest[0]] = True
            units.append(np.array([r, np.conj(r)]))
        else:                                   # unpaired: treat as real
            units.append(np.array([r.real + 0j]))
    return units


def _as_reals(unit):
    """Two real roots standing in for a conjugate pair (same centre)."""
    r = unit[0]
    return [np.array([r.real + abs(r.imag) + 0j]),
            np.array([r.real - abs(r.imag) + 0j])]


def _choices(roots, k):
    """All ways to take k of the roots for one block (pairs together).

    Returns a list of (chosen, rest) root arrays. When no selection of
    whole units has size k (e.g. one pole wanted, a complex pair
    offered), a pair is replaced by two real roots at its real part plus
    and minus its imaginary part, so that every structure gets starts.
    """
    units = _units(roots)
    n = sum(u.size for u in units)
    if k < 0 or k > n:
        return []
    for _ in range(len(units) + 1):
        out = []
        for r in range(len(units) + 1):
            for idx in itertools.combinations(range(len(units)), r):
                if sum(units[i].size for i in idx) != k:
                    continue
                chosen = np.concatenate([units[i] for i in idx]) if idx \
                    else np.zeros(0, complex)
                rest = [units[i] for i in range(len(units)) if i not in idx]
                rest = np.concatenate(rest) if rest else np.zeros(0, complex)
                out.append((chosen, rest))
        if out:
            return out
        pair = next(i for i, u in enumerate(units) if u.size == 2)
        units = units[:pair] + _as_reals(units[pair]) + units[pair + 1:]
    return []


def _poly(roots):
    """Monic real coefficients 1, c1, ..., ascending powers of q^-1."""
    return np.real(np.poly(roots)) if len(roots) else np.ones(1)


def splits(st, B, F):
    """Exact sandwich starts of a linear fit, one per pole/zero assignment.

    Parameters
    ----------
    st : Structure
        The sandwich structure (orders, delays, integrators).
    B : ndarray
        Linear numerator b1..b_{nb+nd+1} (ascending powers of q^-1), on
        the same scaled data the sandwich is fitted to, after the sign of
        B[0] was taken out of the output (so B[0] > 0).
    F : ndarray
        Monic linear denominator with the integrators of `st` included.

    Returns
    -------
    list of ndarray
        Reduced parameter vectors phi with m1 = m2 = B[0] and D1 = D2 = 0;
        the first ones reproduce the linear fit's output exactly, unless
        a zero lies beyond the structure's ``zero_radius`` (see
        `_zero_variants`, which also adds starts with far zeros
        reflected). Within a variant, slowest-first (the assignment giving
        L1 the slowest poles comes first).
    """
    na, nb, nc, nd = st.o[:4]
    gain = float(B[0])
    zeros = np.roots(B) if B.size > 1 else np.zeros(0)
    out = []
    for zs, g in _zero_variants(zeros, gain, st.zero_radius):
        out += _assignments(st, zs, g, F)
    return out


def _zero_variants(zeros, gain, radius):
    """The zeros of the linear fit and, if some are far outside the unit
    circle, a variant with those reflected to 1 / conj(z) (an all-pass
    factor apart: the same magnitude response; a linear fit of sandwich
    data often puts a zero near infinity where the backlash delays the
    response). Zeros beyond 0.9 `radius` are pulled in to it. Each with
    the gain that keeps the high-frequency (far zeros) or low-frequency
    (reflected zeros) level."""
    variants = []
    far = np.abs(zeros) > 0.9 * radius
    if np.any(far):
        pulled = zeros[far] * 0.9 * radius / np.abs(zeros[far])
        g = abs(gain * float(np.real(np.prod(zeros[far] / pulled))))
        zs = zeros.copy()
        zs[far] = pulled
        variants.append((zs, g))
    else:
        variants.append((zeros, gain))
    outside = np.abs(zeros) > 3.0
    factor = float(np.real(np.prod(-zeros[outside])))
    if np.any(outside) and factor > 0:      # the DC gain keeps its sign
        zs = zeros.copy()
        zs[outside] = 1 / np.conj(zeros[outside])
        variants.append((zs, gain * factor))
    return variants


def _assignments(st, zeros, gain, F):
    """Starts for every assignment of poles and `zeros` to L1 and L2."""
    na, nb, nc, nd = st.o[:4]
    # the free poles: F without its integrator factors
    free = np.polydiv(F, integrator_poly(st.i1 + st.i2))[0]
    poles = np.roots(free) if free.size > 1 else np.zeros(0)
    pole_sets = _choices(poles, st.na_free)
    zero_sets = _choices(zeros, nb)
    # slowest poles in L1 first: a drive's L1 (motor loop) is usually the
    # slow block; the order only matters when the list is cut
    pole_sets.sort(key=lambda s: -np.sum(np.abs(s[0])))
    pole_sets = pole_sets[:MAX_SPLITS]
    zero_sets = zero_sets[:MAX_SPLITS]
    out = []
    for (p1, p2), (z1, z2) in itertools.product(pole_sets, zero_sets):
        a, c = _poly(p1)[1:], _poly(p2)[1:]
        b, d = _poly(z1)[1:], _poly(z2)[1:]
        phi = np.concatenate([c, a, [gain, gain, 0.0, 0.0], b, d])
        if phi.size == st.q and np.all(np.isfinite(phi)):
            out.append(phi)
    return out


def refit_l2(st, phi, u, y, max_iter=100, tol=1e-10):
    """A start with L2 re-fitted to the model's own intermediate signal.

    With L1 and the backlash held, y is a linear output-error model of
    the backlash output v; the linear OE fit (ARX, Steiglitz-McBride,
    Levenberg-Marquardt) finds its optimum far more reliably than the
    joint descent, which can stall with L2's zeros or poles in the wrong
    place. Its gain moves into the backlash slopes (d0 = 1 stays).

    Parameters
    ----------
    st : Structure
    phi : ndarray
        The current reduced vector (output offsets and initial conditions
        included, as `st` lays them out).
    u, y : list of ndarray
        The scaled experiments.

    The linear fit starts from rest; estimated initial conditions (if the
    structure has them) are kept, their past v scaled with the slopes.

    Returns
    -------
    ndarray or None
        The new phi, or None when the fit gives no admissible start (v
        constant, a leading coefficient of the wrong sign, a denominator
        not strictly stable or a zero beyond the structure's zero radius,
        a value not finite).
    """
    theta = st.theta(phi)
    vs = [oe_signals(theta, st.o, uu, st.init(phi, e))[2]
          for e, uu in enumerate(u)]
    with np.errstate(all='ignore'):
        sv = float(np.std(np.concatenate(vs)))
    if not (np.isfinite(sv) and sv > 0):
        return None
    na, nb, nc, nd = st.o[:4]
    fit = _fit_oe([v / sv for v in vs], list(y), nd + 1, nc, st.o[5], st.i2,
                  max_iter, tol, offsets=bool(st.n_off))
    B, F = fit['B'], fit['F']
    if not (np.all(np.isfinite(B)) and np.all(np.isfinite(F))
            and B[0] > 1e-9 * np.max(np.abs(B))):
        return None
    new = theta.copy()
    new[:nc] = F[1:]
    im = nc + na
    new[im:im + 2] *= B[0] / sv
    new[im + 4 + nb:] = B[1:] / B[0]
    out = st.phi(new)
    out[st.q:] = phi[st.q:]
    if st.n_off:
        out[st.q:st.q + st.n_off] = fit['offsets'][:st.n_off]
    kx, kv = st.init_sizes[:2]
    for e in range(st.n_inits):           # past v scales with the slopes
        at = st.q + st.n_off + e * st.n_init + kx
        out[at:at + kv] *= B[0] / sv
    return out if st.stable(out) else None
