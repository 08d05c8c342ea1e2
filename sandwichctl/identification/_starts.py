r"""Every start of the output-error search (private).

A start is a reduced parameter vector phi of a `Parametrisation`; each
kind is one function here, in the order of the search's steps
(docs/algorithm.md, ``method="oe"``):

- step 4, `splits` and `opened`: sandwiches nested in the linear fit.
  With D1 = D2 = 0 and m1 = m2 = m the sandwich *is* the linear model
  ``L2 m L1`` of the total orders, so a linear fit B/F, factored into
  poles and zeros, gives one exact sandwich for every assignment of its
  poles and zeros to L1 and L2 (complex pairs kept together), each with
  the linear fit's cost; `opened` opens their backlash;
- step 5, `random_start`, `recursive_start` and `reintegrated`: other
  basins (the last maps the model of the search on the output filtered
  by (1 - q^-1) / (1 - rho q^-1), an integrator of L2 then a pole at rho,
  back to the integrator);
- step 9, `relocations`: one root of L1 moved across the disk. The cost
  has local minima that differ from the global one in a single root of
  L1 (a real pole sitting on a copy of one of L2's poles, a zero on the
  wrong side of the origin); small perturbations fall back into the same
  valley, so the root is put somewhere else on a coarse grid over the
  disk (and, for zeros, beyond it), with the spread of x = L1[u] kept.
  Two real roots where the plant has a complex pair, and a pole of L1
  all but cancelled by a zero, are minima of the same kind that no
  single root's move leaves: two real roots are moved together onto the
  grid's pairs, and a cancelling pole and zero together onto each point;
- step 10 and `refine`'s multi-start, `perturb`: the one random
  perturbation;
- `admissible`: any start moved into the domain.
"""

import itertools
import warnings

import numpy as np
from scipy.signal import lfilter

from ._problem import integrator_poly
from .recursive import RecursiveIdentifier

__all__ = []

#: Step 4: most assignments enumerated per block; beyond this the assignments
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


def _as_reals(unit, how='spread'):
    """Two real roots standing in for a conjugate pair: its real part
    plus and minus its imaginary part (``how='spread'``, same centre) or
    a double root at its modulus (``'modulus'``, same magnitude, the
    sign of its real part)."""
    r = unit[0]
    if how == 'modulus':
        return [np.array([np.copysign(abs(r), r.real) + 0j])] * 2
    return [np.array([r.real + abs(r.imag) + 0j]),
            np.array([r.real - abs(r.imag) + 0j])]


def holds(roots, k):
    """Whether k of the roots can go to one block and the rest to the
    other with every complex pair kept whole."""
    sizes = [u.size for u in _units(roots)]
    sums = {0}
    for size in sizes:
        sums |= {s + size for s in sums}
    return k in sums


def _choices(roots, k, how='spread'):
    """All ways to take k of the roots for one block (pairs together).

    Returns a list of (chosen, rest) root arrays. When no selection of
    whole units has size k (e.g. one pole wanted, a complex pair
    offered), a pair is replaced by two real roots (`_as_reals`, `how`),
    so that every structure gets starts.
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
        units = units[:pair] + _as_reals(units[pair], how) + \
            units[pair + 1:]
    return []


def _poly(roots):
    """Monic real coefficients 1, c1, ..., ascending powers of q^-1."""
    return np.real(np.poly(roots)) if len(roots) else np.ones(1)


def splits(st, B, F):
    """Exact sandwich starts of a linear fit, one per pole/zero assignment.

    Parameters
    ----------
    st : Parametrisation
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


def _free_poles(st, F):
    """The roots of F without its integrator factors."""
    free = np.polydiv(F, integrator_poly(st.i1 + st.i2))[0]
    return np.roots(free) if free.size > 1 else np.zeros(0)


def unsplit(st, B, F):
    """The roots of the linear fit B/F that the structure `st` cannot
    split into L1 and L2 with complex pairs whole: {'poles': roots,
    'zeros': roots}, a kind listed only when it cannot be split (empty:
    the structure holds the linear fit)."""
    zeros = np.roots(B) if B.size > 1 else np.zeros(0)
    out = {}
    for kind, roots, k in (('poles', _free_poles(st, F), st.na_free),
                           ('zeros', zeros, st.o[1])):
        if not holds(roots, k):
            out[kind] = roots
    return out


def held_starts(st, B, F):
    """Starts of the best linear model the structure holds, when it
    cannot hold the linear fit B/F (`unsplit`): the first assignment
    with each pair that does not fit broken into two real roots, either
    spread about its real part or doubled at its modulus
    (`_as_reals`); reduced vectors as `splits` gives."""
    zeros = np.roots(B) if B.size > 1 else np.zeros(0)
    out = []
    for how in ('spread', 'modulus'):
        out += _assignments(st, zeros, float(B[0]), F, how)[:1]
    return out


