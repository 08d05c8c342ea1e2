"""Coefficients of eq. (2.1) and the parameter vector (2.5) (private).

The helpers behind `SandwichSystem`: from transfer functions to the
coefficient arrays (a, b, c, d) and back, declared orders, and the
`theta` of a system with a negative gain, which carries its sign.
"""

import numbers

import numpy as np
import control as ct

from .._checks import (check_order, check_vector, check_finite,
                       MAX_ORDER)


def declare_orders(orders, coef1, coef2):
    """Pad the coefficients of eq. (2.1) with zeros up to declared orders."""
    if not isinstance(orders, dict):
        raise TypeError(f"orders must be a dict with na, nb, nc, nd; got "
                        f"{type(orders).__name__}")
    unknown = set(orders) - {'na', 'nb', 'nc', 'nd', 'q1', 'q2'}
    if unknown:
        raise ValueError(f"orders has unknown keys {sorted(unknown)}; "
                         f"expected na, nb, nc, nd (q1, q2)")
    out = []
    for (a, b, q), (na, nb, qn) in ((coef1, ('na', 'nb', 'q1')),
                                    (coef2, ('nc', 'nd', 'q2'))):
        n_a = check_order(f"orders[{na!r}]", orders.get(na, a.size))
        n_b = check_order(f"orders[{nb!r}]", orders.get(nb, b.size - 1))
        if qn in orders and check_order(f"orders[{qn!r}]",
                                        orders[qn]) != q:
            raise ValueError(f"orders[{qn!r}] = {orders[qn]} but the "
                             f"transfer function has a delay of {q}")
        if n_a < a.size or n_b < b.size - 1:
            raise ValueError(
                f"declared orders {na} = {n_a}, {nb} = {n_b} are smaller "
                f"than the transfer function's ({a.size}, {b.size - 1})")
        out.append((np.concatenate([a, np.zeros(n_a - a.size)]),
                    np.concatenate([b, np.zeros(n_b + 1 - b.size)]), q))
    return out[0], out[1]


def difference_coefficients(num, den):
    """(a, b, q) of eq. (2.1) from normalised descending num, den."""
    q = den.size - num.size
    b = np.trim_zeros(num, 'b')
    a = np.trim_zeros(den[1:], 'b')
    return a, b, q


def tf_from_coefficients(aname, a, bname, b, qname, q, dt):
    """Transfer function in descending powers of z of eq. (2.1).

    Returns it with the checked coefficient arrays. Trailing zeros of the
    coefficients are left out of the transfer function (no extra poles at
    z = 0); the caller keeps them as declared orders.
    """
    a = coefficient_array(aname, a)
    b = coefficient_array(bname, b)
    q = check_order(qname, q)
    for name, arr in ((aname, a), (bname, b)):
        if arr.size > MAX_ORDER + 1:
            raise ValueError(f"{name} has {arr.size} coefficients; "
                             f"sandwichctl accepts orders up to {MAX_ORDER}")
    if b.size == 0:
        raise ValueError(f"{bname} must hold at least {bname}0; got an "
                         f"empty sequence")
    if b[0] == 0:
        raise ValueError(
            f"{bname}[0] is 0, but eq. (2.1) needs the leading coefficient "
            f"{bname}0 != 0 (it is normalised to 1); express a delay with "
            f"{qname} instead of leading zeros")
    a_tf, b_tf = np.trim_zeros(a, 'b'), np.trim_zeros(b, 'b')
    n = max(a_tf.size, q + b_tf.size - 1)
    den = np.zeros(n + 1)
    den[0] = 1.0
    den[1:a_tf.size + 1] = a_tf
    num = np.zeros(n + 1)
    num[q:q + b_tf.size] = b_tf
    return ct.tf(num, den, dt), a, b


def coefficient_array(name, values):
    """A finite 1-D coefficient array (a lone number is one coefficient)."""
    if isinstance(values, (numbers.Real, np.number)) and not isinstance(
            values, (bool, np.bool_)):
        values = [check_finite(f"{name}[0]", values)]
    return check_vector(name, values)


class SignedTheta(np.ndarray):
    """The `theta` of a sandwich with a negative gain: it carries d0.

    The parameter vector (2.5) has no entry for d0 (+1 in the paper); a
    system with a negative gain has d0 = -1, and this array carries it as
    ``sign`` so that `SandwichSystem.from_theta` rebuilds that system.
    Slices, copies and arithmetic keep the sign; reductions give plain
    numbers.
    """

    def __array_finalize__(self, obj):
        self.sign = getattr(obj, 'sign', -1)

    def __array_wrap__(self, obj, context=None, return_scalar=False):
        if obj.ndim == 0:
            return obj[()]
        return super().__array_wrap__(obj, context, return_scalar)

    def __reduce__(self):
        return signed_theta, (np.asarray(self), self.sign)

    def __repr__(self):
        body = repr(np.asarray(self))
        return f"theta{body[len('array'):-1]}, sign={self.sign})"


def signed_theta(theta, sign):
    """`theta` as returned to users: a plain array for a positive gain,
    one that carries ``sign = -1`` for a negative one (private)."""
    theta = np.asarray(theta, dtype=float)
    if sign > 0:
        return theta
    out = theta.copy().view(SignedTheta)
    out.sign = -1
    return out


def difference_equation(out, inp, a, b, q):
    """Render eq. (2.1) as text, e.g. 'x(k) = - 0.1 x(k-1) + 1.5 u(k-1)'."""
    terms = [(-ai, f"{out}(k-{i})") for i, ai in enumerate(a, 1)]
    terms += [(bj, f"{inp}(k{-(q + j):+d})" if q + j else f"{inp}(k)")
              for j, bj in enumerate(b)]
    parts = []
    for coef, sig in terms:
        if coef == 0:
            continue
        if parts:
            parts.append(f"{'-' if coef < 0 else '+'} {abs(coef):.6g} {sig}")
        else:
            parts.append(f"{coef:.6g} {sig}")
    text = ' '.join(parts)
    return f"{out}(k) = {text or '0'}"


#: a leading numerator coefficient (over the denominator's leading one)
#: this small is dropped by scipy's ``normalize`` (1e-14, with a margin)
LOST = 1e-12


def tf_to_ss(sys, **names):
    """``ct.ss(sys, **names)`` of a SISO transfer function, exact at any
    gain.

    python-control's conversion (scipy's ``normalize`` and ``tf2ss``)
    drops leading numerator coefficients below 1e-14 in absolute value,
    so a block whose gain is tiny in the user's units (an L1 of 1e-15, or
    the PID of a plant of gain 1e16) lost its direct term or its whole
    numerator. Such a numerator is converted at unit peak and the output
    scaled back; any other goes through python-control as before.
    """
    den = np.asarray(sys.den[0][0], dtype=float)
    with np.errstate(all='ignore'):
        num = np.asarray(sys.num[0][0], dtype=float) / den[0]
        den = den / den[0]
    lead = np.trim_zeros(num, 'f')
    if not (lead.size and abs(lead[0]) <= LOST and np.all(np.isfinite(
            num)) and np.all(np.isfinite(den))):
        return ct.ss(sys, **names)
    peak = float(np.max(np.abs(num)))
    unit = num / peak
    # what normalize drops anyway, at a warning: below 1e-14 of the peak
    unit = unit[int(np.argmax(np.abs(unit) > 1e-14)):]
    ss = ct.ss(ct.tf(unit, den, sys.dt), **names)
    return ct.ss(ss.A, ss.B, peak * ss.C, peak * ss.D, sys.dt, **names)

