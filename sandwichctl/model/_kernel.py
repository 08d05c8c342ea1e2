"""Compiled simulation kernel for L1 -> backlash -> L2 (private module).

The kernel uses the same state-space realisations of L1 and L2 as the
python-control interconnect in `SandwichSystem`, and the same state
ordering, so that a full state vector means the same thing to both. The
backlash step is `backlash.backlash_step`, the single implementation of
eq. (2.2).
"""

import math

import numba
import numpy as np
import control as ct

from .backlash import backlash_step
from .._checks import (check_signal, check_vector, check_positive,
                       check_nonnegative)

__all__ = []


@numba.njit(cache=True)
def _ss_output(A, B, C, D, s, u):
    """Return C s + D u for a SISO state-space block."""
    out = D[0, 0] * u
    for i in range(s.size):
        out += C[0, i] * s[i]
    return out


@numba.njit(cache=True)
def _ss_update(A, B, s, u, work):
    """Overwrite s with A s + B u (work is scratch of the same size)."""
    n = s.size
    for i in range(n):
        acc = B[i, 0] * u
        for j in range(n):
            acc += A[i, j] * s[j]
        work[i] = acc
    for i in range(n):
        s[i] = work[i]


@numba.njit(cache=True)
def simulate_kernel(u, A1, B1, C1, D1, A2, B2, C2, D2, m1, m2, Dl, Du,
                    state, y, x, v, states):
    """Simulate the sandwich for input u.

    `state` is the full state vector [L1 states, x(k-1), v(k-1), L2 states]
    at k = 0 and is overwritten with the state after the last sample.
    y, x, v receive the output and internal signals (x and v may have
    zero length to skip storing them). If `states` has N
    rows, row k receives the state at sample k (python-control's
    convention); pass an array with zero rows to skip this.
    """
    n1 = A1.shape[0]
    n2 = A2.shape[0]
    s1 = state[:n1].copy()
    s2 = state[n1 + 2:].copy()
    w1 = np.empty(n1)
    w2 = np.empty(n2)
    x_prev = state[n1]
    v_prev = state[n1 + 1]
    keep = states.shape[0] > 0
    internal = x.size > 0
    for k in range(u.size):
        if keep:
            states[k, :n1] = s1
            states[k, n1] = x_prev
            states[k, n1 + 1] = v_prev
            states[k, n1 + 2:] = s2
        xk = _ss_output(A1, B1, C1, D1, s1, u[k])
        vk, _ = backlash_step(xk, x_prev, v_prev, m1, m2, Dl, Du)
        y[k] = _ss_output(A2, B2, C2, D2, s2, vk)
        if internal:
            x[k] = xk
            v[k] = vk
        _ss_update(A1, B1, s1, u[k], w1)
        _ss_update(A2, B2, s2, vk, w2)
        x_prev = xk
        v_prev = vk
    state[:n1] = s1
    state[n1] = x_prev
    state[n1 + 1] = v_prev
    state[n1 + 2:] = s2


SMALL = 4        # orders up to this run with the state in registers


@numba.njit(cache=True)
def _pad(c, i):
    return c[i] if i < c.size else 0.0