def _assignments(st, zeros, gain, F, how='spread'):
    """Starts for every assignment of poles and `zeros` to L1 and L2."""
    na, nb, nc, nd = st.o[:4]
    pole_sets = _choices(_free_poles(st, F), st.na_free, how)
    zero_sets = _choices(zeros, nb, how)
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


def _coefficients(roots):
    """`_poly` without its leading 1 (no roots: no coefficients)."""
    return _poly(roots)[1:]


def _targets(unit, reals, pairs):
    if unit.size == 1:
        return [np.array([r + 0j]) for r in reals]
    return [np.array([r * np.exp(1j * w), r * np.exp(-1j * w)])
            for r, w in pairs]


def _root_units(phi, span):
    """The root units (`_units`) of the monic polynomial in phi[lo:hi],
    span = (lo, hi); None if it has none or they are not finite."""
    coeffs = phi[span[0]:span[1]]
    if coeffs.size == 0:
        return None
    with np.errstate(all='ignore'):
        roots = np.roots(np.r_[1.0, coeffs])
    return _units(roots) if np.all(np.isfinite(roots)) else None


def _rescaled(st, cand, u, s0):
    """cand with the slopes and widths scaled so that x = L1[u] keeps the
    spread s0; None if it is not finite."""
    ratio = l1_std(st, cand, u) / s0
    cand[st.im:st.im + 2] /= ratio
    cand[st.im + 2:st.im + 4] *= ratio
    return cand if np.all(np.isfinite(cand)) else None


def _moved(st, phi, u, s0, span, grid):
    """Copies of phi with one root unit of the monic polynomial in
    phi[lo:hi], span = (lo, hi), moved to each target of the grid =
    (reals, pairs), and with every two real roots moved together to each
    pair of the grid (x's spread s0 kept)."""
    (lo, hi), (reals, pairs) = span, grid
    units = _root_units(phi, span)
    if units is None:
        return []
    single = [i for i, unit in enumerate(units) if unit.size == 1]
    moves = ([([i], _targets(unit, reals, pairs))
              for i, unit in enumerate(units)]
             + [(list(ij), _targets(np.zeros(2), reals, pairs))
                for ij in itertools.combinations(single, 2)])
    out = []
    for which, targets in moves:
        rest = [units[j] for j in range(len(units)) if j not in which]
        for new in targets:
            cand = phi.copy()
            cand[lo:hi] = _coefficients(np.concatenate(rest + [new]))
            cand = _rescaled(st, cand, u, s0)
            if cand is not None:
                out.append(cand)
    return out


#: a pole unit and a zero unit of L1 cancel when no root of one lies
#: further than CANCELLED (relative to the largest modulus, at least 1)
#: from its match in the other
CANCELLED = 0.05


def _cancelled(st, phi, u, s0, poles, zeros):
    """Copies of phi with each pole unit of L1 that a zero unit all but
    cancels (`CANCELLED`) moved, with that zero unit, to each target of
    the poles' grid: the same cancellation elsewhere, from where the pair
    can part (x's spread s0 kept). `poles` and `zeros` are their
    spans."""
    pu, zu = _root_units(phi, poles), _root_units(phi, zeros)
    if pu is None or zu is None:
        return []
    out = []
    for (i, p), (j, z) in itertools.product(enumerate(pu), enumerate(zu)):
        if p.size != z.size or np.max(np.abs(
                np.sort_complex(p) - np.sort_complex(z))) > CANCELLED * max(
                    1.0, np.max(np.abs(p))):
            continue
        p_rest = [pu[k] for k in range(len(pu)) if k != i]
        z_rest = [zu[k] for k in range(len(zu)) if k != j]
        for new in _targets(p, POLES_REAL, POLES_PAIR):
            cand = phi.copy()
            cand[poles[0]:poles[1]] = _coefficients(
                np.concatenate(p_rest + [new]))
            cand[zeros[0]:zeros[1]] = _coefficients(
                np.concatenate(z_rest + [new]))
            cand = _rescaled(st, cand, u, s0)
            if cand is not None:
                out.append(cand)
    return out


