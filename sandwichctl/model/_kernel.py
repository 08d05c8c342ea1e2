"""Compiled simulation kernel for L1 -> backlash -> L2 (private module).

The kernel uses the same state-space realisations of L1 and L2 as the
python-control interconnect in `SandwichSystem`, and the same state
ordering, so that a full state vector means the same thing to both. The
backlash step is `backlash.backlash_step`, the single implementation of
eq. (2.2).
"""

import numba
import numpy as np

from .backlash import backlash_step

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
