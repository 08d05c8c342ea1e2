"""The state-space blocks of `export_c`'s generated code: one SISO block
(A, B, C, D) as ``static const`` arrays and the call that steps it, and
for ``dtype='float'`` a realization whose coefficients survive rounding
to float (`Block.for_float`).

Why the realization matters in float. The compiled kernel keeps each
block as python-control realizes a transfer function: a canonical form,
whose A holds the coefficients of the denominator. The inverse of a
model with slow poles is a block whose output is the small difference of
large terms: the servo tutorial's linear feedforward (poles of the plant
at 0.93 +- 0.11j, 0.975 and 0.9935, zeros at 0.9936 and 0.878) gives
peaks of 0.91 from D r and C x terms of about 190, so that in float its
canonical form erred by 20 % of the peak of u and the real Schur form by
16 %. A balanced realization (equal, diagonal gramians) keeps every state
as large as its share of the output, and erred by 7e-5, next to the 3e-5
that rounding the inputs alone costs. The tutorial's sandwich design
has a linear feedforward of 13 states (two poles, the rest delays for
the band jump's lead) whose observability gramian is singular to double
precision: its factors are taken from the gramians' eigenvalues clipped
at zero, and the states whose Hankel singular values fall below
`TRUNCATE` of the largest are dropped (1.4e-5 of the peak on the probe,
against 4.7e-2 in the canonical form). Blocks with a pole on or outside
the unit circle (the PID's integrator) have no gramians: there the real
Schur form, whose entries are near the poles rather than a polynomial's
coefficients, did best (the tutorial's feedback alone: 1.4e-4 in its
canonical form, 2e-6 in Schur form). No form wins everywhere (a long
delay line is exact in its own form), so `Block.for_float` keeps the one
whose float response to a seeded probe strays least from double.
"""

import warnings

import numpy as np
from scipy.linalg import (LinAlgError, LinAlgWarning, eigh, schur,
                          solve_discrete_lyapunov, svd)

__all__ = []

#: the largest pole radius of a block that is balanced
STABLE = 1.0 - 1e-9
#: Hankel singular values below this share of the largest are truncated
TRUNCATE = 1e-10
#: the gramians of blocks of at most this many states are solved directly
#: (a Kronecker system of n^2 unknowns: 40 states take 20 MB; the 675 of
#: a controller with 217 samples of preview took 24 GB); larger ones by
#: the bilinear transformation
DIRECT_MOST = 40
#: samples of the probe input on which the realizations are compared
PROBE = 2000