@numba.njit(cache=True)
def _small_kernel(u, a1, c1, d1, a2, c2, d2, m1, m2, Dl, Du, state, y, x, v,
                  step, t, u_copy):
    """`companion_kernel` for orders <= SMALL, with no state trajectory.

    The states live in scalar locals, the coefficients are padded with
    zeros up to SMALL; a zero term adds an exact zero, so the result is
    that of the array loop in `companion_kernel` bit for bit.
    """
    n1 = a1.size
    n2 = a2.size
    p0, p1, p2, p3 = _pad(a1, 0), _pad(a1, 1), _pad(a1, 2), _pad(a1, 3)
    h0, h1, h2, h3 = _pad(c1, 0), _pad(c1, 1), _pad(c1, 2), _pad(c1, 3)
    q0, q1, q2, q3 = _pad(a2, 0), _pad(a2, 1), _pad(a2, 2), _pad(a2, 3)
    g0, g1, g2, g3 = _pad(c2, 0), _pad(c2, 1), _pad(c2, 2), _pad(c2, 3)
    s0 = state[0] if n1 > 0 else 0.0
    s1 = state[1] if n1 > 1 else 0.0
    s2 = state[2] if n1 > 2 else 0.0
    s3 = state[3] if n1 > 3 else 0.0
    o = n1 + 2
    t0 = state[o] if n2 > 0 else 0.0
    t1 = state[o + 1] if n2 > 1 else 0.0
    t2 = state[o + 2] if n2 > 2 else 0.0
    t3 = state[o + 3] if n2 > 3 else 0.0
    x_prev = state[n1]
    v_prev = state[n1 + 1]
    internal = x.size > 0
    extra = t.size > 0
    bad = -1
    for k in range(u.size):
        uk = u[k]
        if extra:
            t[k] = step * k
            u_copy[k] = uk
        # oldest state first, newest last: the loop-carried chain is short
        xk = h3 * s3 + h2 * s2 + h1 * s1 + d1 * uk + h0 * s0
        w = p3 * s3 + p2 * s2 + p1 * s1 + uk + p0 * s0
        vk, _ = backlash_step(xk, x_prev, v_prev, m1, m2, Dl, Du)
        yk = g3 * t3 + g2 * t2 + g1 * t1 + g0 * t0 + d2 * vk
        y[k] = yk
        if bad < 0 and not math.isfinite(yk):
            bad = k
        z = q3 * t3 + q2 * t2 + q1 * t1 + q0 * t0 + vk
        if internal:
            x[k] = xk
            v[k] = vk
        s3, s2, s1, s0 = s2, s1, s0, w
        t3, t2, t1, t0 = t2, t1, t0, z
        x_prev = xk
        v_prev = vk
    new1 = (s0, s1, s2, s3)
    new2 = (t0, t1, t2, t3)
    for i in range(n1):
        state[i] = new1[i]
    for i in range(n2):
        state[o + i] = new2[i]
    state[n1] = x_prev
    state[n1 + 1] = v_prev
    return bad


@numba.njit(cache=True)
def _small_kernel2(u, a1, c1, d1, a2, c2, d2, m1, m2, Dl, Du, state, y, x,
                   v, step, t, u_copy):
    """`_small_kernel` for orders <= 2 (fewer zero terms to compute)."""
    n1 = a1.size
    n2 = a2.size
    p0, p1, h0, h1 = _pad(a1, 0), _pad(a1, 1), _pad(c1, 0), _pad(c1, 1)
    q0, q1, g0, g1 = _pad(a2, 0), _pad(a2, 1), _pad(c2, 0), _pad(c2, 1)
    s0 = state[0] if n1 > 0 else 0.0
    s1 = state[1] if n1 > 1 else 0.0
    o = n1 + 2
    t0 = state[o] if n2 > 0 else 0.0
    t1 = state[o + 1] if n2 > 1 else 0.0
    x_prev = state[n1]
    v_prev = state[n1 + 1]
    internal = x.size > 0
    extra = t.size > 0
    bad = -1
    for k in range(u.size):
        uk = u[k]
        if extra:
            t[k] = step * k
            u_copy[k] = uk
        xk = h1 * s1 + d1 * uk + h0 * s0
        w = p1 * s1 + uk + p0 * s0
        vk, _ = backlash_step(xk, x_prev, v_prev, m1, m2, Dl, Du)
        yk = g1 * t1 + g0 * t0 + d2 * vk
        z = q1 * t1 + q0 * t0 + vk
        y[k] = yk
        if bad < 0 and not math.isfinite(yk):
            bad = k
        if internal:
            x[k] = xk
            v[k] = vk
        s1, s0 = s0, w
        t1, t0 = t0, z
        x_prev = xk
        v_prev = vk
    if n1 > 0:
        state[0] = s0
    if n1 > 1:
        state[1] = s1
    if n2 > 0:
        state[o] = t0
    if n2 > 1:
        state[o + 1] = t1
    state[n1] = x_prev
    state[n1 + 1] = v_prev
    return bad