def relocations(st, phi, u):
    """Candidate starts: phi with one real root or conjugate pair of L1's
    free poles or of its zeros moved to a grid point, two real ones moved
    together to a conjugate pair of the grid, or a pole and the zero that
    all but cancels it moved together to a point of the poles' grid.

    Parameters
    ----------
    st : Parametrisation
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
    poles, zeros = (st.nc_free, st.im), (st.im + 4, st.im + 4 + st.o[1])
    s0 = l1_std(st, phi, u)
    return (_moved(st, phi, u, s0, poles, (POLES_REAL, POLES_PAIR))
            + _moved(st, phi, u, s0, zeros, (ZEROS_REAL, ZEROS_PAIR))
            + _cancelled(st, phi, u, s0, poles, zeros))


def opened(st, phi, u, widths):
    """Copies of a closed start phi with the backlash opened to each of
    `widths`, relative to the spread of x (`l1_std`)."""
    width = l1_std(st, phi, u)
    out = []
    for w in widths:
        wide = phi.copy()
        wide[st.im + 2:st.im + 4] = w * width
        out.append(wide)
    return out


def _random_roots(n, rng, radius=0.9):
    """n roots, real or in conjugate pairs, uniform in the disk."""
    roots = []
    while len(roots) < n:
        r = radius * np.sqrt(rng.random())
        if n - len(roots) >= 2 and rng.random() < 0.5:
            a = rng.uniform(0, np.pi)
            roots += [r * np.exp(1j * a), r * np.exp(-1j * a)]
        else:
            roots.append(r * rng.choice([-1.0, 1.0]) + 0j)
    return np.array(roots)


def random_start(st, u, rng):
    """A random admissible structure: poles and zeros in the disk, the
    slopes scaled to the spread of x, a random backlash width (output
    offsets and initial conditions zero)."""
    na, nb, nc, nd = st.o[:4]
    poly = [np.real(np.poly(_random_roots(n, rng)))[1:] if n else
            np.zeros(0) for n in (st.nc_free, st.na_free, nb, nd)]
    phi = np.concatenate([poly[0], poly[1], [1.0, 1.0, 0.0, 0.0], poly[2],
                          poly[3]])
    width = l1_std(st, phi, u)
    phi[st.im:st.im + 2] = 1.0 / width
    phi[st.im + 2:st.im + 4] = rng.uniform(0.05, 0.8) * width
    return st.extend(phi)


def recursive_start(prob, orders):
    """Starts ([(sign, phi)], empty if it fails) from the recursive
    prediction-error estimator run series-parallel over the scaled data of
    the problem `prob` (a different basin than the linear fit's)."""
    st = prob.st
    try:
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')
            longest = int(np.argmax([part.size for part in prob.u]))
            u, y = prob.u[longest], prob.y[longest]
            est = RecursiveIdentifier(*orders.values(), method='rpem',
                                      warmup=u.size)
            est.update_many(u, y)
        phi = admissible(st, st.phi(est.theta), 1e-9)
    except (ValueError, RuntimeError, np.linalg.LinAlgError):
        return []
    if not st.stable(phi):
        return []
    return [(prob.sign, phi)]


def reintegrated(st, st_f, phi_f, rho, gain):
    """The model phi_f of the filtered structure `st_f` (one integrator of
    L2 fewer, fitted to the output filtered by (1 - q^-1) / (1 - rho
    q^-1)) as a start of `st`: its real pole of L2 nearest `rho` put back
    at z = 1, the slopes times `gain` (the ratio of the two outputs'
    scales). None if that pole is complex or the start is not stable."""
    nc = st.o[2]
    theta = st_f.theta(phi_f)
    with np.errstate(all='ignore'):
        roots = np.roots(np.r_[1.0, theta[:nc]])
    near = int(np.argmin(np.abs(roots - rho)))
    if not abs(roots[near].imag) <= 1e-8 * max(1.0, abs(roots[near])):
        return None
    roots[near] = 1.0
    theta[:nc] = _coefficients(roots)
    theta[st.im_theta:st.im_theta + 2] *= gain
    phi = st.phi(theta)
    return phi if st.stable(phi) else None


def perturb(st, phi, rng, spread, m_min=1e-9, tries=20):
    """A random admissible start near phi, or None: the model parameters
    (not the offsets or initial conditions) moved by `spread` of their
    size (at least 0.05), the first of `tries` draws that is stable."""
    for _ in range(tries):
        trial = phi.copy()
        size = np.maximum(np.abs(trial[:st.q]), 0.05)
        trial[:st.q] += spread * size * rng.standard_normal(st.q)
        trial = st.clip(trial, m_min)
        if st.stable(trial):
            return trial
    return None


def admissible(st, phi, m_min):
    """Move a start into the domain: slopes >= m_min, D >= 0, and unstable
    free denominators pulled inside the unit circle (roots scaled by 0.9
    until stable)."""
    phi = phi.copy()
    phi[~np.isfinite(phi)] = 0.0
    phi = st.clip(phi, max(m_min, 1e-3 * max(phi[st.im], phi[st.im + 1],
                                             1e-300)))
    for start, n in ((0, st.nc_free), (st.nc_free, st.na_free)):
        powers = 0.9 ** np.arange(1, n + 1)
        for _ in range(200):
            if st.poles_stable(phi):
                break
            phi[start:start + n] *= powers
    return phi