def _probe():
    """A seeded input with what a block meets: the slow ramps of a
    reference (slopes drawn anew every 100 samples), and noise 1e-3 of
    its size."""
    rng = np.random.default_rng(0x5eed)
    slow = np.cumsum(np.repeat(rng.standard_normal(PROBE // 100), 100))
    return slow / np.max(np.abs(slow)) + 1e-3 * rng.standard_normal(PROBE)


class Block:
    """A SISO state-space block: (A, B, C, D) of n states."""

    def __init__(self, tag, what, n, A, B, C, D):
        self.tag, self.what, self.n = tag, what, n
        self.A, self.B, self.C = (np.ravel(M) for M in (A, B, C))
        self.D = float(np.ravel(D)[0])

    @classmethod
    def packed(cls, tag, what, p, off, n):
        """The block at offset `off` of packed parameters (A, B, C, D)."""
        a, b, c = off, off + n * n, off + n * n + n
        return cls(tag, what, n, p[a:b], p[b:c], p[c:c + n],
                   p[c + n:c + n + 1])

    def _similar(self, T, Ti):
        """The block with states T^-1 x."""
        A = self.A.reshape(self.n, self.n)
        return Block(self.tag, self.what, self.n, Ti @ A @ T, Ti @ self.B,
                     self.C @ T, self.D)

    def for_float(self):
        """The same transfer function in the realization, of its own, the
        real Schur form and the balanced one, whose float response to
        `PROBE` strays least from its own in double (see the module
        notes)."""
        if self.n == 0:
            return self
        u = _probe()
        exact = self._response(u, np.float64)
        best, least = self, np.inf
        # the gramians of a small block by both of scipy's solvers: with
        # slow poles they are near singular, and which one's balanced form
        # keeps float closer to double varies with the machine's LAPACK
        # (SLOW of tests/test_export.py: 2.5e-3 of the peak from the
        # direct solve, 2.4e-5 from the bilinear one, on one machine)
        solvers = ('direct', 'bilinear') if self.n <= DIRECT_MOST else (
            'bilinear',)
        for block in (self, self._schur(),
                      *(self._balanced(how) for how in solvers)):
            if block is None:
                continue
            with np.errstate(all='ignore'):
                err = np.max(np.abs(block._response(u, np.float32) - exact))
            if err < least:
                best, least = block, err
        return best

    def _response(self, u, dtype):
        """The block's output for the input u, in `dtype` arithmetic."""
        A, B, C = (np.asarray(M, dtype) for M in
                   (self.A.reshape(self.n, self.n), self.B, self.C))
        D, x = dtype(self.D), np.zeros(self.n, dtype)
        out = np.empty(u.size)
        for k, uk in enumerate(u.astype(dtype)):
            out[k] = C @ x + D * uk
            x = A @ x + B * uk
        return out

    def _schur(self):
        """The block in real Schur form (an orthogonal change of
        states)."""
        T, Z = schur(self.A.reshape(self.n, self.n), output='real')
        return self._similar(Z, Z.T)

    def _balanced(self, solver=None):
        """The block balanced (square-root method, on the gramians of the
        block with B and C scaled to unit norm: balanced up to one common
        scale of the states), without the states whose Hankel singular
        values are below `TRUNCATE` of the largest (a near-cancelled pole
        and zero: their share of the output is far below a float's
        precision); the gramians by scipy's `solver` (by default 'direct'
        up to `DIRECT_MOST` states, 'bilinear' above); None where a pole
        is on or outside the unit circle, or where the gramians cannot be
        factored."""
        A = self.A.reshape(self.n, self.n)
        if not np.max(np.abs(np.linalg.eigvals(A))) < STABLE:
            return None
        b, c = (v / max(np.linalg.norm(v), 1e-300) for v in (self.B, self.C))
        try:
            factors = []
            for M, v in ((A, b), (A.T, c)):
                with warnings.catch_warnings():
                    warnings.simplefilter('ignore', LinAlgWarning)
                    W = solve_discrete_lyapunov(M, np.outer(v, v), method=(
                        solver or ('direct' if self.n <= DIRECT_MOST
                                   else 'bilinear')))
                lam, vec = eigh(0.5 * (W + W.T))
                factors.append(vec * np.sqrt(np.clip(lam, 0.0, None)))
            u, hsv, vt = svd(factors[1].T @ factors[0])
        except (LinAlgError, ValueError):
            return None
        keep = int(np.sum(hsv > TRUNCATE * hsv[0])) if hsv[0] > 0 else 0
        if keep == 0:
            return None
        scale = np.diag(hsv[:keep] ** -0.5)
        T = factors[0] @ vt[:keep].T @ scale
        Ti = scale @ u[:, :keep].T @ factors[1].T
        return Block(self.tag, self.what, keep, Ti @ A @ T, Ti @ self.B,
                     self.C @ T, self.D)

    def constants(self, w):
        head = f"/* {self.what}: {self.n} state(s) */"
        if self.n == 0:
            return [head, w.const(f"{self.tag}_D", self.D)]
        return [head, w.array(f"{self.tag}_A", self.A, self.n),
                w.array(f"{self.tag}_B", self.B, self.n),
                w.array(f"{self.tag}_C", self.C, self.n),
                w.const(f"{self.tag}_D", self.D)]

    def call(self, w, u):
        """C expression: the block's output for input u (it also advances
        the block's states, s->tag)."""
        t = f"{w.name}_{self.tag}"
        if self.n == 0:
            return f"{t}_D * {u}"
        return (f"{w.name}_block({t}_A, {t}_B, {t}_C, {t}_D,\n"
                f"        {self.n}, s->{self.tag}, {u})")