@numba.njit(cache=True)
def companion_kernel(u, a1, c1, d1, a2, c2, d2, m1, m2, Dl, Du,
                     state, y, x, v, states, step, t, u_copy):
    """`simulate_kernel` for L1 and L2 in controllable companion form.

    The form of ``ct.ss(tf)`` (scipy's tf2ss): A's first row is `a`, the
    rows below shift the state down by one, B = e1, C = `c`, D = `d`.
    The products with the zeros and ones of A and B are left out and the
    sums run from the oldest state to the newest (rounding differs from
    `simulate_kernel` in the last bits only). The arguments otherwise
    mean the same. Orders up to SMALL without a state trajectory go to
    `_small_kernel`, which gives the same numbers.

    If `t` and `u_copy` have N entries, they receive the time points
    ``step * k`` and a copy of u (fused into the loop: cheaper than
    separate passes). Returns the first sample whose output is not
    finite, or -1.
    """
    n1 = a1.size
    n2 = a2.size
    keep = states.shape[0] > 0
    if n1 <= 2 and n2 <= 2 and not keep:
        return _small_kernel2(u, a1, c1, d1, a2, c2, d2, m1, m2, Dl, Du,
                              state, y, x, v, step, t, u_copy)
    if n1 <= SMALL and n2 <= SMALL and not keep:
        return _small_kernel(u, a1, c1, d1, a2, c2, d2, m1, m2, Dl, Du,
                             state, y, x, v, step, t, u_copy)
    s1 = state[:n1].copy()
    s2 = state[n1 + 2:].copy()
    x_prev = state[n1]
    v_prev = state[n1 + 1]
    internal = x.size > 0
    extra = t.size > 0
    bad = -1
    for k in range(u.size):
        uk = u[k]
        if extra:
            t[k] = step * k
            u_copy[k] = uk
        if keep:
            states[k, :n1] = s1
            states[k, n1] = x_prev
            states[k, n1 + 1] = v_prev
            states[k, n1 + 2:] = s2
        xk = 0.0
        acc1 = 0.0
        for i in range(n1 - 1, 0, -1):
            xk += c1[i] * s1[i]
            acc1 += a1[i] * s1[i]
        xk += d1 * uk
        acc1 += uk
        if n1 > 0:
            xk += c1[0] * s1[0]
            acc1 += a1[0] * s1[0]
        vk, _ = backlash_step(xk, x_prev, v_prev, m1, m2, Dl, Du)
        yk = 0.0
        acc2 = 0.0
        for i in range(n2 - 1, -1, -1):
            yk += c2[i] * s2[i]
            acc2 += a2[i] * s2[i]
        yk += d2 * vk
        y[k] = yk
        if bad < 0 and not math.isfinite(yk):
            bad = k
        acc2 += vk
        if internal:
            x[k] = xk
            v[k] = vk
        for i in range(n1 - 1, 0, -1):
            s1[i] = s1[i - 1]
        if n1 > 0:
            s1[0] = acc1
        for i in range(n2 - 1, 0, -1):
            s2[i] = s2[i - 1]
        if n2 > 0:
            s2[0] = acc2
        x_prev = xk
        v_prev = vk
    state[:n1] = s1
    state[n1] = x_prev
    state[n1 + 1] = v_prev
    state[n1 + 2:] = s2
    return bad


@numba.njit(cache=True, parallel=True)
def batch_kernel(U, a1, c1, d1, a2, c2, d2, bl, state0, Y):
    """Run `companion_kernel` for each row of Y, in parallel (prange).

    Row b of Y receives the output for the input row ``U[b]`` (or U[0]
    if U has one row) and the parameter row b (or 0) of a1, c1, d1, a2,
    c2, d2 (L1 and L2 in companion form) and bl (m1, m2, D1, D2); every
    run starts from the state `state0`. Each row is computed exactly as
    one call of `companion_kernel`, whatever the number of threads.
    """
    nb = Y.shape[0]
    su = 1 if U.shape[0] > 1 else 0      # row step: 0 for a shared row
    sp = 1 if a1.shape[0] > 1 else 0
    empty = np.empty(0)
    no_states = np.empty((0, state0.size))
    for b in numba.prange(nb):
        iu = b * su
        ip = b * sp
        state = state0.copy()
        companion_kernel(U[iu], a1[ip], c1[ip], d1[ip], a2[ip], c2[ip],
                         d2[ip], bl[ip, 0], bl[ip, 1], bl[ip, 2], bl[ip, 3],
                         state, Y[b], empty, empty, no_states, 1.0, empty,
                         empty)


def companion_form(A1, B1, C1, D1, A2, B2, C2, D2):
    """Arguments of `companion_kernel` for the realisations, or None.

    Returns (a1, c1, d1, a2, c2, d2) if both blocks are in controllable
    companion form (``ct.ss`` of a transfer function), else None.
    """
    out = []
    for A, B, C, D in ((A1, B1, C1, D1), (A2, B2, C2, D2)):
        n = A.shape[0]
        e1 = np.zeros((n, 1))
        e1[:1] = 1.0
        if not (np.array_equal(A[1:], np.eye(n, k=-1)[1:])
                and np.array_equal(B, e1)):
            return None
        out += [np.ascontiguousarray(A[0] if n else np.zeros(0)),
                np.ascontiguousarray(C[0]), float(D[0, 0])]
    return tuple(out)


def batch_signals(inputs):
    """`inputs` of simulate_batch as a 2-D float array, one signal a row."""
    try:
        ndim = np.ndim(inputs)
    except ValueError:                   # ragged nested sequences
        raise ValueError("inputs must be a 2-D array of signals (one per "
                         "row, all of the same length)") from None
    if ndim == 2 and not isinstance(inputs, str):
        rows = [check_signal(f"inputs[{i}]", r) for i, r in enumerate(inputs)]
        if not rows:
            raise ValueError("inputs must hold at least one signal; got 0")
        return np.ascontiguousarray(np.stack(rows))
    if ndim > 2:
        raise ValueError(f"inputs must be a 2-D array of signals (one per "
                         f"row); got shape {np.shape(inputs)}")
    return check_signal('inputs', inputs)[None, :]


def _companion_rows(den_tail, num):
    """Rows (a, c, d) of scipy's tf2ss for descending num, den = [1, tail]."""
    den1 = den_tail                      # den[1:], den[0] = 1
    return (-den1 / 1.0, num[:, 1:] - num[:, :1] * den1, num[:, 0].copy())


def theta_batch(thetas, orders, sign):
    """Companion-form parameters for rows of parameter vectors (2.5).

    Returns (a1, c1, d1, a2, c2, d2, bl) with one row per parameter set,
    for ``SandwichSystem.from_theta(theta, **orders, sign=sign)``; the
    blocks keep the declared orders (zero coefficients are kept as
    states, which changes nothing in the output).
    """
    na, nb, nc, nd = orders['na'], orders['nb'], orders['nc'], orders['nd']
    q1, q2 = orders['q1'], orders['q2']
    size = nc + na + 4 + nb + nd
    if np.ndim(thetas) == 1:
        thetas = [thetas]
    try:
        rows = [check_vector(f"thetas[{i}]", t, size)
                for i, t in enumerate(thetas)]
    except TypeError as err:
        raise TypeError(f"thetas must be a 2-D array of parameter vectors "
                        f"(one per row): {err}") from None
    if not rows:
        raise ValueError("thetas must hold at least one parameter vector")
    th = np.stack(rows)
    bl = np.ascontiguousarray(th[:, nc + na:nc + na + 4])
    for i, row in enumerate(bl):
        for j, label in enumerate(('m1', 'm2', 'D1', 'D2')):
            check = check_positive if j < 2 else check_nonnegative
            check(f"thetas[{i}] ({label})", row[j])
    out = []
    for den, lead, tail, q in (
            (th[:, nc:nc + na], 1.0, th[:, nc + na + 4:nc + na + 4 + nb],
             q1),
            (th[:, :nc], float(sign), th[:, nc + na + 4 + nb:] * sign, q2)):
        n = max(den.shape[1], q + tail.shape[1])
        den_tail = np.zeros((th.shape[0], n))
        den_tail[:, :den.shape[1]] = den
        num = np.zeros((th.shape[0], n + 1))
        num[:, q] = lead
        num[:, q + 1:q + 1 + tail.shape[1]] = tail
        out += [np.ascontiguousarray(r) for r in
                _companion_rows(den_tail, num)]
    return (*out, bl)


class SimulationResponse(ct.TimeResponseData):
    """The result of `SandwichSystem.simulate`: a ct.TimeResponseData whose
    ``states`` says how to get them when they were not stored."""

    @property
    def states(self):
        if self.x is None:
            raise AttributeError(
                "the states were not stored: call simulate(..., "
                "return_states=True) to keep them (N x nstates values); "
                "resp.final_state is the state after the last sample, and "
                "simulate(..., internal=True) gives x and v as outputs")
        return ct.TimeResponseData.states.fget(self)
